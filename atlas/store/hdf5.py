"""The HDF5 format: one file in netCDF-4 layout (xarray's ``h5netcdf`` engine), the default.

The only code that touches HDF5 (h5py, h5netcdf), as :mod:`atlas.store.zarrformat` is for
Zarr. A tile of a partial run is kept as its map variables encoded exactly as HDF5 stores
them (:func:`encode_chunk`: byte shuffle, then deflate level :data:`DEFLATE_LEVEL`, the edge
chunk padded), so :meth:`HDF5Tiles.finalize` assembles the file without re-encoding:

1. the basin-map variables are created chunked and compressed, one chunk per tile, and each
   tile's chunks are copied in as stored (memory bounded by one tile);
2. the summary is added in one place (:func:`_write_summary`): the root variables, then the
   groups (``/critical_points``, ``/separatrices``, …: xarray's encoding, written with h5py
   in netCDF-4's layout by :class:`_GroupStore`), then the attributes and ``complete = 1``;
3. the file (built inside the partial folder) is fsynced and renamed onto the output, the
   folder fsynced, and only then is the partial folder removed.

:class:`StoredRows` reads a finished file's chunks back the same way, decoded on every core.
"""

from __future__ import annotations

import contextlib
import errno
import gc
import os
import re
import sys
import zlib
from pathlib import Path

import h5netcdf
import h5py
import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import InputFileError
from atlas.layout import Layout
from atlas.models.base import LABELS
from atlas.models.registry import of_attrs
from atlas.store.durable import fsync
from atlas.store.format import Container, TileRun, reason
from atlas.store.schema import (
    SCHEMA,
    chunks_of,
    map_variables,
    not_an_atlas,
)

__all__ = ["HDF5", "HDF5Tiles", "StoredRows", "encode_chunk", "decode_chunk", "DEFLATE_LEVEL",
           "root_attrs"]

#: zlib level of the map's chunks (HDF5's gzip filter, after its byte shuffle).
DEFLATE_LEVEL = 4
_COMPRESSION = {"compression": "gzip", "compression_opts": DEFLATE_LEVEL, "shuffle": True}
#: The HDF5 format signature, at offset 0 or, after a user block, 512, 1024, 2048, …
_SIGNATURE = b"\x89HDF\r\n\x1a\n"


class HDF5Tiles(TileRun):
    """A sweep's tiles into one HDF5 file: each tile's chunks encoded as HDF5 stores them,
    kept with its record, copied into the file at the end (module docstring)."""

    name = "hdf5"

    def write_tile(self, folder: Path, layout: Layout, index: int,
                   values: dict) -> dict[str, bytes]:
        rows = layout.chunk_rows
        return {name: encode_chunk(values[name], rows, var.padding)
                for name, var in map_variables(layout).items()}

    def finalize(self, tiles, output: Path, groups: dict[str, xr.Dataset],
                 root_vars: xr.Dataset, attrs: dict) -> None:
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


class HDF5(Container):
    name = "hdf5"
    kind = "an HDF5 file"
    description = "one HDF5 file in netCDF-4 layout (xarray's h5netcdf engine)"
    suffixes = (".h5", ".hdf5", ".he5", ".nc")
    tile_run = HDF5Tiles()

    def recognises(self, path: Path) -> bool:
        try:
            with open(path, "rb") as fh:
                offset = 0
                while True:
                    fh.seek(offset)
                    head = fh.read(len(_SIGNATURE))
                    if head == _SIGNATURE:
                        return True
                    if len(head) < len(_SIGNATURE):
                        return False
                    offset = max(512, 2 * offset)
        except OSError:  # absent, a directory, unreadable
            return False

    def root_attrs(self, path: Path) -> dict:
        return root_attrs(path)[0]

    def open_dataset(self, path: Path) -> xr.Dataset:
        def load():
            with xr.open_dataset(path, engine="h5netcdf", mask_and_scale=False) as f:
                return f.load()

        return _without_close_noise(load)

    def write_dataset(self, ds: xr.Dataset, path: Path) -> None:
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            ds.to_netcdf(tmp, engine="h5netcdf")
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def attrs(self, path: Path) -> dict:
        if path.is_dir():
            raise InputFileError(f"{path}: is a directory, not an atlas file")
        attrs, has_map = root_attrs(path)
        if attrs.get("atlas_schema") != SCHEMA or not has_map:
            raise InputFileError(not_an_atlas(
                path, attrs, self.kind, " (no atlas basin map in it)",
                "xr.open_dataset('{path}', engine='h5netcdf')"))
        return attrs

    def open(self, path: Path, chunks=None) -> xr.DataTree:
        return _without_close_noise(lambda: xr.open_datatree(
            path, engine="h5netcdf", mask_and_scale=False, chunks=chunks))

    def stored_rows(self, ds: xr.Dataset, name: str, point: dict[str, int]):
        return StoredRows.of(ds, name, point)


