"""The store of an unfinished run: ``<output>.partial/``, one file per finished tile.

A kill at any instant loses at most the tile in flight, because nothing is ever modified in
place:

* ``manifest.json`` (the run's identity, its layout and provenance) is written once, when the
  run starts: the folder is built under a temporary name, fsynced and renamed into place, so
  a partial folder always has its manifest;
* each finished tile is written to a temporary name, fsynced, then renamed to
  ``tiles/<index>.npz`` (and the folder fsynced): the file's existence is the record that the
  tile is done, and its contents are whole (the zip's CRC is checked when it is read back);
* leftovers of a write that was cut short (``*.tmp``) are not tiles and are cleared when the
  run is reopened.

For an HDF5 output a tile file holds the tile's three label arrays as the final file stores
them (a chunk of ``rows_per_tile`` rows, byte-shuffled then deflated, the edge chunk padded;
see :func:`encode_chunk`), so :func:`atlas.store.atlasfile.finalize` assembles the output by copying
compressed chunks without re-encoding. For a Zarr output (``NAME.zarr``) the arrays go by
region into the Zarr store ``atlas.zarr`` inside the partial folder (:mod:`atlas.store.zarrformat`),
before the tile file is written, and the tile file holds only the record. Either way the tile
file holds the tile's basin counts (trapped orbits per well k, and the orbits not trapped), so
basin fractions are summed from O(tiles) numbers. This module never touches HDF5;
:mod:`atlas.store.atlasfile` does.
"""

from __future__ import annotations

import json
import os
import shutil
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from atlas.layout import Layout

__all__ = ["TileStore", "Tile", "partial_path", "encode_chunk", "decode_chunk", "discard",
           "DEFLATE_LEVEL", "MANIFEST", "PartialStoreError", "IdentityMismatch", "VARIABLES",
           "fsync"]

MANIFEST = "manifest.json"
SCHEMA = "atlas-partial/3"
#: zlib level of the chunks (the HDF5 variables' gzip level, :mod:`atlas.store.atlasfile`).
DEFLATE_LEVEL = 4
#: The per-orbit variables of a tile, in file order.
VARIABLES = ("attractor", "status", "t_trap", "boundary_distance")


class PartialStoreError(Exception):
    """A partial folder that cannot be used: unreadable, or from an older atlas."""


class IdentityMismatch(PartialStoreError):
    """A partial run whose identity differs from the run asked for; ``differs`` names keys."""

    def __init__(self, differs: list[str]):
        super().__init__(", ".join(differs))
        self.differs = differs


def partial_path(output: Path) -> Path:
    """Where an unfinished run keeps its tiles: next to the output, never at it."""
    return output.with_name(output.name + ".partial")


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


@dataclass(frozen=True)
class Tile:
    """A finished tile as stored: its encoded chunks and its tally (basin counts and the
    certificate's figures, :meth:`atlas.boundaries.certificate.Certifier.tile`)."""

    chunks: dict[str, bytes]
    tally: dict[str, np.ndarray]


def fsync(path: Path) -> None:
    """Push a file's or a folder's contents (a folder: its entries) to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_durably(path: Path, write) -> None:
    """``write(file)`` into a private temporary name, fsync, rename onto ``path``, fsync the
    folder: ``path`` then either does not exist or holds the whole content, whatever happens."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    fsync(path.parent)


