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
"""

from __future__ import annotations

import functools
import math
import os
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm  # noqa: E402

from .kernels import NEAR_BOUNDARY, RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED  # noqa: E402
from .layout import PARAMETERS, first_point, point_group, point_label, point_of  # noqa: E402
from .store import StoredRows  # noqa: E402

__all__ = ["basin_map", "trap_time_map", "boundary_distance_map", "fraction_curves",
           "plot_atlas", "read_maps", "pi_ticks", "critical_point_markers", "STYLE"]

#: One style for every atlas figure.
STYLE = {"figure.dpi": 110, "savefig.dpi": 150, "axes.grid": False, "font.size": 10,
         "axes.titlesize": 11, "legend.fontsize": 8, "legend.frameon": False}
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


def _critical(ax, tree: xr.DataTree, ds: xr.Dataset) -> None:
    """The critical points of the parameter point that ``ds`` shows, if stored, as
    :func:`critical_point_markers`."""
    cp = point_group(tree, "critical_points", point_of(ds))
    if cp is None:
        return
    critical_point_markers(ax, cp["theta"].values, cp["n"].values % 2 != 0,  # odd n: saddles
                           tilted=bool(float(ds["torque"])))


def _limit_cycle(ax, tree: xr.DataTree, ds: xr.Dataset) -> None:
    """The running limit cycle of the parameter point that ``ds`` shows (if it has one),
    repeated 2π-periodically across the window."""
    cycle = point_group(tree, "limit_cycle", point_of(ds))
    if cycle is None:
        return
    theta, speed = cycle["theta"].values, cycle["theta_dot"].values
    lo, hi = float(ds["theta0"][0]), float(ds["theta0"][-1])
    order = np.argsort(theta)
    theta, speed = theta[order], speed[order]
    shifts = np.arange(np.floor((lo - theta.max()) / TWO_PI), np.ceil((hi - theta.min()) / TWO_PI)
                       + 1)
    for i, shift in enumerate(shifts):
        ax.plot(theta + TWO_PI * shift, speed, color=CYCLE_COLOR, lw=1.6, ls="--",
                label=f"limit cycle (period {float(cycle.attrs['period']):.4g} s)"
                if i == 0 else None)


def _separatrices(ax, tree: xr.DataTree, ds: xr.Dataset) -> None:
    """The separatrices of the parameter point that ``ds`` shows, in red."""
    from .separatrices import branches

    sep = point_group(tree, "separatrices", point_of(ds))
    if sep is None:
        return
    for i, (_, _, theta, theta_dot) in enumerate(branches(sep)):
        ax.plot(theta, theta_dot, color=SEPARATRIX_COLOR, lw=1.2,
                label="separatrices" if i == 0 else None)


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
    (:class:`atlas.store.StoredRows`)."""

    def __init__(self, ds: xr.Dataset, name: str, point: dict[str, int], coarsened=False):
        self.da = ds[name].isel(point).transpose("theta_dot0", "theta0")
        self.shape = self.da.shape
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
    from .kernels import cached_njit

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


def _grid_image(ax, ds: xr.Dataset, image: np.ndarray, **kwargs):
    """Draw a map over the grid (rows θ̇0, columns θ0) as an image whose pixels are the grid's
    cells (centred on the grid points); ``image``: the map already coarsened to the figure's
    resolution (its blocks then span the same extent)."""
    th, v = ds["theta0"].values, ds["theta_dot0"].values
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


