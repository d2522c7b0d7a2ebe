"""The atlas file: one HDF5 file in netCDF-4 layout (xarray's ``h5netcdf`` engine).

This is the only module that touches HDF5. A run keeps its finished tiles in
``<output>.partial/`` (:mod:`atlas.store.partial`, one atomically written file per tile); when every
tile is done, :func:`finalize` assembles the file:

1. the basin-map variables are created chunked and compressed, one chunk per tile, and each
   tile's chunks are copied in as stored (no decoding, memory bounded by one tile);
2. the summary is added in one place (:func:`_write_summary`): the root variables passed in
   (basin fractions and certificate figures, :func:`summary_dataset`, made from the tiles'
   tallies), then the groups (``/critical_points``, ``/separatrices``, …), then the
   attributes and ``complete = 1``;
3. the file (built inside the partial folder) is fsynced and renamed onto the output, the
   folder fsynced, and only then is the partial folder removed. The output path therefore only
   ever holds a complete file, and an interruption anywhere leaves the tiles to finish from.

Layout: root dims ``theta_dot0``, ``theta0`` (leading ``alpha``, ``omega0`` for a
parameter atlas); ``attractor`` int16 (``_FillValue`` where not trapped), ``status`` int8
(CF flags), ``t_trap`` float32 [s], ``boundary_distance`` float32; per basin ``k`` the exact
area fractions and the grid counts with their errors (:data:`BASIN_VARIABLES`); per parameter
point d_cert and the other certificate figures (:data:`POINT_VARIABLES`); provenance
attributes.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import zipfile
import zlib
from pathlib import Path

import h5netcdf
import h5py
import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import InputFileError
from atlas.kernels import ATTRACTOR_FILL
from atlas.layout import Layout
from atlas.store.partial import (
    DEFLATE_LEVEL,
    MANIFEST,
    PartialStoreError,
    TileStore,
    decode_chunk,
    fsync,
    partial_path,
)

__all__ = ["finalize", "StoredRows", "open_atlas", "partial_path", "describe", "FILLS",
           "DamagedTile", "summary_dataset"]

STATUS_FLAGS = {"flag_values": np.array([0, 1, 2, 3, 4, 5], np.int8),
                "flag_meanings": "trapped unresolved nonfinite near_boundary running "
                                 "running_near_boundary",
                "comment": "trapped: certified for the exact equation (energy trap of the RK4 "
                           "map, and farther than d_cert from every basin boundary); "
                           "near_boundary: trapped, certified for the RK4 map only; running "
                           "(torque): in the running barrier of the RK4 map and farther than "
                           "d_cert from every basin boundary, certified for the exact equation "
                           "to converge to the running limit cycle; running_near_boundary: "
                           "running, certified for the RK4 map only"}
_COMPRESSION = {"compression": "gzip", "compression_opts": DEFLATE_LEVEL, "shuffle": True}
SCHEMA = "atlas-basin-map/1"
#: Fill values of the label variables (also the padding of a tile's edge chunk).
FILLS = {"attractor": ATTRACTOR_FILL, "status": np.int8(0), "t_trap": np.float32(np.nan),
         "boundary_distance": np.float32(np.nan)}
_SPECS = {
    "attractor": (np.int16, ATTRACTOR_FILL, {
        "long_name": "index k of the attractor (2*pi*k, 0) reached",
        "units": "1", "comment": "fill value where status != trapped"}),
    "status": (np.int8, None, {"long_name": "labelling status", "units": "1",
                               **STATUS_FLAGS}),
    "t_trap": (np.float32, np.float32(np.nan), {
        "long_name": "time at which the orbit was certified trapped", "units": "s"}),
    "boundary_distance": (np.float32, np.float32(np.nan), {
        "long_name": "Euclidean distance in the (theta, theta_dot) plane to the nearest basin "
                     "boundary",
        "units": "1", "comment": "rad and rad s-1 taken as one unit; boundaries are the stable "
        "manifolds of the saddles integrated by DOP853 (rtol 1e-13)"}),
}


@contextlib.contextmanager
def _netcdf(path: Path, mode: str):
    """``h5netcdf.File`` that, if anything fails inside or while closing (a full disk), is
    closed without another flush: h5netcdf would otherwise flush the broken file again when it
    is garbage collected, and HDF5 can crash the process doing so."""
    f = h5netcdf.File(path, mode)
    try:
        yield f
        f.close()
    except BaseException:
        h5 = f._h5file
        f._closed = True
        with contextlib.suppress(Exception):
            h5.close()
        raise


class DamagedTile(Exception):
    """A tile file that cannot be read back (its index in ``index``)."""

    def __init__(self, index: int, reason: str):
        super().__init__(f"tile {index}: {reason}")
        self.index = index


def chunks_of(layout: Layout) -> tuple[int, ...]:
    """One chunk per tile."""
    return (*(1 for _ in layout.swept), layout.chunk_rows, layout.theta0.size)


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
    "running_fraction": {"long_name": "fraction of the grid labelled running (a count, not "
                                      "an area)"},
    "running_fraction_exact": {"long_name": "area fraction of the window in the running "
                                            "basin, from the exact basin boundaries"},
    "running_fraction_exact_error": {"long_name": "error estimate of "
                                                  "running_fraction_exact"},
    "running_fraction_grid_error_bound": {"long_name": "bound on |running_fraction - "
                                                       "running_fraction_exact|"},
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


def summary_dataset(layout: Layout, points: list[dict]) -> xr.Dataset:
    """The summary of every parameter point (``points`` in the order of ``layout``'s points,
    each a dict of :data:`BASIN_VARIABLES` over its own ``k`` and :data:`POINT_VARIABLES`):
    per-basin variables over ``k`` (the union of every point's basins, 0 where a basin is
    absent) and per-point scalars, both with the parameter dims leading."""
    ks = sorted({int(k) for p in points for k in p["k"]}) or [0]
    lead, lead_dims = layout.parameter_shape, layout.swept
    data = {}
    for name, attrs in BASIN_VARIABLES.items():
        table = np.zeros((len(points), len(ks)))
        for row, p in zip(table, points):
            values = np.asarray(p[name], float)
            if values.size and np.isnan(values).all():
                row[:] = np.nan  # not computed for this point (no exact boundaries)
            row[np.searchsorted(ks, p["k"])] = values
        data[name] = ((*lead_dims, "k"), table.reshape(*lead, len(ks)), {"units": "1", **attrs})
    for name, attrs in POINT_VARIABLES.items():
        values = np.array([p[name] for p in points], np.float64).reshape(lead)
        data[name] = (lead_dims, values, {"units": "1", **attrs})
    return xr.Dataset(data, coords={"k": ("k", np.array(ks, np.int16), {
        "long_name": "attractor index: the rest state (2*pi*k, 0)", "units": "1"})})


def summary_tree(layout: Layout, root_vars: xr.Dataset, groups: dict[str, xr.Dataset],
                 attrs: dict) -> xr.DataTree:
    """What :func:`finalize` writes beyond the basin map, as an in-memory DataTree: the
    grid's and parameters' coordinates, the summary's root variables, the root attributes
    ``attrs`` and the ``groups`` (path → dataset). ``atlas run`` prints its summary from
    this instead of reading the file back (0.1 s of HDF5 metadata on the default grid)."""
    root = root_vars.assign_coords(layout.coords()).assign_attrs(
        {key: value for key, value in attrs.items() if value is not None})
    return xr.DataTree.from_dict({"/": root, **groups})


def _create_map(f: h5netcdf.File, layout: Layout) -> None:
    """Coordinates and the empty, chunked basin-map variables (one chunk per tile). The
    parameters that are not swept are scalar coordinates, named in each variable's CF
    ``coordinates`` attribute."""
    coords = layout.coords()
    f.dimensions = {dims[0]: np.size(values) for dims, values, _ in coords.values() if dims}
    for name, (dims, values, attrs) in coords.items():
        var = f.create_variable(name, dims, np.float64, data=values)
        var.attrs.update(attrs)
    chunks = chunks_of(layout)
    for name, (dtype, fill, var_attrs) in _SPECS.items():
        var = f.create_variable(name, layout.dims, dtype, fillvalue=fill, chunks=chunks,
                                **_COMPRESSION)
        var.attrs.update(var_attrs)
        _name_scalar_coords(var, layout)


def _name_scalar_coords(var, layout: Layout) -> None:
    """CF: list the scalar coordinates (the parameters not swept) on a root variable."""
    scalars = [name for name, (dims, _, _) in layout.coords().items() if not dims]
    if scalars:
        var.attrs["coordinates"] = " ".join(scalars)


def _copy_tiles(f: h5netcdf.File, tiles: TileStore) -> None:
    """Copy every tile's stored chunks into the file."""
    layout = tiles.layout
    datasets = {name: f._h5group[name] for name in _SPECS}
    for index in range(layout.n_tiles):
        try:
            tile = tiles.read_tile(index)
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
            raise DamagedTile(index, exc.__class__.__name__) from None
        params, rows = layout.tile(index)
        offset = (*params, rows.start, 0)
        for name, dset in datasets.items():
            dset.id.write_direct_chunk(offset, tile.chunks[name], 0)


