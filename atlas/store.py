"""The atlas file: one HDF5 file in netCDF-4 layout (xarray's ``h5netcdf`` engine).

This is the only module that touches HDF5. A run writes into ``<output>.partial``:

1. :func:`create` pre-creates the chunked, compressed basin-map variables (one chunk per
   tile row band) and a ``tile_done`` record;
2. :func:`write_tile` writes each finished tile by region and marks it done, then flushes,
   so a crash loses at most the tile in flight and ``--resume`` redoes only missing tiles;
3. :func:`finalize` adds the basin fractions and the small groups (``/critical_points``,
   ``/separatrices``) and renames the file onto the output path, so the output path only ever
   holds a complete file.

Layout (SPEC.md): root dims ``theta_dot0``, ``theta0`` (leading ``alpha``, ``omega0`` for a
parameter atlas); ``attractor`` int16 (``_FillValue`` where not trapped), ``status`` int8
(CF flags), ``t_trap`` float32 [s]; ``basin_fraction`` and ``basin_fraction_stderr`` over
``k``; provenance attributes.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import h5netcdf
import h5py
import numpy as np
import xarray as xr

from .errors import InputFileError
from .labels import ATTRACTOR_FILL

__all__ = ["Layout", "create", "open_partial", "write_tile", "finalize", "open_atlas",
           "partial_path", "describe", "read_layout"]

STATUS_FLAGS = {"flag_values": np.array([0, 1, 2], np.int8),
                "flag_meanings": "trapped unresolved nonfinite"}
_COMPRESSION = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
SCHEMA = "atlas-basin-map/1"


def partial_path(output: Path) -> Path:
    """Where an unfinished run keeps its data: next to the output, never at it."""
    return output.with_name(output.name + ".partial")


@dataclass(frozen=True)
class Layout:
    """Shape of a basin atlas: parameter values, grid axes and the row-band tiling.

    ``alpha``/``omega0`` are None for a single-parameter atlas (no leading dims).
    A tile is one row band ``rows`` of one parameter point ``(ia, iw)``.
    """

    theta0: np.ndarray
    theta_dot0: np.ndarray
    alpha: np.ndarray | None
    omega0: np.ndarray | None
    rows_per_tile: int

    @property
    def n_params(self) -> int:
        return 1 if self.alpha is None else self.alpha.size * self.omega0.size

    @property
    def bands(self) -> int:
        return -(-self.theta_dot0.size // self.rows_per_tile)

    @property
    def n_tiles(self) -> int:
        return self.n_params * self.bands

    @property
    def dims(self) -> tuple[str, ...]:
        lead = () if self.alpha is None else ("alpha", "omega0")
        return (*lead, "theta_dot0", "theta0")

    def tile(self, index: int) -> tuple[tuple[int, ...], slice]:
        """(parameter index tuple, row slice) of tile ``index``; () for no sweep."""
        p, band = divmod(index, self.bands)
        rows = slice(band * self.rows_per_tile,
                     min((band + 1) * self.rows_per_tile, self.theta_dot0.size))
        if self.alpha is None:
            return (), rows
        return divmod(p, self.omega0.size), rows


def _chunks(layout: Layout) -> tuple[int, ...]:
    lead = (1, 1) if layout.alpha is not None else ()
    return (*lead, min(layout.rows_per_tile, layout.theta_dot0.size), layout.theta0.size)


def create(path: Path, layout: Layout, attrs: dict) -> h5netcdf.File:
    """Create a new partial atlas at ``path`` with empty basin-map variables."""
    f = h5netcdf.File(path, "w")
    try:
        coords = {"theta_dot0": (layout.theta_dot0, "rad s-1", "initial angular velocity"),
                  "theta0": (layout.theta0, "rad", "initial angle")}
        if layout.alpha is not None:
            coords = {"alpha": (layout.alpha, "s-1", "damping constant"),
                      "omega0": (layout.omega0, "rad s-1", "natural angular frequency"),
                      **coords}
        f.dimensions = {name: values[0].size for name, values in coords.items()}
        f.dimensions["tile"] = layout.n_tiles
        for name, (values, units, long_name) in coords.items():
            var = f.create_variable(name, (name,), np.float64, data=values)
            var.attrs.update(units=units, long_name=long_name)
        chunks = _chunks(layout)
        specs = {
            "attractor": (np.int16, ATTRACTOR_FILL, {
                "long_name": "index k of the attractor (2*pi*k, 0) reached",
                "units": "1", "comment": "fill value where status != trapped"}),
            "status": (np.int8, None, {"long_name": "labelling status", "units": "1",
                                       **STATUS_FLAGS}),
            "t_trap": (np.float32, np.float32(np.nan), {
                "long_name": "time at which the orbit was certified trapped", "units": "s"}),
        }
        for name, (dtype, fill, var_attrs) in specs.items():
            var = f.create_variable(name, layout.dims, dtype, fillvalue=fill, chunks=chunks,
                                    **_COMPRESSION)
            var.attrs.update(var_attrs)
        done = f.create_variable("tile_done", ("tile",), np.int8,
                                 data=np.zeros(layout.n_tiles, np.int8))
        done.attrs.update(long_name="tile finished and written", units="1",
                          rows_per_tile=np.int64(layout.rows_per_tile))
        f.attrs.update({key: value for key, value in attrs.items() if value is not None})
        f.attrs["atlas_schema"] = SCHEMA
        f.attrs["complete"] = np.int8(0)
        _sync(f)
    except BaseException:
        f.close()
        raise
    return f


def read_layout(f: h5netcdf.File) -> Layout:
    """The layout a file was created with (its tiling included)."""
    sweep = "alpha" in f.variables
    return Layout(
        theta0=f.variables["theta0"][...], theta_dot0=f.variables["theta_dot0"][...],
        alpha=f.variables["alpha"][...] if sweep else None,
        omega0=f.variables["omega0"][...] if sweep else None,
        rows_per_tile=int(f.variables["tile_done"].attrs["rows_per_tile"]),
    )


def open_partial(path: Path, config_hash: str) -> tuple[h5netcdf.File, Layout, np.ndarray]:
    """Reopen an interrupted run for ``--resume``: (file, its layout, tiles still to do).

    The file's own tiling is kept, so a resume may use another ``tile_orbits``. Refuses a
    file that is unreadable or was made from a different config.
    """
    try:
        _discard_summary(path)
        f = h5netcdf.File(path, "a")
    except (OSError, ValueError, KeyError) as exc:
        raise InputFileError(f"{path}: cannot resume, the partial file is unreadable "
                             f"({exc.__class__.__name__}); delete it to start over") from None
    if f.attrs.get("config_hash") != config_hash:
        f.close()
        raise InputFileError(f"{path}: cannot resume, the partial file was made from a "
                             "different config; delete it or run without --resume")
    done = f.variables["tile_done"][...]
    return f, read_layout(f), np.flatnonzero(done == 0)


def _sync(f: h5netcdf.File) -> None:
    """Push everything written so far to disk. h5netcdf's own ``flush`` only writes its
    netCDF bookkeeping, so the HDF5 file underneath is flushed explicitly."""
    f.flush()
    f._h5file.flush()


def write_tile(f: h5netcdf.File, layout: Layout, index: int, attractor, status, t_trap) -> None:
    """Write tile ``index`` (arrays shaped (rows, n_theta0)) and record it done, durably."""
    params, rows = layout.tile(index)
    region = (*params, rows, slice(None))
    f.variables["attractor"][region] = attractor
    f.variables["status"][region] = status
    f.variables["t_trap"][region] = t_trap
    _sync(f)  # data before the record: a crash can lose a tile, never mislabel one
    f.variables["tile_done"][index] = 1
    _sync(f)


def _basin_counts(f: h5netcdf.File, layout: Layout) -> tuple[dict, np.ndarray]:
    """Per parameter point: {k: count} of trapped orbits and the number of orbits not trapped,
    read back tile by tile so memory stays bounded by one tile."""
    counts = [dict() for _ in range(layout.n_params)]
    untrapped = np.zeros(layout.n_params, np.int64)
    for index in range(layout.n_tiles):
        params, rows = layout.tile(index)
        region = (*params, rows, slice(None))
        status = f.variables["status"][region]
        k = f.variables["attractor"][region][status == 0]
        p = index // layout.bands
        for value, count in zip(*np.unique(k, return_counts=True)):
            counts[p][int(value)] = counts[p].get(int(value), 0) + int(count)
        untrapped[p] += int(np.count_nonzero(status != 0))
    return counts, untrapped


def _write_fractions(f: h5netcdf.File, layout: Layout) -> None:
    counts, untrapped = _basin_counts(f, layout)
    ks = sorted(set().union(*counts)) or [0]
    n_orbits = layout.theta0.size * layout.theta_dot0.size
    table = np.array([[c.get(k, 0) for k in ks] for c in counts], np.float64)
    p = table / n_orbits
    lead = () if layout.alpha is None else (layout.alpha.size, layout.omega0.size)
    lead_dims = layout.dims[:-2]
    f.dimensions["k"] = len(ks)
    f.create_variable("k", ("k",), np.int16, data=np.array(ks, np.int16)).attrs.update(
        long_name="attractor index: the rest state (2*pi*k, 0)", units="1")
    for name, values, attrs in [
        ("basin_fraction", p, {"long_name": "fraction of the grid in the basin of k"}),
        ("basin_fraction_stderr", np.sqrt(p * (1 - p) / n_orbits),
         {"long_name": "standard error of basin_fraction, sqrt(p(1-p)/N)"}),
    ]:
        var = f.create_variable(name, (*lead_dims, "k"), np.float64,
                                data=values.reshape(*lead, len(ks)))
        var.attrs.update(units="1", **attrs)
    var = f.create_variable("unresolved_fraction", lead_dims, np.float64,
                            data=(untrapped / n_orbits).reshape(lead))
    var.attrs.update(units="1", long_name="fraction of the grid not certified "
                     "(unresolved or nonfinite)")


#: What :func:`finalize` adds to a file whose tiles are all done.
_SUMMARY = ("basin_fraction", "basin_fraction_stderr", "unresolved_fraction", "k",
            "critical_points", "separatrices")


def finalize(f: h5netcdf.File, path: Path, output: Path, groups: dict[str, xr.Dataset],
             attrs: dict) -> None:
    """Complete the partial file at ``path`` and rename it onto ``output``.

    ``complete`` is set last, just before the rename: a failure on the way (disk full)
    leaves a partial file that ``--resume`` finishes (see :func:`_discard_summary`).
    """
    layout = read_layout(f)
    _write_fractions(f, layout)
    f.attrs.update(attrs)
    f.close()
    for name, ds in groups.items():
        ds.to_netcdf(path, mode="a", group=name, engine="h5netcdf")
    with h5py.File(path, "a") as h:
        h.attrs["complete"] = np.int8(1)
    os.replace(path, output)


def _discard_summary(path: Path) -> None:
    """Remove what an interrupted :func:`finalize` may have added, so it can run again."""
    with h5py.File(path, "a") as h:
        if "basin_fraction" not in h and "critical_points" not in h and "k" not in h:
            return
        for name in _SUMMARY:  # the variables on dim k before k itself
            if name in h:
                del h[name]
        h.attrs["complete"] = np.int8(0)


def open_atlas(path: str | Path, *, chunks=None) -> xr.DataTree:
    """Open an atlas file as a DataTree with the stored dtypes (``attractor`` stays int16 with
    its fill value; plain ``xr.open_dataset`` would mask it to float NaN instead).

    ``chunks={}`` opens lazily with dask (for outputs larger than memory).
    """
    path = Path(path)
    if not _check_atlas_file(path).get("complete", 0):
        raise InputFileError(f"{path}: a partial atlas (an interrupted run); finish it with "
                             "`atlas run CONFIG --resume` first")
    return xr.open_datatree(path, engine="h5netcdf", mask_and_scale=False, chunks=chunks)


def _check_atlas_file(path: Path) -> dict:
    """Attributes of an atlas file, or one clear InputFileError about what is wrong."""
    if not path.exists():
        raise InputFileError(f"{path}: no such file")
    if path.is_dir():
        raise InputFileError(f"{path}: is a directory, not an atlas file")
    try:
        with h5netcdf.File(path, "r") as f:
            attrs = dict(f.attrs)
            has_vars = {"attractor", "status", "t_trap"} <= set(f.variables)
    except (OSError, ValueError) as exc:
        raise InputFileError(f"{path}: not a readable HDF5 file "
                             f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
                             ) from None
    if attrs.get("atlas_schema") != SCHEMA or not has_vars:
        raise InputFileError(f"{path}: an HDF5 file, but not an atlas (no atlas basin map in it)")
    return attrs


def describe(path: str | Path) -> dict:
    """What ``atlas info`` needs without loading the arrays: attrs, completeness, tile counts."""
    path = Path(path)
    attrs = _check_atlas_file(path)
    with h5netcdf.File(path, "r") as f:
        done = f.variables["tile_done"][...]
    return {"attrs": attrs, "complete": bool(attrs.get("complete", 0)),
            "tiles_done": int(done.sum()), "tiles": int(done.size),
            "config": json.loads(attrs["config"]) if "config" in attrs else None}
