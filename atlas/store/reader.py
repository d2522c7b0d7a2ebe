"""Reading atlas files: open one checked (:func:`open_atlas`, ``atlas.open``), describe one
without loading its arrays, and read back the certificate its labels were made with.

The format is found by :func:`atlas.store.formats.format_for`; the file is checked by
:mod:`atlas.store.validate` before anything uses it, so a reader sees either a valid atlas
or one :class:`~atlas.errors.InputFileError` line. Files of format 3 and 4 are read; only
format 4 stores the certificate (the running barrier and the trap's energy cap,
:func:`stored_certificate`), so a view that draws it refuses format 3 with one line
(:func:`require_certificate`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import InputFileError
from atlas.layout import at_point, point_group
from atlas.store.format import reason
from atlas.store.formats import FORMATS, format_for
from atlas.store.partial import MANIFEST, PartialStoreError, TileStore, partial_path
from atlas.store.schema import CERTIFICATE_FORMAT, SCHEMA
from atlas.store.validate import check_tree, format_version, parse_config

__all__ = ["open_atlas", "describe", "is_atlas_file", "interrupted_run", "stored_rows",
           "stores_certificate",
           "require_certificate", "stored_certificate", "StoredBarrier", "StoredCertificate"]

_PARTIAL = ("a partial atlas (an interrupted run); finish it by running `atlas run CONFIG` "
            "again first")
#: Names of config files: given where an atlas file is expected, they get a hint.
CONFIG_SUFFIXES = (".yaml", ".yml")


def open_atlas(path: str | Path, *, chunks=None) -> xr.DataTree:
    """Open an atlas file as a DataTree with the stored dtypes (``attractor`` stays int16 with
    its fill value; plain ``xr.open_dataset`` would mask it to float NaN instead).

    The file is checked before it is returned (:mod:`atlas.store.validate`: format version,
    the basin map's variables, dtypes, dims and coordinates, the status flags, the summary,
    the stored config, the certificate of format 4): a file that fails raises
    :class:`InputFileError` with one line saying what is wrong. ``chunks={}`` opens lazily
    with dask (for outputs larger than memory).
    """
    path = Path(path)
    if not _complete(_attrs(path)):
        raise InputFileError(f"{path}: {_PARTIAL}")
    try:
        tree = format_for(path).open(path, chunks)
    except InputFileError:
        raise
    except Exception as exc:  # a damaged file fails in h5py, h5netcdf, zarr or xarray
        raise InputFileError(f"{path}: not a readable atlas file ({reason(exc)})") from None
    try:
        check_tree(tree, path)
    except BaseException:
        tree.close()
        raise
    return tree


def _complete(attrs: dict) -> bool:
    flag = np.asarray(attrs.get("complete", 0))
    return flag.size == 1 and flag.dtype.kind in "iub" and bool(flag.reshape(()))


def interrupted_run(path: str | Path) -> Path | None:
    """The partial run (``<path>.partial``) of an atlas not written yet because its run was
    interrupted, or None where there is none."""
    partial = partial_path(Path(path))
    return partial if (partial / MANIFEST).is_file() else None


def _attrs(path: Path) -> dict:
    """Attributes of an atlas file, or one clear InputFileError about what is wrong, with a
    hint where the mistake is a common one: the output of an interrupted run (only its
    ``.partial`` is there) or a config given for an atlas file."""
    if not path.exists():
        partial = interrupted_run(path)
        if partial is not None:
            raise InputFileError(f"{path}: not written yet: its run was interrupted and keeps "
                                 f"its finished tiles in {partial}; run the same config again "
                                 "(`atlas run CONFIG`) to finish it")
        raise InputFileError(f"{path}: no such file")
    if path.is_dir() and (path / MANIFEST).exists():
        raise InputFileError(f"{path}: {_PARTIAL}")
    if path.is_file() and not any(fmt.recognises(path) for fmt in FORMATS.values()):
        if path.suffix.lower() in CONFIG_SUFFIXES:
            raise InputFileError(f"{path}: a config, not an atlas file; run it with "
                                 f"`atlas run {path}` (a grid) or `atlas stability {path}` "
                                 "(a study), then give the file it writes")
        raise InputFileError(f"{path}: not an atlas file (an atlas file is the HDF5 file or "
                             "Zarr store that `atlas run` writes)")
    return format_for(path).attrs(path)


def is_atlas_file(path: str | Path) -> bool:
    """True if ``path`` is recognisably a file atlas wrote (an atlas file, complete or not,
    damaged or not, as long as its attributes say so): one a run may write over."""
    try:
        return _attrs(Path(path)).get("atlas_schema") == SCHEMA
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
                "tiles": tiles.layout.n_tiles, "config": parse_config(attrs, path)}
    attrs = _attrs(path)
    return {"attrs": attrs, "complete": _complete(attrs), "tiles_done": None,
            "tiles": None, "config": parse_config(attrs, path)}


def stored_rows(ds: xr.Dataset, name: str, point: dict[str, int]):
    """A reader of the stored chunks of map ``name`` at ``point`` (indices along the swept
    dims) of an atlas opened lazily with :func:`open_atlas`, decoding them in this process
    (its ``read(r0, r1)`` returns rows or None, ``close()`` releases the file;
    :class:`atlas.store.hdf5.StoredRows`), or None where its format has none or the variable
    is not stored as expected: read through xarray then."""
    source = ds[name].encoding.get("source")
    return format_for(source).stored_rows(ds, name, point) if source else None


# --------------------------------------------------------------------------- the certificate

@dataclass(frozen=True)
class StoredBarrier:
    """The running barrier the labels of one parameter point were certified with, as stored
    (format 4; the contract of :class:`atlas.physics.barrier.RunningBarrier`): in the frame
    of positive rotation (u = direction·θ, w = direction·θ̇) a state is certified running
    when ĝ(u) ≤ w ≤ ``top``, ĝ the linear interpolation of ``g`` [rad s-1] on the uniform
    grid u ∈ [``theta0``, ``theta0`` + 2π] (rad), u reduced mod 2π."""

    theta0: float
    g: np.ndarray
    top: float
    direction: int


@dataclass(frozen=True)
class StoredCertificate:
    """The certificate of one parameter point: the energy trap's cap [rad2 s-2] (a state
    of well k is trapped when E_k < ``trap_energy_cap``; −inf where no well can trap) and the
    running barrier (None where the point has no running cycle)."""

    trap_energy_cap: float
    barrier: StoredBarrier | None


def stores_certificate(attrs: dict) -> bool:
    """Whether an atlas file with root attributes ``attrs`` (already checked: :func:`open_atlas`)
    stores the certificate its labels used (format 4 on)."""
    return format_version(attrs, "atlas file") >= CERTIFICATE_FORMAT


def require_certificate(tree: xr.DataTree, path) -> None:
    """One InputFileError line unless the opened atlas ``tree`` (from ``path``) stores the
    certificate its labels used: what a view that draws the certificate calls first."""
    if not stores_certificate(tree.attrs):
        version = format_version(tree.attrs, path)
        raise InputFileError(f"{path} was written in format {version}, which does not store "
                             "the certificate its labels used; recompute it by running its "
                             "config again (`atlas run CONFIG`)")


def stored_certificate(tree: xr.DataTree, point: dict[str, float]) -> StoredCertificate | None:
    """The certificate the labels of parameter point ``point`` ({parameter: value}, as
    :func:`atlas.layout.points` lists them) were made with, read from the opened atlas
    ``tree``; None for a file of format 3, which does not store it."""
    if not stores_certificate(tree.attrs):
        return None
    root = at_point(tree.to_dataset(inherit=False), point)
    cycle = point_group(tree, "limit_cycle", point)
    barrier = None
    if cycle is not None and "barrier_g" in cycle.variables:
        barrier = StoredBarrier(theta0=float(cycle.attrs["barrier_theta0"]),
                                g=np.asarray(cycle["barrier_g"].values, np.float64),
                                top=float(cycle.attrs["barrier_top"]),
                                direction=int(cycle.attrs["barrier_direction"]))
    return StoredCertificate(trap_energy_cap=float(root["trap_energy_cap"].values),
                             barrier=barrier)