def _write_root_vars(f: h5netcdf.File, ds: xr.Dataset, layout: Layout) -> None:
    """Further root variables (on the file's dims, or new ones), with their attributes."""
    for name, size in ds.sizes.items():
        if name not in f.dimensions:
            f.dimensions[name] = size
    for name, var in {**ds.coords, **ds.data_vars}.items():
        if name in f.variables:
            continue
        attrs = dict(var.attrs)
        fill = attrs.pop("_FillValue", var.encoding.get("_FillValue"))
        new = f.create_variable(name, var.dims, var.dtype, data=var.values, fillvalue=fill)
        new.attrs.update(attrs)
        if name in ds.data_vars:
            _name_scalar_coords(new, layout)


def _write_summary(path: Path, layout: Layout, groups: dict[str, xr.Dataset],
                   root_vars: xr.Dataset, attrs: dict) -> None:
    """Everything a finished file has beyond the basin map, in one place: the root variables
    of the summary, the groups, the attributes; ``complete`` last. Written by a forked child
    (:func:`_in_child`)."""
    def write():
        with _netcdf(path, "a") as f:
            _write_root_vars(f, root_vars, layout)
            f.attrs.update({key: value for key, value in attrs.items() if value is not None})
            for path_in_file, ds in groups.items():  # xarray's encoding, into this handle
                ds.dump_to_store(xr.backends.H5NetCDFStore(_group(f, path_in_file), mode="a"))
            f.attrs["complete"] = np.int8(1)

    _in_child(write)


