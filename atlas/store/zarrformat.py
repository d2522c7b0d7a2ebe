"""The atlas as a Zarr v3 store: the final format of an output named ``NAME.zarr``.

The same schema as the HDF5 file (:mod:`atlas.store.atlasfile`: root variables, coordinates,
attributes, groups ``/critical_points`` and ``/separatrices``), read with
``xr.open_datatree(path, engine="zarr")`` or :func:`atlas.open`.

During a run the store is built inside the partial folder (``<output>.partial/atlas.zarr``):
:func:`create` writes the metadata (one chunk per tile), :func:`write_tile` writes a tile by
region, whole chunks only, so tiles never share a chunk and any number of writers (Dask
workers with the partial folder on a shared file system) can write their own tiles at once.
Zarr writes each chunk to a temporary name and renames it, so a kill leaves a chunk whole or
absent; the tile counts as done only once its record is written after it
(:meth:`atlas.store.partial.TileStore.record`). :func:`finalize` adds the summary, marks the store
complete, and renames it onto the output.
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

__all__ = ["DATA", "is_zarr", "create", "write_tile", "finalize", "attrs_of", "open_tree"]

#: The Zarr store's folder name inside the partial folder.
DATA = "atlas.zarr"


def is_zarr(path: Path) -> bool:
    """True for an output path that names a Zarr store (``*.zarr``)."""
    return Path(path).suffix == ".zarr"


def _zarr():
    try:
        import zarr
    except ImportError:
        raise BackendUnavailable("a .zarr output needs the zarr package; "
                                 "pip install 'atlas[zarr]'") from None
    return zarr


def create(path: Path, layout) -> None:
    """The store's metadata: coordinates, empty label variables chunked one chunk per tile
    (no chunk is written)."""
    _zarr()
    import dask.array as da

    from atlas.store.atlasfile import _SPECS, chunks_of

    chunks = chunks_of(layout)
    shape = (*layout.parameter_shape, layout.theta_dot0.size, layout.theta0.size)
    data, encoding = {}, {}
    for name, (dtype, fill, attrs) in _SPECS.items():
        empty = da.zeros(shape, dtype=dtype, chunks=chunks)
        data[name] = (layout.dims, empty, attrs)
        encoding[name] = {"chunks": chunks, "_FillValue": fill}
    coords = layout.coords()
    xr.Dataset(data, coords=coords).to_zarr(path, mode="w", compute=False, encoding=encoding,
                                            zarr_format=3, consolidated=False)


def write_tile(path: Path, layout, index: int, values: dict) -> None:
    """Write tile ``index`` (``values``: name → array shaped (rows, n_theta0)) into its own
    chunks."""
    zarr = _zarr()
    params, rows = layout.tile(index)
    group = zarr.open_group(path, mode="r+")
    for name, array in values.items():
        group[name][(*params, rows, slice(None))] = array


def attrs_of(path: Path) -> dict:
    """The root attributes of a Zarr atlas (InputFileError if it is not one)."""
    zarr = _zarr()
    try:
        return dict(zarr.open_group(path, mode="r").attrs)
    except Exception as exc:  # zarr raises several kinds for a folder that is not a store
        raise InputFileError(f"{path}: not a readable Zarr store "
                             f"({exc.__class__.__name__})") from None


def open_tree(path: Path, chunks=None) -> xr.DataTree:
    return xr.open_datatree(path, engine="zarr", mask_and_scale=False, chunks=chunks)


def finalize(tiles, output: Path, groups: dict[str, xr.Dataset],
             root_vars: xr.Dataset, attrs: dict) -> None:
    """Complete the partial run's Zarr store and rename it onto ``output`` (an older store
    there is moved aside first and removed last); then remove the partial folder. Same
    arguments as :func:`atlas.store.atlasfile.finalize`."""
    zarr = _zarr()
    from atlas.store.atlasfile import SCHEMA

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


def _vlen_strings(ds: xr.Dataset) -> xr.Dataset:
    """Fixed-width numpy strings as variable-length ones (Zarr v3 specifies only these)."""
    return ds.map(lambda v: v.astype(object) if v.dtype.kind == "U" else v, keep_attrs=True) \
        .assign_coords({n: c.astype(object) for n, c in ds.coords.items() if c.dtype.kind == "U"})


def _plain(value):
    return value.item() if isinstance(value, np.generic) else value