# ------------------------------------------------------------------- the chunk encoding

def _without_close_noise(opener):
    """``opener()``, whose error on a damaged file comes out alone: an h5netcdf File whose
    constructor failed is closed by its ``__del__``, which raises AttributeError (no
    ``_writable``) and prints "Exception ignored in" with a traceback on stderr, under the
    one line atlas says. The error's tracebacks (which hold that File) are dropped here and
    the File collected while that noise of a File that never opened is not printed."""
    hook = sys.unraisablehook

    def quiet(unraisable):
        if not (isinstance(unraisable.exc_value, AttributeError)
                and getattr(unraisable.object, "__module__", "").startswith("h5netcdf")):
            hook(unraisable)

    sys.unraisablehook = quiet
    try:
        try:
            return opener()
        except Exception as exc:
            error = exc
        seen = error
        while seen is not None:  # the chain's tracebacks hold the half-built File
            seen.__traceback__ = None
            seen = seen.__context__
        gc.collect()
    finally:
        sys.unraisablehook = hook
    raise error


def root_attrs(path: Path) -> tuple[dict, bool]:
    """(the root attributes of the HDF5 file at ``path``, whether it holds an atlas basin
    map); InputFileError in one line if it is not a readable HDF5 file."""
    try:  # h5py, not h5netcdf: a half-made h5netcdf.File complains again when collected
        with h5py.File(path, "r") as f:
            attrs = {name: _plain_attr(value) for name, value in f.attrs.items()
                     if not name.startswith("_")}
            has_map = all(isinstance(f.get(name), h5py.Dataset) for name in LABELS)
    except Exception as exc:  # OSError for most damage; h5py raises others too
        raise InputFileError(f"{path}: not a readable HDF5 file ({reason(exc)})") from None
    return attrs, has_map


def encode_chunk(values: np.ndarray, chunk_rows: int, fill) -> bytes:
    """One HDF5 chunk of ``values`` (rows × columns) exactly as HDF5's shuffle + deflate filter
    pipeline stores it: padded with ``fill`` to ``chunk_rows`` rows (an edge chunk is stored
    whole), bytes shuffled (byte j of every element together; a no-op for 1-byte types), then
    zlib-compressed (HDF5's deflate filter writes zlib streams)."""
    values = np.ascontiguousarray(values)
    if values.shape[0] < chunk_rows:
        pad = np.full((chunk_rows - values.shape[0], values.shape[1]), fill, values.dtype)
        values = np.concatenate([values, pad])
    raw = values.view(np.uint8).reshape(-1, values.dtype.itemsize).T
    return zlib.compress(np.ascontiguousarray(raw).tobytes(), DEFLATE_LEVEL)


def decode_chunk(raw: bytes, chunk_rows: int, cols: int, dtype, shuffle: bool = True
                 ) -> np.ndarray:
    """The inverse of :func:`encode_chunk`: a stored chunk (deflated, after HDF5's byte
    shuffle when ``shuffle``) as its ``chunk_rows`` × ``cols`` array of ``dtype``; ValueError
    if it does not inflate to that size (zlib.error if it does not inflate at all)."""
    dtype = np.dtype(dtype)
    data = np.frombuffer(zlib.decompress(raw), np.uint8)
    if data.size != chunk_rows * cols * dtype.itemsize:
        raise ValueError("a chunk of the wrong size")
    if shuffle:  # byte j of every element was stored together
        data = np.ascontiguousarray(data.reshape(dtype.itemsize, -1).T)
    return data.view(dtype).reshape(chunk_rows, cols)