def _group(f: h5netcdf.File, path: str):
    """The group at ``path`` ("a/b"), made with its parents where missing."""
    group = f
    for part in path.split("/"):
        group = group.groups[part] if part in group.groups else group.create_group(part)
    return group


def _in_child(work) -> None:
    """Run ``work`` (HDF5 writes) in a forked child that leaves by ``os._exit``. After a write
    fails (a full disk), HDF5 retries the failed flush whenever one of the file's objects is
    collected and at exit, and crashes the process doing so (SIGSEGV); the child is never torn
    down, so that cannot happen, and this process raises an OSError with the system's errno."""
    if not hasattr(os, "fork"):  # no fork (Windows): write in this process
        work()
        return
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        code = 0
        try:
            os.close(read)
            null = os.open(os.devnull, os.O_WRONLY)  # HDF5's complaints after a failed
            os.dup2(null, 2)  # write: the reason goes through the pipe
            work()
        except BaseException as exc:
            code = 1
            text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            number = getattr(exc, "errno", None)
            found = re.search(r"errno = (\d+)", str(exc))
            number = number or (int(found.group(1)) if found else 0)
            with contextlib.suppress(Exception):
                os.write(write, f"{number} {type(exc).__name__}: {text}".encode()[:4000])
        finally:
            os._exit(code)
    os.close(write)
    with os.fdopen(read, "rb") as pipe:
        message = pipe.read().decode(errors="replace")
    _, status = os.waitpid(pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        number, _, text = message.partition(" ")
        raise OSError(int(number) if number.isdigit() and int(number) else errno.EIO,
                      text or f"the writer ended with status {status}")


def finalize(tiles: TileStore, output: Path, groups: dict[str, xr.Dataset],
             root_vars: xr.Dataset, attrs: dict) -> None:
    """Assemble the finished tiles of ``tiles`` into the atlas file ``output``; then remove
    the partial folder.

    ``groups`` become HDF5 groups (``/critical_points``, …), ``root_vars`` the summary's
    root variables next to the basin map (:func:`summary_dataset`), ``attrs`` the root
    attributes (with the partial run's own: provenance, config). The file is built inside the
    partial folder, fsynced and renamed onto ``output``: an interruption or a full disk at any
    point leaves the output as it was and the tiles in place (run again to finish). Raises
    :class:`DamagedTile` for a tile file that cannot be read back.
    """
    layout = tiles.layout
    path = tiles.path / "assembly.h5"
    path.unlink(missing_ok=True)
    with _netcdf(path, "w") as f:
        _create_map(f, layout)
        f.attrs.update(tiles.manifest["attrs"])
        f.attrs["atlas_schema"] = SCHEMA
        f.attrs["complete"] = np.int8(0)
        _copy_tiles(f, tiles)
    _write_summary(path, layout, groups, root_vars, attrs)
    fsync(path)
    os.replace(path, output)
    fsync(output.parent)
    tiles.remove()


class StoredRows:
    """Rows of a map of an atlas file, read as stored chunks and decoded in this process
    (:func:`atlas.store.partial.decode_chunk`, the inverse of the encoding the tiles were stored
    with). HDF5 inflates under its global lock, one chunk at a time; zlib and numpy's copies
    release the GIL, so the bands of a map are decoded on every core. Only for a variable
    filtered by deflate (after shuffle) alone, chunked by whole rows of one parameter point,
    and read lazily from the file whose coordinates the dataset has (:meth:`of` returns None
    otherwise); anything unexpected (a chunk stored unfiltered, one that does not inflate to
    its size) makes :meth:`read` return None, and the caller reads the band through xarray,
    which reports a damaged chunk as it always has."""

    def __init__(self, file, dset, lead: tuple[int, ...], shuffle: bool):
        self.file, self.dset, self.lead, self.shuffle = file, dset, lead, shuffle
        self.rows, self.cols = dset.chunks[-2], dset.shape[-1]
        self.dtype = dset.dtype

    @classmethod
    def of(cls, ds: xr.Dataset, name: str, point: dict[str, int]) -> StoredRows | None:
        da = ds[name]
        source = da.encoding.get("source")
        if (not source or da.chunks is not None or getattr(da.variable, "_in_memory", True)
                or da.dims[-2:] != ("theta_dot0", "theta0")
                or any(key in da.encoding for key in ("scale_factor", "add_offset"))):
            return None
        try:
            file = h5py.File(source, "r")
        except (OSError, ValueError):
            return None
        try:
            dset = file.get(name)
            if cls._same(file, dset, ds, da):
                plist = dset.id.get_create_plist()
                filters = [plist.get_filter(i)[0] for i in range(plist.get_nfilters())]
                if filters in ([h5py.h5z.FILTER_DEFLATE],
                               [h5py.h5z.FILTER_SHUFFLE, h5py.h5z.FILTER_DEFLATE]):
                    return cls(file, dset, tuple(point[d] for d in da.dims[:-2]),
                               filters[0] == h5py.h5z.FILTER_SHUFFLE)
        except (OSError, ValueError, KeyError, TypeError):
            pass
        file.close()
        return None

    @staticmethod
    def _same(file, dset, ds: xr.Dataset, da: xr.DataArray) -> bool:
        """Whether ``dset`` holds ``da`` (same shape, type and coordinates), chunked by whole
        rows of one parameter point."""
        if not isinstance(dset, h5py.Dataset) or dset.chunks is None:
            return False
        if dset.shape != da.shape or dset.dtype != da.dtype:
            return False
        if any(c != 1 for c in dset.chunks[:-2]) or dset.chunks[-1] != dset.shape[-1]:
            return False
        for dim in da.dims:
            stored = file.get(dim)
            if not isinstance(stored, h5py.Dataset) or stored.shape != (ds.sizes[dim],):
                return False
            if not np.array_equal(stored[()], ds[dim].values):
                return False
        return True

    def read(self, r0: int, r1: int) -> np.ndarray | None:
        """Rows [r0, r1), or None if a chunk is not as expected."""
        out = np.empty((r1 - r0, self.cols), self.dtype)
        try:
            for c0 in range(r0 - r0 % self.rows, r1, self.rows):
                mask, raw = self.dset.id.read_direct_chunk((*self.lead, c0, 0))
                if mask:
                    return None
                self._inflate(raw, c0, r0, out)
        except (OSError, ValueError, KeyError, RuntimeError, zlib.error):
            return None
        return out

    def _inflate(self, raw: bytes, c0: int, r0: int, out: np.ndarray) -> None:
        """Decode the chunk of rows [c0, c0 + rows) into ``out``, the rows [r0, …)."""
        chunk = decode_chunk(raw, self.rows, self.cols, self.dtype, self.shuffle)
        lo, hi = max(c0, r0), min(c0 + self.rows, r0 + out.shape[0])
        out[lo - r0:hi - r0] = chunk[lo - c0:hi - c0]


def open_atlas(path: str | Path, *, chunks=None) -> xr.DataTree:
    """Open an atlas file as a DataTree with the stored dtypes (``attractor`` stays int16 with
    its fill value; plain ``xr.open_dataset`` would mask it to float NaN instead).

    The file is checked before it is returned (:mod:`atlas.store.validate`: format version, the basin
    map's variables, dtypes, dims and coordinates, the status flags, the summary, the stored
    config): a file that fails raises :class:`InputFileError` with one line saying what is
    wrong. ``chunks={}`` opens lazily with dask (for outputs larger than memory).
    """
    from atlas.store.validate import check_tree

    path = Path(path)
    if not _complete(_check_atlas_file(path)):
        raise InputFileError(f"{path}: a partial atlas (an interrupted run); finish it by "
                             "running `atlas run CONFIG` again first")
    try:
        if path.is_dir():
            from atlas.store import zarrformat as zarrstore

            tree = zarrstore.open_tree(path, chunks)
        else:
            tree = xr.open_datatree(path, engine="h5netcdf", mask_and_scale=False,
                                    chunks=chunks)
    except InputFileError:
        raise
    except Exception as exc:  # a damaged file fails in h5py, h5netcdf, zarr or xarray
        raise InputFileError(f"{path}: not a readable atlas file ({_first_line(exc)})") from None
    try:
        check_tree(tree, path)
    except BaseException:
        tree.close()
        raise
    return tree


def _complete(attrs: dict) -> bool:
    flag = np.asarray(attrs.get("complete", 0))
    return flag.size == 1 and flag.dtype.kind in "iub" and bool(flag.reshape(()))


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0][:200] if text else exc.__class__.__name__


