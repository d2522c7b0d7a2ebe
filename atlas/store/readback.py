"""Reading back every stored chunk of an atlas or study file (``atlas info --check``).

Opening a file reads its metadata, and ``atlas info`` reads a few of its arrays: a chunk
damaged on disk (a flipped bit in its compressed bytes) is found only when something reads it,
perhaps long after. :func:`read_back` decodes every variable of every group in full, so that
such a chunk is found now and named (:class:`DamagedChunk`, one line). It finds what the
chunks' codecs detect: a compressed chunk whose bytes changed fails to decompress (zlib's
Adler-32 checksum, the stream's own structure); a changed byte of uncompressed data is a valid
number and cannot be told from the original.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from atlas.errors import InputFileError
from atlas.store.format import reason
from atlas.store.formats import format_for

__all__ = ["read_back", "ReadBack", "DamagedChunk"]


class DamagedChunk(InputFileError):
    """A stored variable that cannot be read back (exit status 2, one line naming it)."""


@dataclass(frozen=True)
class ReadBack:
    """What :func:`read_back` read: ``groups``, ``variables`` (coordinates included) and the
    decoded ``nbytes`` [bytes]."""

    groups: int
    variables: int
    nbytes: int


def read_back(path: str | Path) -> ReadBack:
    """Read every variable of every group of the atlas or study file at ``path`` in full
    (every stored chunk decoded). :class:`DamagedChunk` naming the group and variable of the
    first that cannot be read; :class:`~atlas.errors.InputFileError` where the file cannot
    be opened at all."""
    path = Path(path)
    if not path.exists():
        raise InputFileError(f"{path}: no such file")
    try:
        tree = format_for(path).open(path)
    except Exception as exc:  # a damaged file fails in h5py, h5netcdf, zarr or xarray
        raise InputFileError(f"{path}: not a readable atlas or study file "
                             f"({reason(exc)})") from None
    groups = variables = nbytes = 0
    try:
        for node in tree.subtree:
            groups += 1
            for name, var in node.to_dataset(inherit=False).variables.items():
                try:
                    values = np.asarray(var.values)
                except Exception as exc:  # a codec's or a library's error: damaged bytes
                    raise DamagedChunk(f"{path}: damaged data in group {node.path}, variable "
                                       f"{name}: a stored chunk cannot be read "
                                       f"({reason(exc)})") from None
                variables += 1
                nbytes += values.nbytes
    finally:
        tree.close()
    return ReadBack(groups, variables, nbytes)