def basin_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the basin map of ``tree`` (colour by k) with critical points and separatrices;
    ``maps``: :func:`read_maps` of the same point, if already read."""
    ds = _single(tree.to_dataset(inherit=False), **index)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.8))
    k, kmin, kmax, running = (maps or read_maps(tree, "basin", **index))["basin"]
    colors = list(plt.get_cmap("tab10")(np.arange(kmin, kmax + 1) % 10))
    ticks, names = list(range(kmin, kmax + 1)), [f"{k:+d}" for k in range(kmin, kmax + 1)]
    if running:  # the running basin: one more colour after the wells
        colors.append(RUNNING_COLOR)
        ticks.append(kmax + 1)
        names.append("running")
    cmap = ListedColormap(colors).with_extremes(bad="white")
    levels = np.arange(kmin, kmin + len(colors) + 1) - 0.5
    mesh = _grid_image(ax, ds, k, cmap=cmap, norm=BoundaryNorm(levels, cmap.N))
    cbar = ax.figure.colorbar(mesh, ax=ax, ticks=ticks)
    cbar.ax.set_yticklabels(names)
    cbar.set_label("attractor k: orbit settles at the rest state of well k"
                   + ("; running: rotates" if running else ""))
    _separatrices(ax, tree, ds)
    _limit_cycle(ax, tree, ds)
    _critical(ax, tree, ds)
    ax.set_title(f"Basins of attraction, {point_title(point_of(ds))}")
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=3, borderaxespad=0)
    return ax


def trap_time_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the certified trapping time t_trap [s] on a log colour scale (``maps`` as
    :func:`basin_map`)."""
    ds = _single(tree.to_dataset(inherit=False), **index)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.8))
    # blocks keep their largest t_trap (the transform below is monotone: the same as the
    # largest of the transformed cells)
    t, lo, hi = (maps or read_maps(tree, "t_trap", **index))["t_trap"]
    lo = lo if lo == lo else 1e-2
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = plt.get_cmap("magma").with_extremes(under="0.8", bad="white")
    # t_trap = 0 (already inside the trap) is drawn below the scale, in grey
    mesh = _grid_image(ax, ds, np.where(t > 0, t, lo / 2), cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label("trapping time t_trap [s]")
    _separatrices(ax, tree, ds)
    ax.set_title("Time to certified trapping (grey: trapped at t = 0; white: never)")
    return ax


def boundary_distance_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw ``boundary_distance`` on a log colour scale, the separatrices, and in white the
    states closer than d_cert (labels certified for the RK4 map only); ``maps`` as
    :func:`basin_map`."""
    ds = _single(tree.to_dataset(inherit=False), **index)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.8))
    d, lo, hi = (maps or read_maps(tree, "boundary_distance", **index))["boundary_distance"]
    d_cert = float(ds["d_cert"])
    lo = max(lo if lo == lo else 1e-12, d_cert if d_cert > 0 else 0, 1e-12)
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = plt.get_cmap("viridis").with_extremes(under="white", bad="0.5")
    mesh = _grid_image(ax, ds, d, cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label(
        "distance to the nearest basin boundary (rad-ish)")
    _separatrices(ax, tree, ds)
    cert = f"d_cert = {d_cert:.1e}" if d_cert == d_cert else "d_cert not measured"
    ax.set_title(f"Distance to tipping into another well (white: closer than {cert})")
    return ax


#: Axis labels of the parameters.
PARAMETER_AXES = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
                  "torque": "torque τ [rad/s²]"}


def fraction_curves(tree: xr.DataTree, ax=None, dim: str = "alpha", max_curves: int = 7):
    """Exact basin fraction of each k against the swept parameter ``dim`` (lines), with the
    grid counts and their error bounds (markers with error bars); any other swept parameter
    is held at its first value (named in the title).

    The ``max_curves`` largest basins get a curve each; the rest are summed into one
    "other k" curve. A dashed line marks critical damping α = ω0 when α is swept.
    """
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in full["basin_fraction_exact"].dims if d not in (dim, "k")})
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    x = ds[dim].values
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
    for e, g, b, label, color in curves:
        line, = ax.plot(x, e, "-", color=color, label=label)
        ax.errorbar(x, g, yerr=b, fmt="o", ms=3, capsize=2, color=line.get_color())
    if dim == "alpha" and ds["omega0"].ndim == 0:
        ax.axvline(float(ds["omega0"]), color="0.3", ls=":", lw=1, label="α = ω0 (critical)")
    ax.set_xscale("log" if x.min() > 0 and x.max() / x.min() > 20 else "linear")
    ax.set_xlabel(PARAMETER_AXES[dim])
    ax.set_ylabel("basin fraction of the window")
    held = {n: float(ds[n]) for n in PARAMETERS if n != dim and n in full.dims}
    ax.set_title("Basin fractions: exact areas (lines), grid counts with error bounds (dots)"
                 + (f"\nat {point_label(held)}" if held else ""))
    ax.legend(ncol=2)
    return ax


def basin_stability(tree: xr.DataTree, ax=None, dim: str = "torque"):
    """Basin stability against the swept parameter ``dim``: the share of the window that
    settles at a rest state (all wells together) and the running basin's share, as exact
    areas (lines, where computed) and grid counts (markers; error bars: the grid error bound,
    where computed). Any other swept parameter is held at its first value."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in PARAMETERS if d in full.dims and d != dim})
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    x = ds[dim].values
    exact = ds["basin_fraction_exact"].sum("k", skipna=False).values
    grid = ds["basin_fraction"].sum("k").values
    bound = ds["basin_fraction_grid_error_bound"].sum("k", skipna=False).values
    running = ds["running_fraction"].values
    running_exact = ds["running_fraction_exact"].values
    shown = np.isfinite(exact)
    if shown.any():
        ax.plot(x[shown], exact[shown], "-", color="C0", label="rest states, exact area")
        ax.plot(x[shown], running_exact[shown], "-", color="0.4", label="running, exact area")
    ax.errorbar(x, grid, yerr=np.where(np.isfinite(bound), bound, 0.0), fmt="o", ms=3,
                capsize=2, color="C0", label="rest states, grid count")
    ax.plot(x, running, "s", ms=3, color="0.4", label="running, grid count")
    ax.set_xlabel(PARAMETER_AXES[dim])
    ax.set_ylabel("basin stability (fraction of the window)")
    ax.set_ylim(-0.02, 1.02)
    held = {n: float(ds[n]) for n in PARAMETERS if n != dim and n in full.dims}
    ax.set_title("Basin stability of the rest states and of the running cycle"
                 + (f"\nat {point_label(held)}" if held else ""))
    ax.legend()
    return ax


#: The root variables of the basin map (one value per grid point): read band by band.
MAP_VARIABLES = ("attractor", "status", "t_trap", "boundary_distance")


def _load_all_but_the_maps(tree: xr.DataTree) -> None:
    """Read (in place) every variable of ``tree`` except the root's basin maps: the summary
    and the groups, each small."""
    for name, variable in tree.variables.items():
        if name not in MAP_VARIABLES:
            variable.load()
    for child in tree.children.values():
        child.load()


def plot_atlas(tree: xr.DataTree, path: Path) -> list[Path]:
    """Write the figures of the atlas stored at ``path`` next to it; returns the PNG paths.

    Everything drawn is read before the first PNG is written (a file that cannot be read
    leaves none): the summary and the groups whole, the maps of the drawn parameter point
    band by band, coarsened to the figure's pixels (:func:`read_maps`), so that the memory
    needed is bounded whatever the size of the map."""
    path = Path(path)
    written = []
    _load_all_but_the_maps(tree)
    ds = tree.to_dataset(inherit=False)
    maps = read_maps(tree)
    with plt.rc_context(STYLE):
        jobs = [(path.with_suffix(".png"), basin_map),
                (path.with_name(path.stem + "_t_trap.png"), trap_time_map),
                (path.with_name(path.stem + "_boundary_distance.png"), boundary_distance_map)]
        jobs = [(out, functools.partial(draw, maps=maps)) for out, draw in jobs]
        for dim in (name for name in PARAMETERS if name in ds.dims):
            jobs.append((path.with_name(f"{path.stem}_fractions_{dim}.png"),
                         functools.partial(fraction_curves, dim=dim)))
            if dim == "torque":
                jobs.append((path.with_name(f"{path.stem}_basin_stability.png"),
                             basin_stability))
        for out, draw in jobs:
            ax = draw(tree)
            ax.figure.tight_layout()
            # laid out once: without this, savefig would draw the figure once more first
            # (for tight_layout's placeholder engine) before drawing it into the PNG
            ax.figure.set_layout_engine(None)
            ax.figure.savefig(out)
            plt.close(ax.figure)
            written.append(out)
    return written
