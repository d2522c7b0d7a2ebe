"""The store of an unfinished run: ``<output>.partial/``, one file per finished tile.

A kill at any instant loses at most the tile in flight: nothing is modified in place
(:mod:`atlas.store.durable`). ``manifest.json`` (identity, layout, output format, provenance)
is written once, with the folder built under a temporary name and renamed into place; each
finished tile is written under a temporary name and renamed to ``tiles/<index>.npz``, so the
file's existence is the record that the tile is done and its contents are whole (the zip's
CRC is checked on reading); leftovers of cut-short writes (``*.tmp``) are cleared on reopening.

The store is handed the output format's :class:`~atlas.store.format.TileRun` and never asks
which one it is: it writes each tile's label arrays (``write_tile``: HDF5 returns encoded
chunks, kept in the tile file; Zarr writes into its store in the folder) and assembles the
output (:meth:`TileStore.finalize`). Each tile file holds the tile's tally (basin counts,
certificate figures), so the summary is summed from O(tiles) numbers.
"""

from __future__ import annotations

import json
import os
import shutil
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from atlas.layout import Layout
from atlas.store.durable import discard, fsync, write_durably
from atlas.store.format import TileRun
from atlas.store.formats import DEFAULT, format_named

__all__ = ["TileStore", "Tile", "partial_path", "discard", "MANIFEST", "PartialStoreError",
           "IdentityMismatch", "DamagedTile"]

MANIFEST = "manifest.json"
SCHEMA = "atlas-partial/3"
#: What reading a damaged tile file raises (a zip cut short, a CRC that fails, …).
_DAMAGE = (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile)


class PartialStoreError(Exception):
    """A partial folder that cannot be used: unreadable, or from an older atlas."""


class IdentityMismatch(PartialStoreError):
    """A partial run whose identity differs from the run asked for; ``differs`` names keys."""

    def __init__(self, differs: list[str]):
        super().__init__(", ".join(differs))
        self.differs = differs


class DamagedTile(Exception):
    """A tile file that cannot be read back (its index in ``index``): set it aside
    (:meth:`TileStore.set_aside`) and compute the tile again."""

    def __init__(self, index: int, reason: str):
        super().__init__(f"tile {index}: {reason}")
        self.index = index


def partial_path(output: Path) -> Path:
    """Where an unfinished run keeps its tiles: next to the output, never at it."""
    return output.with_name(output.name + ".partial")


@dataclass(frozen=True)
class Tile:
    """A finished tile as stored: the bytes its format keeps with the record (HDF5: the
    encoded chunks of each map variable; none for Zarr) and its tally (basin counts and the
    certificate's figures, :meth:`atlas.boundaries.certificate.Certifier.tile`)."""

    chunks: dict[str, bytes]
    tally: dict[str, np.ndarray]


class TileStore:
    """An open partial run: its manifest, its output format and its finished tiles.

    Make one with :meth:`create` or :meth:`open`; the caller holds the output's lock.
    """

    def __init__(self, path: Path, manifest: dict, tile_run: TileRun):
        self.path = path
        self.manifest = manifest
        self.layout = Layout.from_json(manifest["layout"])
        self.tile_run = tile_run

    # ---------------------------------------------------------------- creating, opening

    @classmethod
    def create(cls, path: Path, layout: Layout, identity: dict, attrs: dict,
               tile_run: TileRun = DEFAULT.tile_run) -> TileStore:
        """A new, empty partial run at ``path`` (which must not exist), written by
        ``tile_run`` (the :attr:`~atlas.store.format.Container.tile_run` of
        :func:`atlas.store.formats.format_for` of the output)."""
        manifest = {"schema": SCHEMA, "identity": identity, "layout": layout.to_json(),
                    "format": tile_run.name, "attrs": _jsonable(attrs)}
        new = path.with_name(f"{path.name}.{os.getpid()}.new")
        shutil.rmtree(new, ignore_errors=True)
        try:
            (new / "tiles").mkdir(parents=True)
            tile_run.create(new, layout)
            write_durably(new / MANIFEST,
                          lambda fh: fh.write(json.dumps(manifest, indent=1).encode()))
            fsync(new / "tiles")
            os.rename(new, path)  # fails if path exists: never over someone's tiles
        except BaseException:
            shutil.rmtree(new, ignore_errors=True)
            raise
        fsync(path.parent)
        return cls(path, manifest, tile_run)

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
            store = cls(path, manifest, format_named(manifest["format"]).tile_run)
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

    def write(self, index: int, values: dict, tally: dict) -> None:
        """Store tile ``index`` durably and atomically: ``values`` maps each map variable
        (the model's :attr:`~atlas.models.base.Model.map_variables`) to its array (shaped
        (rows, columns)), written by the format; ``tally`` holds the tile's named count arrays."""
        self.record(index, tally, self.tile_run.write_tile(self.path, self.layout, index,
                                                           values))

    def record(self, index: int, tally: dict, chunks: dict | None = None) -> None:
        """Record tile ``index`` done, with its ``tally`` and the bytes its format keeps
        (:meth:`~atlas.store.format.TileRun.write_tile`'s result; none where the tile was
        written by a worker into the format's own store): the tile file appears whole, or
        not at all."""
        arrays = {name: np.frombuffer(data, np.uint8) for name, data in (chunks or {}).items()}
        arrays.update({f"tally_{name}": np.asarray(value) for name, value in tally.items()})
        write_durably(self._tile_path(index), lambda fh: np.savez(fh, **arrays))

    def read_tile(self, index: int) -> Tile:
        """A finished tile; :class:`DamagedTile` if its file cannot be read back."""
        try:
            with np.load(self._tile_path(index)) as z:
                return Tile(chunks={name: z[name].tobytes() for name in z.files
                                    if not name.startswith("tally_")},
                            tally={name[6:]: z[name] for name in z.files
                                   if name.startswith("tally_")})
        except _DAMAGE as exc:
            raise DamagedTile(index, exc.__class__.__name__) from None

    def read_tally(self, index: int) -> dict[str, np.ndarray]:
        """Only the tally of a finished tile (a few numbers: the label chunks are not read);
        :class:`DamagedTile` if its file cannot be read back."""
        try:
            with np.load(self._tile_path(index)) as z:
                return {name[6:]: z[name] for name in z.files if name.startswith("tally_")}
        except _DAMAGE as exc:
            raise DamagedTile(index, exc.__class__.__name__) from None

    def set_aside(self, index: int) -> None:
        """Move a damaged tile file to ``damaged/`` (kept for inspection, no longer done)."""
        (self.path / "damaged").mkdir(exist_ok=True)
        os.replace(self._tile_path(index), self.path / "damaged" / self._tile_path(index).name)

    def finalize(self, output: Path, groups: dict, root_vars, attrs: dict) -> None:
        """Assemble the finished tiles into the atlas at ``output`` in this run's format,
        then remove the partial run (:meth:`atlas.store.format.TileRun.finalize`)."""
        self.tile_run.finalize(self, output, groups, root_vars, attrs)

    def remove(self) -> None:
        """Delete the partial run, once its output is in place."""
        discard(self.path)


def _jsonable(attrs: dict) -> dict:
    return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in attrs.items()
            if v is not None}
