"""The atlas file: one HDF5 file in netCDF-4 layout (xarray's ``h5netcdf`` engine).

This is the only module that touches HDF5. A run writes into ``<output>.partial``:

1. :func:`create` pre-creates the chunked, compressed basin-map variables (one chunk per
   tile row band) and a ``tile_done`` record;
2. :func:`write_tile` writes each finished tile by region and marks it done, then flushes,
   so a crash loses at most the tile in flight and ``--resume`` redoes only missing tiles;
3. the sweep certifies each tile (:func:`read_labels`, :func:`write_certificate`);
4. :func:`finalize` adds the summary variables and the small groups (``/critical_points``,
   ``/separatrices``) and renames the file onto the output path, so the output path only ever
   holds a complete file.

Layout (SPEC.md): root dims ``theta_dot0``, ``theta0`` (leading ``alpha``, ``omega0`` for a
parameter atlas); ``attractor`` int16 (``_FillValue`` where not trapped), ``status`` int8
(CF flags), ``t_trap`` float32 [s]; ``boundary_distance`` float32; per basin ``k`` the exact
area fractions and the grid counts with their errors (:data:`BASIN_VARIABLES`); per parameter
point d_cert and the other certificate figures (:data:`POINT_VARIABLES`); provenance
attributes.
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

STATUS_FLAGS = {"flag_values": np.array([0, 1, 2, 3], np.int8),
                "flag_meanings": "trapped unresolved nonfinite near_boundary",
                "comment": "trapped: certified for the exact equation (energy trap of the RK4 "
                           "map, and farther than d_cert from every basin boundary); "
                           "near_boundary: trapped, certified for the RK4 map only"}
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
            "boundary_distance": (np.float32, np.float32(np.nan), {
                "long_name": "Euclidean distance in the (theta, theta_dot) plane to the "
                             "nearest basin boundary",
                "units": "1", "comment": "rad and rad s-1 taken as one unit; boundaries are "
                "the stable manifolds of the saddles integrated by DOP853 (rtol 1e-13)"}),
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


def read_labels(f: h5netcdf.File, layout: Layout, index: int):
    """(attractor, status) of tile ``index``, each shaped (rows, n_theta0)."""
    params, rows = layout.tile(index)
    region = (*params, rows, slice(None))
    return f.variables["attractor"][region], f.variables["status"][region]


def write_certificate(f: h5netcdf.File, layout: Layout, index: int, status,
                      boundary_distance) -> None:
    """Write tile ``index``'s certified status and boundary distances."""
    params, rows = layout.tile(index)
    region = (*params, rows, slice(None))
    f.variables["status"][region] = status
    f.variables["boundary_distance"][region] = boundary_distance


#: Per-basin summary variables (dims: the parameter dims, then ``k``), and their attributes.
BASIN_VARIABLES = {
    "basin_fraction_exact": {
        "long_name": "area fraction of the window in the basin of k",
        "comment": "from the exact basin boundaries (stable manifolds integrated by DOP853, "
                   "rtol 1e-13): integral of the clipped boundary curves over theta"},
    "basin_fraction_exact_error": {
        "long_name": "error estimate of basin_fraction_exact",
        "comment": "change of the result from rtol 1e-12 to 1e-13 (about 10x the error)"},
    "basin_fraction": {
        "long_name": "fraction of the grid points labelled k (a count, not an area)"},
    "basin_fraction_grid_error_bound": {
        "long_name": "bound on |basin_fraction - basin_fraction_exact|",
        "comment": "from the grid cells: a certified cell farther than its half-diagonal "
                   "from every boundary counts |1/N - a/A|, every other cell max(1/N, a/A) "
                   "in each basin it may meet; first order in the cell size"},
    "basin_fraction_grid_error": {
        "long_name": "measured |basin_fraction - basin_fraction_exact|"},
}
#: Per-parameter-point summary variables and their attributes.
POINT_VARIABLES = {
    "unresolved_fraction": {"long_name": "fraction of the grid without a well label "
                                         "(unresolved or nonfinite)"},
    "certified_fraction": {"long_name": "fraction of the grid whose label is certified for "
                                        "the exact equation (status trapped)"},
    "d_cert": {"long_name": "distance to the basin boundaries beyond which RK4 labels are "
                            "certified for the exact equation",
               "comment": "10 x (boundary shift + bisection tol + reference error); NaN: "
                          "not measured (separatrices disabled), no label certified"},
    "boundary_shift": {"long_name": "largest distance of the RK4 map's basin boundary "
                                    "(bisected) from the exact one"},
    "boundary_reference_error": {"long_name": "error estimate of the DOP853 basin "
                                              "boundaries (change from rtol 1e-12 to 1e-13)"},
    "trap_margin": {"long_name": "relative safety margin m of the energy trap"},
    "side_mismatches": {"long_name": "labels farther than d_cert from every boundary whose "
                                     "RK4 label differs from the exact side (expected 0)"},
}


def _write_summary(f: h5netcdf.File, layout: Layout, points: list[dict]) -> None:
    """The summary of every parameter point (in the order of ``layout``'s points): per-basin
    variables over ``k`` (the union of every point's basins, 0 where a basin is absent) and
    per-point scalars, both with the parameter dims leading."""
    ks = sorted({int(k) for p in points for k in p["k"]}) or [0]
    lead = () if layout.alpha is None else (layout.alpha.size, layout.omega0.size)
    lead_dims = layout.dims[:-2]
    f.dimensions["k"] = len(ks)
    f.create_variable("k", ("k",), np.int16, data=np.array(ks, np.int16)).attrs.update(
        long_name="attractor index: the rest state (2*pi*k, 0)", units="1")
    for name, attrs in BASIN_VARIABLES.items():
        table = np.zeros((len(points), len(ks)))
        for row, p in zip(table, points):
            row[np.searchsorted(ks, p["k"])] = p[name]
        var = f.create_variable(name, (*lead_dims, "k"), np.float64,
                                data=table.reshape(*lead, len(ks)))
        var.attrs.update(units="1", **attrs)
    for name, attrs in POINT_VARIABLES.items():
        values = np.array([p[name] for p in points], np.float64).reshape(lead)
        var = f.create_variable(name, lead_dims, np.float64, data=values)
        var.attrs.update(units="1", **attrs)


#: What :func:`finalize` adds to a file whose tiles are all done.
_SUMMARY = (*BASIN_VARIABLES, *POINT_VARIABLES, "k", "critical_points", "separatrices")


def finalize(f: h5netcdf.File, path: Path, output: Path, points: list[dict],
             groups: dict[str, xr.Dataset], attrs: dict) -> None:
    """Complete the partial file at ``path`` with the summary of every parameter point
    (:func:`_write_summary`), the groups and attributes, and rename it onto ``output``.

    ``complete`` is set last, just before the rename: a failure on the way (disk full)
    leaves a partial file that ``--resume`` finishes (see :func:`_discard_summary`).
    """
    _write_summary(f, read_layout(f), points)
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
        if not any(name in h for name in _SUMMARY):
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