# ------------------------------------------------------------------- assembling the file

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
    for name, spec in map_variables(layout).items():
        var = f.create_variable(name, layout.dims, spec.dtype, fillvalue=spec.fill,
                                chunks=chunks, **_COMPRESSION)
        var.attrs.update(spec.attrs)
        _name_scalar_coords(var, layout)


def _name_scalar_coords(var, layout: Layout) -> None:
    """CF: list the scalar coordinates (the parameters not swept) on a root variable."""
    scalars = [name for name, (dims, _, _) in layout.coords().items() if not dims]
    if scalars:
        var.attrs["coordinates"] = " ".join(scalars)


def _copy_tiles(f: h5netcdf.File, tiles) -> None:
    """Copy every tile's stored chunks into the file (a damaged tile file raises
    :class:`~atlas.store.partial.DamagedTile` from ``tiles.read_tile``)."""
    layout = tiles.layout
    datasets = {name: f._h5group[name] for name in map_variables(layout)}
    for index in range(layout.n_tiles):
        tile = tiles.read_tile(index)
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
    of the summary, the groups (xarray's encoding, written by :class:`_GroupStore`), the
    attributes; ``complete`` last. Written by a forked child (:func:`_in_child`)."""
    def write():
        with _netcdf(path, "a") as f:
            _write_root_vars(f, root_vars, layout)
            f.attrs.update({key: value for key, value in attrs.items() if value is not None})
            stores = _stores(groups)
            for path_in_file, ds in groups.items():
                ds.dump_to_store(stores[path_in_file](_group(f, path_in_file), mode="a"))
            f.attrs["complete"] = np.int8(1)

    _in_child(write)


#: netCDF-4's NAME of a dimension scale that is no variable: netCDF-C's text, then the length
#: in 10 characters (NetCDF-4 format specification, "Dimensions": dimension scales).
_NOT_A_VARIABLE = b"This is a netCDF dimension but not a netCDF variable.%10d"
#: Encodings that leave no mark in the file (xarray drops them too); any other one asks for
#: storage (chunks, filters, a type) that only h5netcdf's path makes.
_NO_STORAGE = frozenset({"source", "original_shape"})
#: Attribute names that netCDF-4's layout uses itself (h5netcdf's list: it refuses them).
_RESERVED = h5netcdf.attrs._HIDDEN_ATTRS


class _GroupStore(xr.backends.H5NetCDFStore):
    """xarray's store for one new, empty group of an h5netcdf file: xarray's CF encoding (a
    NaN ``_FillValue`` on floats, text as variable-length UTF-8, the non-dimension coordinates
    named in ``coordinates``), then the group written with h5py, each object opened once, in
    netCDF-4's layout (Unidata, netCDF-C documentation, "File Format Specifications": the
    NetCDF-4 format and its dimension scales):

    * a dimension is an HDF5 dimension scale: the variable of its name if it has one (its
      coordinate), else a float32 dataset never written whose NAME says it is no variable
      (:data:`_NOT_A_VARIABLE`); ``_Netcdf4Dimid`` numbers it, on from h5netcdf's count
      for the file (``File._max_dim_id``, which this keeps current). A dimension that an
      enclosing group has at the same length is that one, as xarray decides;
    * a variable is a contiguous dataset, the scales of its dimensions attached
      (DIMENSION_LIST, REFERENCE_LIST), with ``_Netcdf4Coordinates`` (its dimensions'
      numbers), ``_Netcdf4Dimid`` (its first dimension's) and its ``_FillValue`` as its HDF5
      fill value and as an attribute;
    * a non-string scalar attribute is stored as a one-element array, as netCDF-C does;
      datasets keep their attributes in creation order where their group tracks its own so
      (h5netcdf's ``track_order``, on in every file it creates with h5py ≥ 3.7).

    These are the objects and attributes, in the same order, that h5netcdf's
    ``create_variable`` makes (tests/store/test_hdf5.py compares the two files object by
    object), without its bookkeeping: h5netcdf opens each dimension scale and dataset again
    by its path from the file's root whenever it needs it, some 35 times a variable, which
    made the summary of a sweep (hundreds of small variables) take seconds. A group this does
    not cover (:func:`_covers`) is written through h5netcdf, as before; so is a group that
    encloses other groups of the summary (:func:`_stores`): h5netcdf does not see
    what this writes, and an inner group written through it would not find the enclosing
    group's dimensions and would make its own (the per-point groups enclose none)."""

    def store(self, variables, attributes, check_encoding_set=frozenset(), writer=None,
              unlimited_dims=None):
        encoded, attrs = self.encode(variables, attributes)
        group = self.ds._h5group
        if (check_encoding_set or unlimited_dims or set(attrs) & _RESERVED
                or not _covers(group, encoded)):
            super().store(variables, attributes, check_encoding_set, writer, unlimited_dims)
            return
        _set_attrs(group, attrs)
        dims = self._dimensions(group, encoded)
        for name, var in encoded.items():
            dset = _create_variable(group, name, var, dims)
            if var.dims == (name,):  # a coordinate: its dimension's scale
                dims[name] = (dset, dims[name][1])

    def _dimensions(self, group: h5py.Group, variables: dict) -> dict:
        """{dimension: (its scale, its number)} for every dimension of ``variables``: an
        enclosing group's (:func:`_enclosing_scale`), else a new one, its scale made here
        unless a variable is its coordinate (None until that variable is written)."""
        root = self.ds._root
        sizes = {}
        for var in variables.values():
            sizes |= var.sizes
        dims = {}
        for dim, size in sizes.items():
            scale = _enclosing_scale(group, dim, size)
            if scale is not None:
                dims[dim] = (scale, int(scale.attrs["_Netcdf4Dimid"]))
                continue
            root._max_dim_id += 1
            number = root._max_dim_id
            dims[dim] = (None if dim in variables else _phony_scale(group, dim, size, number),
                         number)
        return dims


def _covers(group: h5py.Group, variables: dict) -> bool:
    """Whether :class:`_GroupStore` writes these encoded variables into ``group`` itself: not
    if one has a dimension of length 0 (h5netcdf makes it unlimited and the variable chunked),
    a storage encoding (chunks, filters, a type), a type other than plain numbers or text (an
    enum's metadata, text with a fill value), a slash in its name or its dimensions' names,
    an attribute that netCDF-4 reserves (:data:`_RESERVED`: h5netcdf refuses it), or the name
    of a dimension that it is not the coordinate of; nor if a coordinate comes after a
    variable on its dimension (h5netcdf then replaces the dimension's scale by it) or is on an
    enclosing group's dimension."""
    seen = set()
    for name, var in variables.items():
        if (0 in var.shape or set(var.encoding) - _NO_STORAGE or "/" in name
                or any("/" in dim for dim in var.dims) or set(var.attrs) & _RESERVED
                or var.dtype.kind not in "iufU" or var.dtype.metadata
                or var.dtype.kind == "U" and "_FillValue" in var.attrs
                or var.dims == (name,) and (
                    name in seen or _enclosing_scale(group, name, var.size) is not None)):
            return False
        seen.update(var.dims)
    coords = {name for name, var in variables.items() if var.dims == (name,)}
    return not any(name in seen for name in set(variables) - coords)


def _enclosing_scale(group: h5py.Group, dim: str, size: int) -> h5py.Dataset | None:
    """The scale of dimension ``dim`` of length ``size`` that the variables of ``group`` are
    on if ``group`` makes no such dimension: the nearest enclosing group's dimension of that
    name, if it has that length (as xarray and h5netcdf decide)."""
    while group.name != "/":
        group = group.parent
        scale = group.get(dim)
        if isinstance(scale, h5py.Dataset) and h5py.h5ds.is_scale(scale.id):
            return scale if scale.shape == (size,) else None
    return None


def _phony_scale(group: h5py.Group, dim: str, size: int, number: int) -> h5py.Dataset:
    """The scale of dimension ``dim`` that has no variable (netCDF-4's, never written)."""
    scale = group.create_dataset(dim, (size,), ">f4", track_order=_tracks_order(group))
    scale.attrs["_Netcdf4Dimid"] = np.int32(number)
    scale.make_scale(_NOT_A_VARIABLE % size)
    return scale


def _create_variable(group: h5py.Group, name: str, var: xr.Variable,
                     dims: dict) -> h5py.Dataset:
    """The encoded variable ``var`` as the dataset ``name`` of ``group``, in netCDF-4's
    layout (see :class:`_GroupStore`); ``dims``: {dimension: (scale, number)}, the scale None
    for the dimension ``var`` is the coordinate of."""
    attrs = dict(var.attrs)
    fill = attrs.pop("_FillValue", None)
    data = var.values
    if data.dtype.kind == "U":  # h5py writes text from Python strings
        data = data.astype(object)
    dtype = h5py.string_dtype() if var.dtype.kind == "U" else var.dtype
    dset = group.create_dataset(name, data=data, dtype=dtype, fillvalue=fill,
                                track_order=_tracks_order(group))
    numbers = np.array([dims[dim][1] for dim in var.dims], np.int32)
    if var.dims == (name,):
        dset.attrs["_Netcdf4Dimid"] = numbers[0]
        dset.make_scale(name)
        dset.attrs["_Netcdf4Coordinates"] = numbers
    elif var.dims:
        for axis, dim in enumerate(var.dims):
            dset.dims[axis].attach_scale(dims[dim][0])
        dset.attrs["_Netcdf4Coordinates"] = numbers
        dset.attrs["_Netcdf4Dimid"] = numbers[0]
    if fill is not None:
        attrs = {"_FillValue": var.dtype.type(fill), **attrs}
    _set_attrs(dset, attrs)
    return dset


def _tracks_order(group: h5py.Group) -> bool:
    """Whether ``group`` tracks and indexes its attributes' creation order: the datasets made
    in it then keep their attributes in creation order too (h5netcdf's ``_track_order``)."""
    order = group.id.get_create_plist().get_attr_creation_order()
    return bool(order & h5py.h5p.CRT_ORDER_TRACKED) and bool(order & h5py.h5p.CRT_ORDER_INDEXED)


def _set_attrs(obj, attrs: dict) -> None:
    """netCDF-4 attributes on an HDF5 object, as h5netcdf writes them: a non-string scalar
    as a one-element array; no booleans (not a netCDF type)."""
    for key, value in attrs.items():
        dtype = np.asarray(value).dtype
        if dtype.kind == "b":
            raise h5netcdf.CompatibilityError(f"attribute {key!r}: booleans are not a "
                                              "netCDF-4 type")
        if np.isscalar(value) and dtype.kind not in "SU":
            value = np.atleast_1d(value)
        obj.attrs[key] = value


def _stores(groups) -> dict:
    """The xarray store class that writes each group (path → class): :class:`_GroupStore`,
    but xarray's h5netcdf store for a group that encloses other groups of ``groups`` (their
    dimensions may be its own, which h5netcdf then has to know: see :class:`_GroupStore`)."""
    enclosing = {path.rsplit("/", k)[0] for path in groups
                 for k in range(1, path.count("/") + 1)}
    return {path: xr.backends.H5NetCDFStore if path in enclosing else _GroupStore
            for path in groups}


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


def _plain_attr(value):
    """An attribute as h5netcdf reads it: text decoded, one-element arrays as scalars."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        return _plain_attr(value.reshape(())[()])
    return value


# ------------------------------------------------------------------- reading chunks back

class StoredRows:
    """Rows of a map of an atlas file, read as stored chunks and decoded in this process
    (:func:`decode_chunk`, the inverse of the encoding the tiles were stored with). HDF5
    inflates under its global lock, one chunk at a time; zlib and numpy's copies release the
    GIL, so the bands of a map are decoded on every core. Only for a variable filtered by
    deflate (after shuffle) alone, chunked by whole rows of one parameter point, and read
    lazily from the file whose coordinates the dataset has (:meth:`of` returns None
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
                or da.dims[-2:] != tuple(a.name for a in reversed(of_attrs(ds.attrs).axes))
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

    def close(self) -> None:
        self.file.close()
