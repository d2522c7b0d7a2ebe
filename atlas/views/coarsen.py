"""Reading a map for a figure: band by band, coarsened to the figure's pixels.

A map larger than MAX_PIXELS per axis is read in bands of whole rows (whole blocks of the
coarsening, aligned to the file's chunks; for a tree opened lazily, the stored chunks are
inflated here: :func:`atlas.store.reader.stored_rows`) and each band is reduced to blocks
by compiled kernels: labels by their mode (never averaged into a k that no orbit reached),
t_trap by the block max, boundary_distance by the block min. So the memory a figure needs
does not grow with the map (a 16384² atlas: about 0.5 GB). :func:`coarsen_blocks` is the
definition on a whole array, which the streamed readers equal (tested).
"""

from __future__ import annotations

import functools
import math
import os
import warnings
from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import parameter_names
from atlas.models.registry import of_attrs

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["MAX_PIXELS", "BAND_CELLS", "read_maps", "workers", "coarsen_blocks"]

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


def coarsen_blocks(values: np.ndarray, how: str) -> np.ndarray:
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




def _point_index(ds: xr.Dataset, index: dict) -> dict[str, int]:
    """The parameter point that :func:`atlas.layout.first_point` selects with ``index``, as
    an index (≥ 0) into each swept dim."""
    return {name: range(ds.sizes[name])[index.get(name, 0)] for name in parameter_names(ds)
            if name in ds.dims}


def _chunk_rows(da: xr.DataArray) -> int:
    """Rows of one stored chunk of ``da`` (1 if unknown)."""
    if da.chunks:  # dask
        return int(da.chunks[0][0])
    preferred = da.encoding.get("preferred_chunks") or {}
    if da.dims[-2] in preferred:  # the rows
        return int(preferred[da.dims[-2]])
    sizes = da.encoding.get("chunksizes") or da.encoding.get("chunks")
    return int(sizes[-2]) if sizes and len(sizes) >= 2 else 1


class _MapRows:
    """One map of one parameter point (rows: the model's velocity axis, columns: its
    position axis; for the pendulum θ̇0 and θ0), read a range of rows at a time:
    through xarray (from memory, or the file's own decoding for a lazy tree), or for a map
    that is coarsened and stored as an atlas file stores it (deflated, shuffled, chunks of
    whole rows), as its stored chunks inflated in this process
    (:func:`atlas.store.reader.stored_rows`)."""

    def __init__(self, ds: xr.Dataset, name: str, point: dict[str, int], coarsened=False):
        columns, rows = of_attrs(ds.attrs).axes
        self.rows = rows.name
        self.da = ds[name].isel(point).transpose(rows.name, columns.name)
        self.shape = self.da.shape
        from atlas.store.reader import stored_rows

        self.raw = stored_rows(ds, name, point) if coarsened else None
        self.chunk_rows = self.raw.rows if self.raw else _chunk_rows(self.da)

    def read(self, r0: int, r1: int) -> np.ndarray:
        if self.raw is not None:
            rows = self.raw.read(r0, r1)
            if rows is not None:
                return rows
        return np.asarray(self.da.isel({self.rows: slice(r0, r1)}).values)

    def close(self) -> None:
        if self.raw is not None:
            self.raw.close()


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


def workers() -> int:
    """Threads that read and reduce bands at once (each holds one band)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, min(cores or 1, 8))


def _blocks(ds: xr.Dataset) -> tuple[int, int, np.ndarray]:
    """(fr, fc, an empty image): the block of the coarsening of the maps of ``ds``, and an
    image of one pixel per block."""
    columns, rows = of_attrs(ds.attrs).axes
    rows, cols = ds.sizes[rows.name], ds.sizes[columns.name]
    fr, fc = _factors((rows, cols))
    return fr, fc, np.empty((-(-rows // fr), -(-cols // fc)))


def _reduce_bands(ds: xr.Dataset, names: list[str], point: dict[str, int], fr: int, fc: int,
                  reduce) -> list:
    """Read the maps ``names`` at ``point`` band by band (whole blocks of fr × fc cells), the
    rows [r0, r1) of each at once, and call ``reduce(r0, r1, arrays)`` on every band;
    returns the results in the order of the bands. Coarsened maps are read and reduced by
    :func:`workers` threads at once (the kernels and zlib release the GIL), each holding
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
        with ThreadPoolExecutor(workers()) as pool:
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
    def mode_blocks(attractor, status, kinds, fr, fc, out, stats):  # pragma: no cover
        """out[i, j]: the most frequent well label of block (i, j) of these rows (ties: the
        smallest k), inf if running cells outnumber every well label, NaN if no cell has a
        label. stats: the smallest and largest well label, and the number of running cells.
        ``kinds``: the model's :meth:`~atlas.models.base.Model.status_kinds` (1 a label k,
        2 running, over status + 128)."""
        h, w = attractor.shape
        nr, nc = out.shape
        counts = np.zeros(65536, np.int64)
        all_lo, all_hi, all_run = 1 << 20, -(1 << 20), 0
        for i in range(nr):
            for j in range(nc):
                lo, hi, n_run = 1 << 20, -(1 << 20), 0
                for r in range(i * fr, min(i * fr + fr, h)):
                    for c in range(j * fc, min(j * fc + fc, w)):
                        s = kinds[np.int64(status[r, c]) + 128]
                        if s == 1:
                            k = np.int64(attractor[r, c])
                            counts[k + 32768] += 1
                            lo = min(lo, k)
                            hi = max(hi, k)
                        elif s == 2:
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


def _int16_labels(attractor: np.ndarray, status: np.ndarray, kinds: np.ndarray) -> np.ndarray:
    """``attractor`` as int16 (the file's type, which the mode kernel indexes by), or
    ValueError if a labelled cell holds no int16."""
    if attractor.dtype == np.int16:
        return attractor
    labelled = kinds[status.astype(np.int64) + 128] == 1
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
    whole map (0, 0 if none); running: whether any cell runs. Which statuses carry a label
    (and which run) is the file's model's (:meth:`atlas.models.base.Model.status_kinds`)."""
    fr, fc, out = _blocks(ds)
    kinds = of_attrs(ds.attrs).status_kinds()

    def reduce(r0, r1, arrays):
        a, s = arrays
        if fr == fc == 1:
            kind = kinds[s.astype(np.int64) + 128]
            k = a.astype(float)
            k[kind != 1] = np.nan
            running = kind == 2
            k[running] = np.inf
            finite = k[np.isfinite(k)]
            out[r0:r1] = k
            lo, hi = (finite.min(), finite.max()) if finite.size else (np.inf, -np.inf)
            return lo, hi, bool(running.any())
        stats = np.empty(3, np.int64)
        _kernels()[0](_int16_labels(a, s, kinds), s, kinds, fr, fc, out[r0 // fr:-(-r1 // fr)],
                      stats)
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
    """Read the maps ``names`` (default: all three) of one parameter point (``index``: an
    index into each swept dim, as :func:`atlas.layout.first_point`) band by band, coarsened
    for drawing: the ``maps`` argument of :func:`atlas.views.maps.basin_map`,
    ``trap_time_map`` and ``boundary_distance_map``."""
    ds = tree.to_dataset(inherit=False)
    point = _point_index(ds, index)
    return {name: _MAP_READERS[name](ds, point) for name in names or _MAP_READERS}