def _check_atlas_file(path: Path) -> dict:
    """Attributes of an atlas file, or one clear InputFileError about what is wrong."""
    if not path.exists():
        raise InputFileError(f"{path}: no such file")
    if path.is_dir():
        if (path / MANIFEST).exists():
            raise InputFileError(f"{path}: a partial atlas (an interrupted run); finish it by "
                                 "running `atlas run CONFIG` again first")
        if not (path / "zarr.json").exists():
            raise InputFileError(f"{path}: is a directory, not an atlas file")
        from atlas.store import zarrformat as zarrstore

        attrs = zarrstore.attrs_of(path)
        if attrs.get("atlas_schema") != SCHEMA:
            raise InputFileError(f"{path}: a Zarr store, but not an atlas")
        return attrs
    try:  # h5py, not h5netcdf: a half-made h5netcdf.File complains again when collected
        with h5py.File(path, "r") as f:
            attrs = {name: _plain_attr(value) for name, value in f.attrs.items()
                     if not name.startswith("_")}
            has_vars = all(isinstance(f.get(name), h5py.Dataset)
                           for name in ("attractor", "status", "t_trap"))
    except Exception as exc:  # OSError for most damage; h5py raises others too
        raise InputFileError(f"{path}: not a readable HDF5 file ({_first_line(exc)})") from None
    if attrs.get("atlas_schema") != SCHEMA or not has_vars:
        raise InputFileError(f"{path}: an HDF5 file, but not an atlas (no atlas basin map in it)")
    return attrs


