"""The table of file formats and the one lookup that answers "which format?".

After xarray's ``backends/plugins.py`` (``guess_engine``): :data:`FORMATS` lists every
:class:`~atlas.store.format.Container` by name, :func:`format_for` picks the one for a path and
:func:`format_named` the one a partial run's manifest records. The rest of atlas asks these
and calls the format's methods; it never tests a format's name or a path's suffix itself.
A new format is one module implementing :class:`~atlas.store.format.Container` and its
:class:`~atlas.store.format.TileRun`, and one line in
:data:`FORMATS`.
"""

from __future__ import annotations

from pathlib import Path

from atlas.store.format import Container
from atlas.store.hdf5 import HDF5
from atlas.store.zarrformat import Zarr

__all__ = ["FORMATS", "DEFAULT", "format_for", "format_named"]

#: Every format, by name (the name a partial run's manifest records).
FORMATS: dict[str, Container] = {fmt.name: fmt for fmt in (HDF5(), Zarr())}
#: The format of an output whose name asks for none (``NAME.h5``, or any other name).
DEFAULT = FORMATS["hdf5"]


def format_for(path: str | Path) -> Container:
    """The format of the atlas at ``path``, to read or to write: the one whose suffix it
    has (``NAME.zarr``: Zarr; ``NAME.h5``, ``.nc``: HDF5), else the one that recognises what
    is there (by content: a name without a known suffix), else :data:`DEFAULT`."""
    path = Path(path)
    for fmt in FORMATS.values():
        if path.suffix in fmt.suffixes:
            return fmt
    for fmt in FORMATS.values():
        if fmt.recognises(path):
            return fmt
    return DEFAULT


def format_named(name: str) -> Container:
    """The format called ``name`` (KeyError naming the known ones if there is none)."""
    try:
        return FORMATS[name]
    except KeyError:
        raise KeyError(f"no file format {name!r} (known: {', '.join(FORMATS)})") from None
