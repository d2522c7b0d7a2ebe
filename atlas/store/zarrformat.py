"""The Zarr format: the atlas as a Zarr v3 store, for an output named ``NAME.zarr``.

The only code that touches Zarr, as :mod:`atlas.store.hdf5` is for HDF5. The same schema as the HDF5
file (:mod:`atlas.store.schema`: root variables, coordinates, attributes, groups
``/critical_points``, ``/separatrices``, ``/limit_cycle``), read with
``xr.open_datatree(path, engine="zarr")`` or :func:`atlas.open`.

During a run the store is built inside the partial folder (``<output>.partial/atlas.zarr``):
:meth:`ZarrTiles.create` writes the metadata (one chunk per tile), :meth:`ZarrTiles.write_tile`
writes a tile by region, whole chunks only, so tiles never share a chunk and any number of
writers (Dask workers with the partial folder on a shared file system) can write their own
tiles at once. Zarr writes each chunk to a temporary name and renames it, so a kill leaves a
chunk whole or absent; the tile counts as done only once its record is written after it
(:meth:`atlas.store.partial.TileStore.record`). :meth:`ZarrTiles.finalize` adds the summary,
marks the store complete, and renames it onto the output.
"""

from __future__ import annotations

import os
import shutil
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import BackendUnavailable, InputFileError
from atlas.layout import Layout
from atlas.store.format import Container, TileRun
from atlas.store.schema import SCHEMA, chunks_of, map_variables, not_an_atlas

__all__ = ["Zarr", "ZarrTiles", "DATA", "root_attrs"]

#: The Zarr store's folder name inside the partial folder.
DATA = "atlas.zarr"


def _zarr():
    try:
        import zarr
    except ImportError:
        raise BackendUnavailable("a .zarr output needs the zarr package; "
                                 "pip install 'pendulum-atlas[zarr]'") from None
    return zarr


class ZarrTiles(TileRun):
    """A sweep's tiles into a Zarr store inside the partial folder, each tile its own
    chunks, written by whichever process computed it (module docstring)."""

    name = "zarr"
    parallel_tile_writes = True

    def create(self, folder: Path, layout: Layout) -> None:
        """The store's metadata: coordinates, empty label variables chunked one chunk per
        tile (no chunk is written)."""
        _zarr()
        import dask.array as da

        chunks = chunks_of(layout)
        shape = (*layout.parameter_shape, layout.v0.size, layout.x0.size)
        data, encoding = {}, {}
        for name, spec in map_variables(layout).items():
            empty = da.zeros(shape, dtype=spec.dtype, chunks=chunks)
            data[name] = (layout.dims, empty, spec.attrs)
            encoding[name] = {"chunks": chunks, "_FillValue": spec.fill}
        xr.Dataset(data, coords=layout.coords()).to_zarr(
            folder / DATA, mode="w", compute=False, encoding=encoding, zarr_format=3,
            consolidated=False)

    def write_tile(self, folder: Path, layout: Layout, index: int,
                   values: dict) -> dict[str, bytes]:
        """Write tile ``index`` into its own chunks of the store; nothing to keep with the
        record."""
        zarr = _zarr()
        params, rows = layout.tile(index)
        group = zarr.open_group(folder / DATA, mode="r+")
        for name, array in values.items():
            group[name][(*params, rows, slice(None))] = array
        return {}

    def finalize(self, tiles, output: Path, groups: dict[str, xr.Dataset],
                 root_vars: xr.Dataset, attrs: dict) -> None:
        """Complete the partial run's store and rename it onto ``output`` (an older store
        there is moved aside first and removed last); then remove the partial folder."""
        zarr = _zarr()
        layout = tiles.layout
        path = tiles.path / DATA
        for leftover in path.rglob("*.partial"):  # a chunk write cut short (zarr's temp name)
            leftover.unlink()
        root_vars.drop_vars([n for n in root_vars.coords if n in layout.coords()]).to_zarr(
            path, mode="a", consolidated=False)
        for name, ds in groups.items():
            _vlen_strings(ds).to_zarr(path, group=name, mode="w", consolidated=False)
        root = zarr.open_group(path, mode="r+")
        root.attrs.update({**tiles.manifest["attrs"], "atlas_schema": SCHEMA,
                           **{k: _plain(v) for k, v in attrs.items() if v is not None},
                           "complete": 1})
        with warnings.catch_warnings():  # "not part of the v3 spec yet": xarray reads it
            warnings.simplefilter("ignore")
            zarr.consolidate_metadata(path)  # one read opens the whole tree
        for stale in output.parent.glob(f".{output.name}.*.old"):  # a rename cut short
            shutil.rmtree(stale, ignore_errors=True)
        aside = output.with_name(f".{output.name}.{os.getpid()}.old")
        if output.exists():
            os.rename(output, aside)
        os.rename(path, output)
        shutil.rmtree(aside, ignore_errors=True)
        tiles.remove()