class TileStore:
    """An open partial run: its manifest and its finished tiles.

    Make one with :meth:`create` or :meth:`open`; the caller holds the output's lock.
    """

    def __init__(self, path: Path, manifest: dict):
        self.path = path
        self.manifest = manifest
        self.layout = Layout.from_json(manifest["layout"])

    # ---------------------------------------------------------------- creating, opening

    @classmethod
    def create(cls, path: Path, layout: Layout, identity: dict, attrs: dict,
               output_format: str = "hdf5") -> TileStore:
        """A new, empty partial run at ``path`` (which must not exist), for an output of
        ``output_format`` 'hdf5' or 'zarr'."""
        manifest = {"schema": SCHEMA, "identity": identity, "layout": layout.to_json(),
                    "format": output_format, "attrs": _jsonable(attrs)}
        new = path.with_name(f"{path.name}.{os.getpid()}.new")
        shutil.rmtree(new, ignore_errors=True)
        try:
            (new / "tiles").mkdir(parents=True)
            if output_format == "zarr":
                from atlas.store import zarrformat as zarrstore

                zarrstore.create(new / zarrstore.DATA, layout)
            _write_durably(new / MANIFEST,
                           lambda fh: fh.write(json.dumps(manifest, indent=1).encode()))
            fsync(new / "tiles")
            os.rename(new, path)  # fails if path exists: never over someone's tiles
        except BaseException:
            shutil.rmtree(new, ignore_errors=True)
            raise
        fsync(path.parent)
        return cls(path, manifest)

    @classmethod
    def read(cls, path: Path) -> TileStore:
        """Read a partial run's manifest without changing anything (PartialStoreError if it is
        not a readable partial run)."""
        if not path.is_dir():
            raise PartialStoreError("not a partial-run folder (a partial file from an older "
                                    "atlas, or something else)")
        try:
            manifest = json.loads((path / MANIFEST).read_text())
            if manifest.get("schema") != SCHEMA:
                raise ValueError(f"schema {manifest.get('schema')!r}")
            store = cls(path, manifest)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise PartialStoreError(f"unreadable manifest ({exc.__class__.__name__})") from None
        return store

    @classmethod
    def open(cls, path: Path, identity: dict) -> TileStore:
        """Reopen a partial run to continue it: its identity must equal ``identity``
        (checked before anything in the folder is touched), then leftovers of interrupted
        writes are cleared."""
        store = cls.read(path)
        store.check(identity)
        for leftover in (*path.glob("tiles/.*.tmp"), *path.glob(".*.tmp")):
            leftover.unlink(missing_ok=True)
        return store

    def check(self, identity: dict) -> None:
        """Raise IdentityMismatch (naming the keys) unless this run has ``identity``."""
        theirs = self.manifest["identity"]
        differs = sorted(k for k in {*identity, *theirs} if identity.get(k) != theirs.get(k))
        if differs:
            raise IdentityMismatch(differs)

    @staticmethod
    def clear_leftovers(path: Path) -> None:
        """Remove folders of creations cut short (they hold no tiles) and of removals cut
        short (:func:`discard`)."""
        for folder in (*path.parent.glob(f"{path.name}.*.new"),
                       *path.parent.glob(f".{path.name}.*.discarded")):
            shutil.rmtree(folder, ignore_errors=True)

    # ---------------------------------------------------------------- tiles

    def _tile_path(self, index: int) -> Path:
        return self.path / "tiles" / f"{index:07d}.npz"

    def done(self) -> np.ndarray:
        """Indices of the finished tiles, sorted."""
        names = (p.name for p in (self.path / "tiles").glob("*.npz"))
        return np.array(sorted(int(n[:-4]) for n in names if n[:-4].isdigit()), np.int64)

    def todo(self) -> np.ndarray:
        return np.setdiff1d(np.arange(self.layout.n_tiles), self.done())

    @property
    def format(self) -> str:
        return self.manifest["format"]

    def write(self, index: int, values: dict, tally: dict, fills: dict) -> None:
        """Store tile ``index`` durably and atomically: ``values`` maps each of
        :data:`VARIABLES` to its array (shaped (rows, n_theta0)), ``tally`` holds the tile's
        named count arrays."""
        if self.format == "zarr":
            from atlas.store import zarrformat as zarrstore

            zarrstore.write_tile(self.path / zarrstore.DATA, self.layout, index, values)
            chunks = {}
        else:
            rows = self.layout.chunk_rows
            chunks = {name: encode_chunk(values[name], rows, fills[name]) for name in VARIABLES}
        self.record(index, tally, chunks)

    def record(self, index: int, tally: dict, chunks: dict | None = None) -> None:
        """Record tile ``index`` done, with its ``tally`` and, for an HDF5 output, its encoded
        chunks: the tile file appears whole, or not at all."""
        arrays = {name: np.frombuffer(data, np.uint8) for name, data in (chunks or {}).items()}
        arrays.update({f"tally_{name}": np.asarray(value) for name, value in tally.items()})
        _write_durably(self._tile_path(index), lambda fh: np.savez(fh, **arrays))

    def read_tile(self, index: int) -> Tile:
        """A finished tile; OSError/ValueError/BadZipFile if its file is damaged."""
        with np.load(self._tile_path(index)) as z:
            return Tile(chunks={name: z[name].tobytes() for name in VARIABLES if name in z},
                        tally={name[6:]: z[name] for name in z.files
                               if name.startswith("tally_")})

    def read_tally(self, index: int) -> dict[str, np.ndarray]:
        """Only the tally of a finished tile (a few numbers: the label chunks are not read);
        OSError/ValueError/BadZipFile if its file is damaged."""
        with np.load(self._tile_path(index)) as z:
            return {name[6:]: z[name] for name in z.files if name.startswith("tally_")}

    def set_aside(self, index: int) -> None:
        """Move a damaged tile file to ``damaged/`` (kept for inspection, no longer done)."""
        (self.path / "damaged").mkdir(exist_ok=True)
        os.replace(self._tile_path(index), self.path / "damaged" / self._tile_path(index).name)

    def remove(self) -> None:
        """Delete the partial run, once its output is in place."""
        discard(self.path)


def discard(path: Path) -> None:
    """Delete a partial run (file or folder) so that an interruption never leaves half of
    it at ``path``: it is renamed away first (atomic), then deleted; what an interruption
    leaves under the new name is cleared by :meth:`TileStore.clear_leftovers`."""
    away = path.with_name(f".{path.name}.{os.getpid()}.discarded")
    os.rename(path, away)
    fsync(path.parent)
    if away.is_dir():
        shutil.rmtree(away)
    else:
        away.unlink()


def _jsonable(attrs: dict) -> dict:
    return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in attrs.items()
            if v is not None}