def _plain_attr(value):
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:  # as h5netcdf reads it
        return _plain_attr(value.reshape(())[()])
    return value


def is_atlas_file(path: str | Path) -> bool:
    """True if ``path`` is recognisably a file atlas wrote (an atlas file, complete or not,
    damaged or not, as long as its attributes say so): one a run may write over."""
    try:
        return _check_atlas_file(Path(path)).get("atlas_schema") == SCHEMA
    except InputFileError:
        return False


def describe(path: str | Path) -> dict:
    """What ``atlas info`` needs without loading the arrays: attrs, completeness, and for a
    partial run (its ``.partial`` folder) how many tiles are done."""
    path = Path(path)
    if path.is_dir() and (path / MANIFEST).exists():
        try:
            tiles = TileStore.read(path)
        except PartialStoreError as exc:
            raise InputFileError(f"{path}: a partial run that cannot be read ({exc})") from None
        attrs = tiles.manifest["attrs"]
        if not isinstance(attrs, dict):
            raise InputFileError(f"{path}: a partial run that cannot be read (its manifest "
                                 "has no attributes)")
        return {"attrs": attrs, "complete": False, "tiles_done": int(tiles.done().size),
                "tiles": tiles.layout.n_tiles, "config": _config(attrs, path)}
    attrs = _check_atlas_file(path)
    return {"attrs": attrs, "complete": _complete(attrs), "tiles_done": None,
            "tiles": None, "config": _config(attrs, path)}


def _config(attrs: dict, path="atlas file"):
    """The stored config as a dict (None if absent); InputFileError if it is not JSON."""
    from atlas.store.validate import parse_config

    return parse_config(attrs, path)