class Zarr(Container):
    name = "zarr"
    kind = "a Zarr store"
    description = "a Zarr v3 store (a folder; tiles written in parallel, e.g. by Dask workers)"
    suffixes = (".zarr",)
    folder = True
    tile_run = ZarrTiles()

    def recognises(self, path: Path) -> bool:
        return (path / "zarr.json").is_file()

    def require(self) -> None:
        _zarr()

    def root_attrs(self, path: Path) -> dict:
        return root_attrs(path)

    def attrs(self, path: Path) -> dict:
        if path.is_dir() and not (path / "zarr.json").exists():
            raise InputFileError(f"{path}: is a directory, not an atlas file")
        attrs = root_attrs(path)
        if attrs.get("atlas_schema") != SCHEMA:
            raise InputFileError(not_an_atlas(path, attrs, self.kind,
                                              xarray="xr.open_zarr('{path}')"))
        return attrs

    def open(self, path: Path, chunks=None) -> xr.DataTree:
        return xr.open_datatree(path, engine="zarr", mask_and_scale=False, chunks=chunks)


    def open_dataset(self, path: Path) -> xr.Dataset:
        return xr.open_zarr(path, consolidated=False, mask_and_scale=False).load()

    def write_dataset(self, ds: xr.Dataset, path: Path) -> None:
        """A folder cannot be replaced in one step: the new store is written under a
        temporary name, the old one moved aside, the new one renamed into place, and only
        then the old one removed (put back if the rename fails)."""
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        old = path.with_name(f".{path.name}.{os.getpid()}.old")
        try:
            ds.to_zarr(tmp, mode="w", consolidated=False)
            if path.exists() or path.is_symlink():
                os.replace(path, old)
            os.replace(tmp, path)
        except BaseException:
            if old.exists() and not path.exists():  # put the old store back where it was
                os.replace(old, path)
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        shutil.rmtree(old, ignore_errors=True)


def root_attrs(path: Path) -> dict:
    """The root attributes of the Zarr store at ``path``; InputFileError in one line if it is
    not a readable store."""
    zarr = _zarr()
    try:
        return dict(zarr.open_group(path, mode="r").attrs)
    except Exception as exc:  # zarr raises several kinds for what is not a store
        raise InputFileError(f"{path}: not a readable Zarr store "
                             f"({exc.__class__.__name__})") from None


def _vlen_strings(ds: xr.Dataset) -> xr.Dataset:
    """Fixed-width numpy strings as variable-length ones (Zarr v3 specifies only these)."""
    return ds.map(lambda v: v.astype(object) if v.dtype.kind == "U" else v, keep_attrs=True) \
        .assign_coords({n: c.astype(object) for n, c in ds.coords.items() if c.dtype.kind == "U"})


def _plain(value):
    return value.item() if isinstance(value, np.generic) else value
