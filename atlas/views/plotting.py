"""Figures of an atlas: a leaf layer that only reads Datasets (it computes nothing).

* :func:`basin_map` — colour by attractor k, separatrices in red, saddles as open circles,
  attractors as filled dots;
* :func:`trap_time_map` — the certified trapping time on a log colour scale;
* :func:`boundary_distance_map` — each state's distance to the nearest basin boundary (how
  far it is from tipping into another well), with the band d_cert where labels hold for the
  RK4 map only;
* :func:`fraction_curves` — exact basin fractions against a swept parameter, with the grid
  counts and their error bounds.

The maps are drawn as images of at most MAX_PIXELS per axis: a larger map is read band by band
(:func:`read_maps`; from the file, for a tree opened lazily) and each band reduced to blocks
(labels by their mode, t_trap by the block max, boundary_distance by the block min), so that
the memory a figure needs does not grow with the map (a 16384² atlas: about 0.5 GB).

Each figure is read, then drawn: a reader (``_*_scene``) takes what the figure shows out of the
tree as plain arrays and strings, a drawer (``_draw_*``) draws them and reads nothing. This
lets ``atlas plot`` (:func:`plot_file`) read the file in one process while another imports
matplotlib (each takes a few tenths of a second), then draw the figures in several processes
at once (:mod:`atlas.views.forked`). matplotlib is imported only where a figure is drawn.
"""

from __future__ import annotations

import functools
import math
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from atlas.kernels import NEAR_BOUNDARY, RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED
from atlas.layout import PARAMETERS, first_point, point_group, point_label, point_of

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["basin_map", "trap_time_map", "boundary_distance_map", "fraction_curves",
           "basin_stability", "plot_atlas", "plot_file", "read_maps", "pi_ticks",
           "critical_point_markers", "STYLE"]

#: One style for every atlas figure.
STYLE = {"figure.dpi": 110, "savefig.dpi": 150, "axes.grid": False, "font.size": 10,
         "axes.titlesize": 11, "legend.fontsize": 8, "legend.frameon": False}
#: Figure sizes [in]: the maps, and the curves against a swept parameter.
MAP_SIZE, CURVE_SIZE = (8, 4.8), (7, 4.5)
#: PNG options of the written figures: zlib's fastest level (deflating the smooth colour maps
#: at the default level took longer than drawing them; the files are about 40 % larger).
PNG_OPTIONS = {"compress_level": 1}
SEPARATRIX_COLOR = "red"
#: The running basin's colour, and the running limit cycle's.
RUNNING_COLOR, CYCLE_COLOR = "0.82", "black"
TWO_PI = 2.0 * np.pi


def pi_ticks(ax, lo: float, hi: float) -> None:
    """θ ticks at the multiples of π in [lo, hi] [rad], labelled −2π, −π, 0, π, 2π, …"""
    n = np.arange(np.ceil(lo / np.pi), np.floor(hi / np.pi) + 1).astype(int)
    ax.set_xticks(n * np.pi)
    ax.set_xticklabels(["0" if k == 0 else f"{'−' if k < 0 else ''}{'' if abs(k) == 1 else abs(k)}π"
                        for k in n])


def _single(ds: xr.Dataset, **index) -> xr.Dataset:
    """The basin map of one parameter point (the first along each swept dim unless
    indexed)."""
    return first_point(ds, **index)


def point_title(point: dict[str, float]) -> str:
    """"α = 0.1 s⁻¹, ω0 = 1 rad/s" (and τ where the pendulum has a torque)."""
    text = f"α = {point['alpha']:g} s⁻¹, ω0 = {point['omega0']:g} rad/s"
    torque = point.get("torque", 0.0)
    return text + (f", τ = {torque:g} rad/s²" if torque else "")


def critical_point_markers(ax, theta, is_saddle, tilted: bool = False) -> None:
    """Mark the critical points (θ [rad], 0) on the θ axis: attractors (2πk, 0) as black dots,
    saddles ((2j+1)π, 0) as open red circles (essay Figure 9), labelled for the legend;
    ``tilted``: a pendulum with torque, whose rest states sit at θ* + 2πk, θ* = asin(τ/ω0²),
    and saddles at π − θ* + 2πk."""
    theta, is_saddle = np.asarray(theta, float), np.asarray(is_saddle, bool)
    ax.plot(theta[~is_saddle], np.zeros((~is_saddle).sum()), "o", color="black", ms=5,
            label="attractors (θ* + 2πk, 0)" if tilted else "attractors (2πk, 0)", zorder=5)
    ax.plot(theta[is_saddle], np.zeros(is_saddle.sum()), "o", mfc="none",
            mec=SEPARATRIX_COLOR, mew=1.5, ms=7,
            label="saddles (π − θ* + 2πk, 0)" if tilted else "saddles ((2j+1)π, 0)", zorder=5)


