"""The file-format interface, after xarray's ``BackendEntrypoint``, in two parts.

A :class:`Container` is a format as a place that holds xarray data: it recognises its files
(:meth:`~Container.guess_can_open`: by name, or by content: :meth:`~Container.recognises`),
reads their root attributes and opens them (:meth:`~Container.root_attrs`,
:meth:`~Container.attrs` of an atlas, :meth:`~Container.open`,
:meth:`~Container.open_dataset`) and writes a whole Dataset durably
(:meth:`~Container.write_dataset`: the study file of ``atlas stability``). A :class:`TileRun`
is how a partial run of a sweep writes into that format: it makes what its tiles need in the
partial folder (:meth:`~TileRun.create`), writes one tile's label arrays
(:meth:`~TileRun.write_tile`) and assembles the finished atlas (:meth:`~TileRun.finalize`);
each container names its own (:attr:`Container.tile_run`). The formats are
:mod:`atlas.store.hdf5` and :mod:`atlas.store.zarrformat`, the only modules that import h5py,
h5netcdf or zarr; the table of them and the one lookup that answers "which format?" are in
:mod:`atlas.store.formats`. The schema they write is :mod:`atlas.store.schema`; the partial
run that hands them its tiles is :class:`atlas.store.partial.TileStore`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

if TYPE_CHECKING:
    import xarray as xr

    from atlas.layout import Layout

__all__ = ["Container", "TileRun", "reason"]


class _Stateless:
    """Equal to any instance of its class; picklable (to Dask workers) and hashable."""

    name: ClassVar[str]

    def __eq__(self, other) -> bool:
        return type(other) is type(self)

    def __hash__(self) -> int:
        return hash(type(self))


class TileRun(_Stateless):
    """How a partial run writes the tiles of an atlas of one format (stateless).

    ``name`` is the format's, recorded in a partial run's manifest;
    ``parallel_tile_writes`` says whether many processes may write tiles at once
    (:meth:`write_tile` on Dask workers, each into its own chunks).
    """

    parallel_tile_writes: ClassVar[bool] = False

    def __repr__(self) -> str:
        return f"<tile run of atlas file format {self.name!r}>"

    def create(self, folder: Path, layout: Layout) -> None:
        """Make, inside a new partial-run folder, what this format's tiles are written into
        (nothing where each tile's bytes are kept with its record)."""

    def write_tile(self, folder: Path, layout: Layout, index: int,
                   values: dict) -> dict[str, bytes]:
        """Write tile ``index`` (``values``: each map variable's array, shaped (rows,
        n_theta0)) of the partial run in ``folder``; return the bytes to keep with the tile's
        record ({} where the tile is already written into the format's own store)."""
        raise NotImplementedError

    def finalize(self, tiles, output: Path, groups: dict[str, xr.Dataset],
                 root_vars: xr.Dataset, attrs: dict) -> None:
        """Assemble the finished tiles of ``tiles`` (a
        :class:`~atlas.store.partial.TileStore`) into the atlas at ``output``, then remove the
        partial run. ``groups`` (path → dataset) become groups (``/critical_points``, …),
        ``root_vars`` the summary's root variables
        (:func:`atlas.store.schema.summary_dataset`), ``attrs`` root attributes (after the
        partial run's own). The output path only ever holds a complete atlas: an
        interruption leaves it as it was and the tiles in place. A tile that cannot be read
        back raises :class:`~atlas.store.partial.DamagedTile`."""
        raise NotImplementedError


class Container(_Stateless):
    """One file format as a container of xarray data (stateless).

    ``kind`` names a file of this format in messages ("an HDF5 file"); ``suffixes`` are the
    output names that ask for this format (``NAME.zarr``); ``folder`` says whether a file of
    this format is a directory; :attr:`tile_run` is how a sweep writes an atlas in it.
    """

    kind: ClassVar[str]
    description: ClassVar[str]
    suffixes: ClassVar[tuple[str, ...]]
    folder: ClassVar[bool] = False
    tile_run: ClassVar[TileRun]

    def __repr__(self) -> str:
        return f"<atlas file format {self.name!r}>"

    def guess_can_open(self, path: Path) -> bool:
        """Whether ``path`` is of this format: its name has one of :attr:`suffixes`, or what
        is there is recognised (:meth:`recognises`)."""
        return Path(path).suffix in self.suffixes or self.recognises(Path(path))

    def recognises(self, path: Path) -> bool:
        """Whether what is at ``path`` is of this format, by its content (a magic number, a
        metadata file: cheap, no library opened); False where nothing is there."""
        raise NotImplementedError

    def require(self) -> None:
        """Raise :class:`~atlas.errors.BackendUnavailable` if this format's library is not
        installed (before a run starts)."""

    def root_attrs(self, path: Path) -> dict:
        """The root attributes of the file at ``path``, whatever it holds, read from the
        metadata only; :class:`~atlas.errors.InputFileError` with one line if it is not a
        readable file of this format."""
        raise NotImplementedError

    def attrs(self, path: Path) -> dict:
        """The root attributes of the atlas at ``path`` (complete or not), read from the
        metadata only; :class:`~atlas.errors.InputFileError` with one line if it is not a
        readable atlas of this format."""
        raise NotImplementedError

    def open(self, path: Path, chunks=None) -> xr.DataTree:
        """The atlas at ``path`` as a DataTree with the stored dtypes (``mask_and_scale``
        off); ``chunks={}`` opens it lazily with dask."""
        raise NotImplementedError

    def open_dataset(self, path: Path) -> xr.Dataset:
        """The root group of the file at ``path``, loaded, with the stored dtypes
        (``mask_and_scale`` off): a study file."""
        raise NotImplementedError

    def write_dataset(self, ds: xr.Dataset, path: Path) -> None:
        """Write ``ds`` as the whole file at ``path``: whole or not at all (a temporary name
        renamed into place; an older file there stays until the new one is complete)."""
        raise NotImplementedError

    def stored_rows(self, ds: xr.Dataset, name: str, point: dict[str, int]):
        """A reader of the stored chunks of map ``name`` at ``point`` of a lazily opened
        atlas, decoded in this process (:class:`atlas.store.hdf5.StoredRows`), or None where
        the format has none: the caller reads through xarray."""
        return None


def reason(exc: BaseException) -> str:
    """The first line of an exception's message (its type where it has none), for a one-line
    :class:`~atlas.errors.InputFileError`."""
    text = str(exc).strip()
    return text.splitlines()[0][:200] if text else exc.__class__.__name__
