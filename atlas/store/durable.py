"""Durable writes: a file or a folder is whole at its path, or absent, whatever interrupts.

The three moves every store write is made of (POSIX semantics: ``rename`` is atomic within
a file system, ``fsync`` of a folder makes its entries durable): :func:`fsync` pushes a
file or a folder's entries to disk, :func:`write_durably` writes a file under a temporary
name and renames it into place, :func:`discard` renames a folder away before deleting it.
Where ``fsync`` of a folder is not supported (Windows) the writes are atomic but not
durable against a power cut.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["fsync", "write_durably", "discard"]


def fsync(path: Path) -> None:
    """Push a file's or a folder's contents (a folder: its entries) to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_durably(path: Path, write) -> None:
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


def discard(path: Path) -> None:
    """Delete a file or folder so that an interruption never leaves half of it at ``path``:
    it is renamed away first (atomic), then deleted; what an interruption leaves under the
    new name (``.NAME.<pid>.discarded``) is cleared by the next run
    (:meth:`atlas.store.partial.TileStore.clear_leftovers`)."""
    away = path.with_name(f".{path.name}.{os.getpid()}.discarded")
    os.rename(path, away)
    fsync(path.parent)
    if away.is_dir():
        shutil.rmtree(away)
    else:
        away.unlink()