#: Largest image drawn per axis [pixels]: a figure is 8 in wide at 150 dpi. Larger maps are
#: coarsened to it first (labels by their mode, never averaged into a k that no orbit reached).
MAX_PIXELS = 1200
#: Cells read at once when a map is drawn: a map is read in bands of whole rows (whole blocks
#: of the coarsening, aligned to the file's chunks where that costs little), so the memory a
#: figure needs is bounded by this and by MAX_PIXELS², not by the size of the map.
BAND_CELLS = 1 << 22


def _factors(shape: tuple[int, int]) -> tuple[int, int]:
    """Rows and columns of a coarsening block: at most MAX_PIXELS blocks along each axis."""
    return -(-shape[0] // MAX_PIXELS), -(-shape[1] // MAX_PIXELS)


def _coarsen(values: np.ndarray, how: str) -> np.ndarray:
    """Block-reduce ``values`` (rows × columns, NaN = no value) to at most MAX_PIXELS per axis:
    ``mode`` for labels, ``min`` or ``max`` for continuous maps (keeping their extremes).

    The definition, on a whole array in memory; the figures read their maps band by band
    and reduce each band with compiled kernels (:func:`_read_labels`,
    :func:`_read_extreme`), which compute the same."""
    fr, fc = _factors(values.shape)
    if fr == fc == 1:
        return values
    rows, cols = -(-values.shape[0] // fr), -(-values.shape[1] // fc)
    padded = np.full((rows * fr, cols * fc), np.nan)
    padded[:values.shape[0], :values.shape[1]] = values
    blocks = padded.reshape(rows, fr, cols, fc).transpose(0, 2, 1, 3).reshape(rows, cols, -1)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN blocks stay NaN
        if how == "min":
            return np.nanmin(blocks, axis=2)
        if how == "max":
            return np.nanmax(blocks, axis=2)
    finite = blocks[np.isfinite(blocks)]
    if not finite.size:
        return blocks[..., 0]
    lo = int(finite.min())
    counts = np.stack([(blocks == k).sum(axis=2) for k in range(lo, int(finite.max()) + 1)])
    mode = (lo + counts.argmax(axis=0)).astype(float)
    return np.where(counts.max(axis=0) > 0, mode, np.nan)


# --------------------------------------------------------------------------- streamed maps

def _point_index(ds: xr.Dataset, index: dict) -> dict[str, int]:
    """The parameter point that ``_single(ds, **index)`` selects, as an index (≥ 0) into each
    swept dim."""
    return {name: range(ds.sizes[name])[index.get(name, 0)] for name in PARAMETERS
            if name in ds.dims}


def _chunk_rows(da: xr.DataArray) -> int:
    """Rows of one stored chunk of ``da`` (1 if unknown)."""
    if da.chunks:  # dask
        return int(da.chunks[0][0])
    preferred = da.encoding.get("preferred_chunks") or {}
    if "theta_dot0" in preferred:
        return int(preferred["theta_dot0"])
    sizes = da.encoding.get("chunksizes") or da.encoding.get("chunks")
    return int(sizes[-2]) if sizes and len(sizes) >= 2 else 1


class _MapRows:
    """One map of one parameter point (rows θ̇0, columns θ0), read a range of rows at a time:
    through xarray (from memory, or the file's own decoding for a lazy tree), or for a map
    that is coarsened and stored as an atlas file stores it (deflated, shuffled, chunks of
    whole rows), as its stored chunks inflated in this process
    (:class:`atlas.store.atlasfile.StoredRows`)."""

    def __init__(self, ds: xr.Dataset, name: str, point: dict[str, int], coarsened=False):
        self.da = ds[name].isel(point).transpose("theta_dot0", "theta0")
        self.shape = self.da.shape
        from atlas.store.atlasfile import StoredRows

        self.raw = StoredRows.of(ds, name, point) if coarsened else None
        self.chunk_rows = self.raw.rows if self.raw else _chunk_rows(self.da)

    def read(self, r0: int, r1: int) -> np.ndarray:
        if self.raw is not None:
            rows = self.raw.read(r0, r1)
            if rows is not None:
                return rows
        return np.asarray(self.da.isel(theta_dot0=slice(r0, r1)).values)

    def close(self) -> None:
        if self.raw is not None:
            self.raw.file.close()


def _row_bands(rows: int, cols: int, fr: int, chunk_rows: int) -> list[tuple[int, int]]:
    """Row ranges [r0, r1) covering a map: whole blocks of ``fr`` rows (only the last band
    may end inside a block), about BAND_CELLS cells each, aligned to the stored chunks unless
    that would make a band much larger."""
    step = math.lcm(fr, chunk_rows)
    if step * cols > 4 * BAND_CELLS:
        step = fr
    step *= max(1, BAND_CELLS // (step * cols))
    return [(r0, min(r0 + step, rows)) for r0 in range(0, rows, step)]


def _read_rows(source: _MapRows, r0: int, r1: int) -> np.ndarray:
    """Rows [r0, r1) of a map, read (from its file, when the tree is lazy)."""
    return source.read(r0, r1)


def _workers() -> int:
    """Threads that read and reduce bands at once (each holds one band)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, min(cores or 1, 8))


def _blocks(ds: xr.Dataset) -> tuple[int, int, np.ndarray]:
    """(fr, fc, an empty image): the block of the coarsening of the maps of ``ds``, and an
    image of one pixel per block."""
    rows, cols = ds.sizes["theta_dot0"], ds.sizes["theta0"]
    fr, fc = _factors((rows, cols))
    return fr, fc, np.empty((-(-rows // fr), -(-cols // fc)))


def _reduce_bands(ds: xr.Dataset, names: list[str], point: dict[str, int], fr: int, fc: int,
                  reduce) -> list:
    """Read the maps ``names`` at ``point`` band by band (whole blocks of fr × fc cells), the
    rows [r0, r1) of each at once, and call ``reduce(r0, r1, arrays)`` on every band;
    returns the results in the order of the bands. Coarsened maps are read and reduced by
    :func:`_workers` threads at once (the kernels and zlib release the GIL), each holding
    one band."""
    from concurrent.futures import ThreadPoolExecutor

    if fr * fc > 1:
        _kernels()  # compiled (or loaded) once, before the threads need them
    sources = []
    try:
        for name in names:
            sources.append(_MapRows(ds, name, point, coarsened=fr * fc > 1))
        bands = _row_bands(*sources[0].shape, fr, sources[0].chunk_rows)

        def work(band):
            return reduce(*band, [_read_rows(source, *band) for source in sources])

        if fr * fc == 1 or len(bands) == 1:
            return [work(band) for band in bands]
        with ThreadPoolExecutor(_workers()) as pool:
            return list(pool.map(work, bands))
    finally:
        for source in sources:
            source.close()


@functools.cache
def _kernels():
    """The Numba kernels of the streamed coarsening (compiled, or loaded from the cache, on
    the first map that needs coarsening: small maps never import Numba). Each runs on one
    core without the GIL; bands are reduced in threads."""
    from atlas.kernels import cached_njit

    @cached_njit(nogil=True)
    def mode_blocks(attractor, status, fr, fc, out, stats):  # pragma: no cover - compiled
        """out[i, j]: the most frequent well label of block (i, j) of these rows (ties: the
        smallest k), inf if running cells outnumber every well label, NaN if no cell has a
        label. stats: the smallest and largest well label, and the number of running cells.
        """
        h, w = attractor.shape
        nr, nc = out.shape
        counts = np.zeros(65536, np.int64)
        all_lo, all_hi, all_run = 1 << 20, -(1 << 20), 0
        for i in range(nr):
            for j in range(nc):
                lo, hi, n_run = 1 << 20, -(1 << 20), 0
                for r in range(i * fr, min(i * fr + fr, h)):
                    for c in range(j * fc, min(j * fc + fc, w)):
                        s = status[r, c]
                        if s == TRAPPED or s == NEAR_BOUNDARY:
                            k = np.int64(attractor[r, c])
                            counts[k + 32768] += 1
                            lo = min(lo, k)
                            hi = max(hi, k)
                        elif s == RUNNING or s == RUNNING_NEAR_BOUNDARY:
                            n_run += 1
                best, best_k = 0, 0
                for k in range(lo, hi + 1):
                    if counts[k + 32768] > best:
                        best, best_k = counts[k + 32768], k
                    counts[k + 32768] = 0
                if n_run > best:  # the running label is the largest: it loses every tie
                    out[i, j] = np.inf
                elif best > 0:
                    out[i, j] = best_k
                else:
                    out[i, j] = np.nan
                all_lo, all_hi, all_run = min(all_lo, lo), max(all_hi, hi), all_run + n_run
        stats[0], stats[1], stats[2] = all_lo, all_hi, all_run

    @cached_njit(nogil=True)
    def extreme_blocks(values, fr, fc, want_max, out, stats):  # pragma: no cover - compiled
        """out[i, j]: the largest (``want_max``) or smallest value of block (i, j), NaNs
        skipped (NaN if all are); stats: the smallest and largest finite positive value
        (inf, -inf if none)."""
        h, w = values.shape
        nr, nc = out.shape
        pos_lo, pos_hi = np.inf, -np.inf
        for i in range(nr):
            for j in range(nc):
                best = np.nan
                for r in range(i * fr, min(i * fr + fr, h)):
                    for c in range(j * fc, min(j * fc + fc, w)):
                        v = np.float64(values[r, c])
                        if v == v:
                            if best != best or (v > best if want_max else v < best):
                                best = v
                            if 0.0 < v < np.inf:
                                pos_lo, pos_hi = min(pos_lo, v), max(pos_hi, v)
                out[i, j] = best
        stats[0], stats[1] = pos_lo, pos_hi

    return mode_blocks, extreme_blocks


def _int16_labels(attractor: np.ndarray, status: np.ndarray) -> np.ndarray:
    """``attractor`` as int16 (the file's type, which the mode kernel indexes by), or
    ValueError if a labelled cell holds no int16."""
    if attractor.dtype == np.int16:
        return attractor
    labelled = np.isin(status, (TRAPPED, NEAR_BOUNDARY))
    k = attractor[labelled]
    if k.size and not (np.all(k == np.round(k)) and k.min() >= -32768 and k.max() <= 32767):
        raise ValueError("attractor labels that are not int16")
    return np.where(labelled, attractor, 0).astype(np.int16)


def _read_labels(ds: xr.Dataset, point: dict[str, int] | None = None
                 ) -> tuple[np.ndarray, int, int, bool]:
    """The basin map of ``ds`` at ``point`` (indices into the swept dims; none for a dataset
    of one point), read band by band and coarsened to at most MAX_PIXELS per axis: (image,
    kmin, kmax, running). The image holds each cell's (block's most frequent) well label k
    where status is trapped or near_boundary, kmax + 1 for the running basin (status running
    or running_near_boundary), NaN for no label; kmin and kmax span the well labels of the
    whole map (0, 0 if none); running: whether any cell runs."""
    fr, fc, out = _blocks(ds)

    def reduce(r0, r1, arrays):
        a, s = arrays
        if fr == fc == 1:
            k = a.astype(float)
            k[~np.isin(s, (TRAPPED, NEAR_BOUNDARY))] = np.nan
            running = (s == RUNNING) | (s == RUNNING_NEAR_BOUNDARY)
            k[running] = np.inf
            finite = k[np.isfinite(k)]
            out[r0:r1] = k
            lo, hi = (finite.min(), finite.max()) if finite.size else (np.inf, -np.inf)
            return lo, hi, bool(running.any())
        stats = np.empty(3, np.int64)
        _kernels()[0](_int16_labels(a, s), s, fr, fc, out[r0 // fr:-(-r1 // fr)], stats)
        return stats[0], stats[1], bool(stats[2])

    stats = _reduce_bands(ds, ["attractor", "status"], point or {}, fr, fc, reduce)
    lo, hi = min(s[0] for s in stats), max(s[1] for s in stats)
    kmin, kmax = (int(lo), int(hi)) if lo <= hi else (0, 0)
    out[np.isinf(out)] = kmax + 1
    return out, kmin, kmax, any(s[2] for s in stats)


def _read_extreme(ds: xr.Dataset, name: str, how: str, point: dict[str, int] | None = None
                  ) -> tuple[np.ndarray, float, float]:
    """The continuous map ``name`` of ``ds`` at ``point`` (as :func:`_read_labels`), read
    band by band and coarsened by the block ``how`` ("max" or "min", NaNs skipped): (image
    as float64, smallest and largest finite positive value of the whole map; NaN, NaN if
    none)."""
    fr, fc, out = _blocks(ds)

    def reduce(r0, r1, arrays):
        v = arrays[0]
        if fr == fc == 1:
            out[r0:r1] = v
            positive = out[r0:r1][np.isfinite(out[r0:r1]) & (out[r0:r1] > 0)]
            return (positive.min(), positive.max()) if positive.size else (np.inf, -np.inf)
        stats = np.empty(2)
        if v.dtype not in (np.float32, np.float64):
            v = v.astype(float)
        _kernels()[1](v, fr, fc, how == "max", out[r0 // fr:-(-r1 // fr)], stats)
        return stats[0], stats[1]

    stats = _reduce_bands(ds, [name], point or {}, fr, fc, reduce)
    lo, hi = min(s[0] for s in stats), max(s[1] for s in stats)
    return (out, float(lo), float(hi)) if lo <= hi else (out, np.nan, np.nan)


#: The maps that :func:`read_maps` reads: name → reader(dataset, point).
_MAP_READERS = {
    "basin": _read_labels,
    "t_trap": lambda ds, point: _read_extreme(ds, "t_trap", "max", point),
    "boundary_distance": lambda ds, point: _read_extreme(ds, "boundary_distance", "min", point),
}


def read_maps(tree: xr.DataTree, *names: str, **index) -> dict:
    """Read the maps ``names`` (default: all three) of one parameter point (``index`` as
    :func:`basin_map`) band by band, coarsened for drawing: the ``maps`` argument of
    :func:`basin_map`, :func:`trap_time_map` and :func:`boundary_distance_map`."""
    ds = tree.to_dataset(inherit=False)
    point = _point_index(ds, index)
    return {name: _MAP_READERS[name](ds, point) for name in names or _MAP_READERS}


# --------------------------------------------------------------------------- the figures

def _axes(ax, size: tuple[float, float]):
    """``ax``, or the Axes of a new pyplot figure of ``size`` [in] (pyplot manages it, as an
    interactive session expects; :func:`plot_atlas` draws into figures of its own)."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=size)[1]


def _map_scene(tree: xr.DataTree, name: str, maps: dict | None, index: dict
               ) -> tuple[xr.Dataset, dict]:
    """The point drawn (its dataset) and what every map figure shows of it: the grid (θ0
    [rad], θ̇0 [rad/s]), the map ``name`` as :func:`read_maps` reads it, and the separatrix
    branches (θ [rad], θ̇ [rad/s]; none where not stored)."""
    from atlas.boundaries.separatrices import branches

    ds = _single(tree.to_dataset(inherit=False), **index)
    sep = point_group(tree, "separatrices", point_of(ds))
    return ds, {"grid": (ds["theta0"].values, ds["theta_dot0"].values),
                "image": (maps or read_maps(tree, name, **index))[name],
                "separatrices": [] if sep is None else
                [(theta, theta_dot) for _, _, theta, theta_dot in branches(sep)]}


def _grid_image(ax, grid: tuple[np.ndarray, np.ndarray], image: np.ndarray, **kwargs):
    """Draw a map over the grid (θ0, θ̇0: columns, rows) as an image whose pixels are the
    grid's cells (centred on the grid points); ``image``: the map already coarsened to the
    figure's resolution (its blocks then span the same extent)."""
    th, v = grid
    half_t = 0.5 * (th[-1] - th[0]) / max(th.size - 1, 1)
    half_v = 0.5 * (v[-1] - v[0]) / max(v.size - 1, 1)
    image = ax.imshow(np.ma.masked_invalid(image), origin="lower",
                      extent=(th[0] - half_t, th[-1] + half_t, v[0] - half_v, v[-1] + half_v),
                      aspect="auto", interpolation="nearest", **kwargs)
    ax.set_xlim(th[0], th[-1])
    ax.set_ylim(v[0], v[-1])
    pi_ticks(ax, th[0], th[-1])
    ax.set_xlabel("θ0 [rad]")
    ax.set_ylabel("θ̇0 [rad/s]")
    return image


def _draw_separatrices(ax, separatrices: list) -> None:
    """The separatrix branches (θ [rad], θ̇ [rad/s]), in red."""
    for i, (theta, theta_dot) in enumerate(separatrices):
        ax.plot(theta, theta_dot, color=SEPARATRIX_COLOR, lw=1.2,
                label="separatrices" if i == 0 else None)


def _draw_limit_cycle(ax, lo: float, hi: float, theta: np.ndarray, theta_dot: np.ndarray,
                      period: float) -> None:
    """The running limit cycle (θ [rad], θ̇ [rad/s]; period [s]), repeated 2π-periodically
    across the window θ ∈ [lo, hi]."""
    order = np.argsort(theta)
    theta, theta_dot = theta[order], theta_dot[order]
    shifts = np.arange(np.floor((lo - theta.max()) / TWO_PI), np.ceil((hi - theta.min()) / TWO_PI)
                       + 1)
    for i, shift in enumerate(shifts):
        ax.plot(theta + TWO_PI * shift, theta_dot, color=CYCLE_COLOR, lw=1.6, ls="--",
                label=f"limit cycle (period {period:.4g} s)" if i == 0 else None)


def _basin_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`basin_map` draws: :func:`_map_scene`'s, the critical points (θ [rad],
    saddle or not, tilted or not) and the running limit cycle (θ [rad], θ̇ [rad/s], period
    [s]) where stored, and the title."""
    ds, scene = _map_scene(tree, "basin", maps, index)
    point = point_of(ds)
    cp = point_group(tree, "critical_points", point)
    cycle = point_group(tree, "limit_cycle", point)
    return scene | {
        "critical": None if cp is None else  # odd n: saddles
        (cp["theta"].values, cp["n"].values % 2 != 0, bool(float(ds["torque"]))),
        "cycle": None if cycle is None else
        (cycle["theta"].values, cycle["theta_dot"].values, float(cycle.attrs["period"])),
        "title": f"Basins of attraction, {point_title(point)}"}


def _draw_basin(ax, grid, image, separatrices, critical, cycle, title: str):
    """Draw :func:`_basin_scene` (as :func:`basin_map`)."""
    from matplotlib import colormaps
    from matplotlib.colors import BoundaryNorm, ListedColormap

    k, kmin, kmax, running = image
    colors = list(colormaps["tab10"](np.arange(kmin, kmax + 1) % 10))
    ticks, names = list(range(kmin, kmax + 1)), [f"{k:+d}" for k in range(kmin, kmax + 1)]
    if running:  # the running basin: one more colour after the wells
        colors.append(RUNNING_COLOR)
        ticks.append(kmax + 1)
        names.append("running")
    cmap = ListedColormap(colors).with_extremes(bad="white")
    levels = np.arange(kmin, kmin + len(colors) + 1) - 0.5
    mesh = _grid_image(ax, grid, k, cmap=cmap, norm=BoundaryNorm(levels, cmap.N))
    cbar = ax.figure.colorbar(mesh, ax=ax, ticks=ticks)
    cbar.ax.set_yticklabels(names)
    cbar.set_label("attractor k: orbit settles at the rest state of well k" if not running
                   else "attractor k: orbit settles at the rest state of well k;\n"
                   "running: orbit rotates (the running limit cycle)")
    _draw_separatrices(ax, separatrices)
    if cycle is not None:
        _draw_limit_cycle(ax, grid[0][0], grid[0][-1], *cycle)
    if critical is not None:
        critical_point_markers(ax, *critical)
    ax.set_title(title)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=3, borderaxespad=0)
    return ax


def basin_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the basin map of ``tree`` (colour by k) with critical points and separatrices;
    ``maps``: :func:`read_maps` of the same point, if already read."""
    return _draw_basin(_axes(ax, MAP_SIZE), **_basin_scene(tree, maps, **index))


def _trap_time_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`trap_time_map` draws (:func:`_map_scene`'s)."""
    return _map_scene(tree, "t_trap", maps, index)[1]


def _draw_trap_time(ax, grid, image, separatrices):
    """Draw :func:`_trap_time_scene` (as :func:`trap_time_map`)."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm

    # blocks keep their largest t_trap (the transform below is monotone: the same as the
    # largest of the transformed cells)
    t, lo, hi = image
    lo = lo if lo == lo else 1e-2
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = colormaps["magma"].with_extremes(under="0.8", bad="white")
    # t_trap = 0 (already inside the trap) is drawn below the scale, in grey
    mesh = _grid_image(ax, grid, np.where(t > 0, t, lo / 2), cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label("trapping time t_trap [s]")
    _draw_separatrices(ax, separatrices)
    ax.set_title("Time to certified trapping (grey: trapped at t = 0; white: never)")
    return ax


def trap_time_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the certified trapping time t_trap [s] on a log colour scale (``maps`` as
    :func:`basin_map`)."""
    return _draw_trap_time(_axes(ax, MAP_SIZE), **_trap_time_scene(tree, maps, **index))


def _boundary_distance_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`boundary_distance_map` draws: :func:`_map_scene`'s and d_cert [rad-ish]."""
    ds, scene = _map_scene(tree, "boundary_distance", maps, index)
    return scene | {"d_cert": float(ds["d_cert"])}


def _draw_boundary_distance(ax, grid, image, separatrices, d_cert: float):
    """Draw :func:`_boundary_distance_scene` (as :func:`boundary_distance_map`)."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm

    d, lo, hi = image
    lo = max(lo if lo == lo else 1e-12, d_cert if d_cert > 0 else 0, 1e-12)
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = colormaps["viridis"].with_extremes(under="white", bad="0.5")
    mesh = _grid_image(ax, grid, d, cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label(
        "distance to the nearest basin boundary (rad-ish)")
    _draw_separatrices(ax, separatrices)
    cert = f"d_cert = {d_cert:.1e}" if d_cert == d_cert else "d_cert not measured"
    ax.set_title(f"Distance to tipping into another well (white: closer than {cert})")
    return ax


def boundary_distance_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw ``boundary_distance`` on a log colour scale, the separatrices, and in white the
    states closer than d_cert (labels certified for the RK4 map only); ``maps`` as
    :func:`basin_map`."""
    return _draw_boundary_distance(_axes(ax, MAP_SIZE),
                                   **_boundary_distance_scene(tree, maps, **index))


#: Axis labels of the parameters.
PARAMETER_AXES = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
                  "torque": "torque τ [rad/s²]"}


def _held(full: xr.Dataset, ds: xr.Dataset, dim: str) -> str:
    """The title's second line: the swept parameters other than ``dim`` at the values held."""
    held = {n: float(ds[n]) for n in PARAMETERS if n != dim and n in full.dims}
    return f"\nat {point_label(held)}" if held else ""


def _fraction_scene(tree: xr.DataTree, dim: str = "alpha", max_curves: int = 7) -> dict:
    """What :func:`fraction_curves` draws: the swept values, the curves (exact fractions,
    grid counts, their bounds, label, colour), α = ω0 where α is swept, and the labels."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in full["basin_fraction_exact"].dims if d not in (dim, "k")})
    exact = ds["basin_fraction_exact"].transpose(dim, "k").values
    grid = ds["basin_fraction"].transpose(dim, "k").values
    bound = ds["basin_fraction_grid_error_bound"].transpose(dim, "k").values
    shown = np.sort(np.argsort(exact.max(axis=0))[::-1][:max_curves])
    rest = np.setdiff1d(np.arange(exact.shape[1]), shown)
    curves = [(exact[:, j], grid[:, j], bound[:, j], f"k = {int(ds['k'].values[j]):+d}", None)
              for j in shown]
    if rest.size:
        curves.append((exact[:, rest].sum(axis=1), grid[:, rest].sum(axis=1),
                       bound[:, rest].sum(axis=1), f"other k ({rest.size})", "0.5"))
    return {"x": ds[dim].values, "curves": curves,
            "critical": float(ds["omega0"]) if dim == "alpha" and ds["omega0"].ndim == 0
            else None, "xlabel": PARAMETER_AXES[dim],
            "title": "Basin fractions: exact areas (lines), grid counts with error bounds "
                     "(dots)" + _held(full, ds, dim)}


def _draw_fractions(ax, x, curves, critical, xlabel: str, title: str):
    """Draw :func:`_fraction_scene` (as :func:`fraction_curves`)."""
    for e, g, b, label, color in curves:
        line, = ax.plot(x, e, "-", color=color, label=label)
        ax.errorbar(x, g, yerr=b, fmt="o", ms=3, capsize=2, color=line.get_color())
    if critical is not None:
        ax.axvline(critical, color="0.3", ls=":", lw=1, label="α = ω0 (critical)")
    ax.set_xscale("log" if x.min() > 0 and x.max() / x.min() > 20 else "linear")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("basin fraction of the window")
    ax.set_title(title)
    ax.legend(ncol=2)
    return ax


def fraction_curves(tree: xr.DataTree, ax=None, dim: str = "alpha", max_curves: int = 7):
    """Exact basin fraction of each k against the swept parameter ``dim`` (lines), with the
    grid counts and their error bounds (markers with error bars); any other swept parameter
    is held at its first value (named in the title).

    The ``max_curves`` largest basins get a curve each; the rest are summed into one
    "other k" curve. A dashed line marks critical damping α = ω0 when α is swept.
    """
    return _draw_fractions(_axes(ax, CURVE_SIZE), **_fraction_scene(tree, dim, max_curves))


def _stability_scene(tree: xr.DataTree, dim: str = "torque") -> dict:
    """What :func:`basin_stability` draws: the swept values, the rest states' and the running
    basin's shares (exact and grid counts), the grid error bound, and the labels."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in PARAMETERS if d in full.dims and d != dim})
    return {"x": ds[dim].values,
            "exact": ds["basin_fraction_exact"].sum("k", skipna=False).values,
            "grid": ds["basin_fraction"].sum("k").values,
            "bound": ds["basin_fraction_grid_error_bound"].sum("k", skipna=False).values,
            "running": ds["running_fraction"].values,
            "running_exact": ds["running_fraction_exact"].values,
            "xlabel": PARAMETER_AXES[dim],
            "title": "Basin stability of the rest states and of the running cycle"
                     + _held(full, ds, dim)}


def _draw_stability(ax, x, exact, grid, bound, running, running_exact, xlabel: str,
                    title: str):
    """Draw :func:`_stability_scene` (as :func:`basin_stability`)."""
    shown = np.isfinite(exact)
    if shown.any():
        ax.plot(x[shown], exact[shown], "-", color="C0", label="rest states, exact area")
        ax.plot(x[shown], running_exact[shown], "-", color="0.4", label="running, exact area")
    ax.errorbar(x, grid, yerr=np.where(np.isfinite(bound), bound, 0.0), fmt="o", ms=3,
                capsize=2, color="C0", label="rest states, grid count")
    ax.plot(x, running, "s", ms=3, color="0.4", label="running, grid count")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("basin stability (fraction of the window)")
    ax.set_ylim(-0.02, 1.02)
    ax.set_title(title)
    ax.legend()
    return ax


def basin_stability(tree: xr.DataTree, ax=None, dim: str = "torque"):
    """Basin stability against the swept parameter ``dim``: the share of the window that
    settles at a rest state (all wells together) and the running basin's share, as exact
    areas (lines, where computed) and grid counts (markers; error bars: the grid error bound,
    where computed). Any other swept parameter is held at its first value."""
    return _draw_stability(_axes(ax, CURVE_SIZE), **_stability_scene(tree, dim))


# --------------------------------------------------------------------------- writing them

def _figure_jobs(tree: xr.DataTree, path: Path) -> list[tuple]:
    """The figures of ``tree`` to write next to ``path``, read: (PNG path, size [in], drawer,
    scene) each, every scene read from the tree (the maps band by band)."""
    path = Path(path)
    maps = read_maps(tree)
    jobs = [(path.with_suffix(".png"), MAP_SIZE, _draw_basin, _basin_scene(tree, maps)),
            (path.with_name(path.stem + "_t_trap.png"), MAP_SIZE, _draw_trap_time,
             _trap_time_scene(tree, maps)),
            (path.with_name(path.stem + "_boundary_distance.png"), MAP_SIZE,
             _draw_boundary_distance, _boundary_distance_scene(tree, maps))]
    swept = tree.to_dataset(inherit=False).dims
    for dim in (name for name in PARAMETERS if name in swept):
        jobs.append((path.with_name(f"{path.stem}_fractions_{dim}.png"), CURVE_SIZE,
                     _draw_fractions, _fraction_scene(tree, dim)))
        if dim == "torque":
            jobs.append((path.with_name(f"{path.stem}_basin_stability.png"), CURVE_SIZE,
                         _draw_stability, _stability_scene(tree)))
    return jobs


def _draw_figure(out: Path, size: tuple[float, float], draw, scene: dict) -> Path:
    """Draw ``scene`` (``draw(ax, **scene)``) into a figure of ``size`` [in] of its own (no
    pyplot), laid out tight, and write it to ``out`` (PNG)."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with matplotlib.rc_context(STYLE):
        # laid out at the resolution it is saved at, so that the text the layout measures
        # is measured once (matplotlib caches it per renderer and resolution)
        fig = Figure(figsize=size, dpi=STYLE["savefig.dpi"])
        FigureCanvasAgg(fig)
        draw(fig.add_subplot(), **scene)
        fig.tight_layout()
        # laid out once: without this, savefig would draw the figure once more first
        # (for tight_layout's placeholder engine) before drawing it into the PNG
        fig.set_layout_engine(None)
        fig.savefig(out, pil_kwargs=PNG_OPTIONS)
    return out


def plot_atlas(tree: xr.DataTree, path: Path) -> list[Path]:
    """Write the figures of the atlas stored at ``path`` next to it; returns the PNG paths.

    Everything drawn is read before the first PNG is written (a file that cannot be read
    leaves none): the maps of the drawn parameter point band by band, coarsened to the
    figure's pixels (:func:`read_maps`), so that the memory needed is bounded whatever the
    size of the map, and what else each figure shows."""
    return [_draw_figure(*job) for job in _figure_jobs(tree, path)]


def plot_file(path: str | Path) -> list[Path]:
    """``atlas plot``: :func:`plot_atlas` of the atlas file at ``path``, opened and closed
    here.

    On Linux the figures are drawn by forked processes (:class:`atlas.views.forked.ForkedJobs`):
    one is started first and imports matplotlib (:func:`_warm_up`) while this one opens and
    reads the file, then draws the figures with forks of itself, on every core at once (one
    process per core and one more, so that a figure that finishes first does not leave a core
    idle: three for the three maps on 2 cores). Elsewhere (no safe ``fork``) they are drawn
    here, after reading."""
    from atlas.views.forked import ForkedJobs, can_fork

    drawers = ForkedJobs.start(_warm_up, _draw_job, _workers() + 1) if can_fork() else None
    try:
        from atlas.store.atlasfile import (
            open_atlas,  # imported after the fork: xarray, h5py only here
        )

        tree = open_atlas(path)
        try:
            jobs = _figure_jobs(tree, path)
        finally:
            tree.close()
        if drawers is None:
            return [_draw_job(job) for job in jobs]
        drawers.run(jobs)
        return [job[0] for job in jobs]
    finally:
        if drawers is not None:
            drawers.close()


def _draw_job(job: tuple) -> Path:
    """:func:`_draw_figure` of one of :func:`_figure_jobs`."""
    return _draw_figure(*job)


def _warm_up() -> None:
    """Import what drawing needs and draw a small figure with a legend, a log colour bar and
    a PNG of it, so that every drawing process forked after this finds matplotlib, the fonts,
    the mathtext parser and the PNG writer ready. The colour bar spans 1e-16 to 1e4, so the
    labels 10^k of the log colour bars (trapping times, boundary distances) are parsed here
    once, while the reader is still reading, rather than in each figure."""
    import io

    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm

    def draw(ax):
        ax.plot([0.0, 1.0], label="θ̇0 [rad/s]")
        ax.legend()
        ax.figure.colorbar(ScalarMappable(LogNorm(1e-16, 1e4)), ax=ax)

    _draw_figure(io.BytesIO(), (2, 2), draw, {})
