"""What each command writes, and what it may write over.

Every file an atlas command writes is of one :class:`Kind`: an atlas (``atlas run``), a study
(``atlas stability``), a figure (``atlas plot``, ``atlas orbit``, ``atlas figures``), a page
(``atlas view``), a config (``atlas zoom -o``) or a benchmark table (``atlas bench``). A kind
has the suffixes its files are written with and a test that recognises a file of that kind
that atlas wrote. Before a command writes anything, it asks :func:`check_output` of every
path it will write, and is refused, in one line, where a path

* is one of the command's own inputs (``atlas plot q.png`` of an atlas called ``q.png``);
* does not end in one of its kind's suffixes (``atlas run -o q.png``: ``atlas plot`` would
  later write the basin map over the atlas itself);
* holds a file that atlas did not write as that kind of output (a photo where the basin map
  goes, an atlas where the page goes), unless the command was told ``--force`` where it
  offers it.

So no command writes over its input, or over anything but its own earlier output of the same
kind, by the same command: figures carry their maker and the command that drew them in their
metadata (:func:`figure_metadata`: PNG ``Software``, SVG and PDF ``Creator``), so ``atlas orbit
-o NAME.png`` does not write over the basin map ``atlas plot`` drew there, nor the reverse.
Figures that ``atlas plot`` and ``atlas figures`` wrote at their fixed names before atlas
marked them are recognised as matplotlib's (every atlas figure is drawn by matplotlib).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from atlas.errors import OutputInTheWay

__all__ = ["Kind", "KINDS", "check_output", "check_suffix", "figure_metadata", "MAKER"]

#: The maker recorded in every figure atlas writes (:func:`figure_metadata`); the
#: distribution's name, which no other program writes there.
MAKER = "pendulum-atlas"
#: Bytes of a file read to recognise it (a figure's metadata comes first in a PNG; SVG and
#: PDF figures of atlas are at most a few MB, read whole up to this size).
_HEAD_BYTES = 1 << 26
#: The commands whose figures have fixed names (next to the atlas, or in the figures' folder),
#: where a figure written before atlas marked its figures (matplotlib's) is taken as theirs.
_FIXED_NAMES = ("atlas plot", "atlas figures")
#: The first bytes of each figure format.
_MAGIC = {".png": (b"\x89PNG\r\n\x1a\n",), ".pdf": (b"%PDF",), ".svg": (b"<?xml", b"<svg")}


def _read(path: Path, size: int = _HEAD_BYTES) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read(size)
    except OSError:
        return b""


def _is_atlas(path: Path) -> bool:
    from atlas.store.reader import is_atlas_file

    return is_atlas_file(path)


def _is_study(path: Path) -> bool:
    from atlas.store.study import is_study_file

    return is_study_file(path)


def _is_figure(path: Path, command: str | None = None) -> bool:
    """A figure atlas wrote (by ``command`` where given): the magic number of its suffix's
    format, and atlas's mark (:func:`figure_metadata`) naming the command; or, for figures
    written before atlas marked them, matplotlib as its maker, where ``command`` is one of
    :data:`_FIXED_NAMES` (or None)."""
    data = _read(path)
    magic = _MAGIC.get(path.suffix.lower())
    if magic is None or not data.lstrip().startswith(magic):
        return False
    if MAKER.encode() in data:
        return command is None or f"({command})".encode() in data
    return (command is None or command in _FIXED_NAMES) and b"matplotlib" in data.lower()


def _is_page(path: Path) -> bool:
    """A page of ``atlas view``: HTML holding the atlas's data block."""
    data = _read(path)
    return data.lstrip().lower().startswith(b"<!doctype html") and b'id="atlas-data"' in data


def _is_zoom_config(path: Path) -> bool:
    """A config ``atlas zoom -o`` wrote: its first line is the command that made it."""
    return _read(path, 64).startswith(b"# atlas zoom ")


def _is_bench(path: Path) -> bool:
    """A table of ``atlas bench``: a JSON object with its machine or its GPU rows."""
    try:
        data = json.loads(_read(path).decode())
    except (UnicodeDecodeError, ValueError):
        return False
    return isinstance(data, dict) and bool({"machine", "gpu"} & set(data))


@dataclass(frozen=True)
class Kind:
    """One kind of file atlas writes: ``what`` names it in messages, ``names`` are the
    suffixes it is written with (lower case), or a function giving them (read on first use:
    the formats' table imports their libraries, which a command that only draws need not
    load before it forks), ``recognises`` tells a file of this kind that atlas wrote."""

    what: str
    names: tuple[str, ...] | Callable[[], tuple[str, ...]]
    recognises: Callable[[Path], bool]

    @property
    def suffixes(self) -> tuple[str, ...]:
        return self.names() if callable(self.names) else self.names


def _atlas_suffixes() -> tuple[str, ...]:
    from atlas.store.formats import FORMATS

    return tuple(s for fmt in FORMATS.values() for s in fmt.suffixes)


#: Every kind of file atlas writes, by name.
KINDS: dict[str, Kind] = {
    "atlas": Kind("an atlas", _atlas_suffixes, _is_atlas),
    "study": Kind("a study", _atlas_suffixes, _is_study),
    "figure": Kind("a figure", (".png", ".svg", ".pdf"), _is_figure),
    "page": Kind("a page", (".html", ".htm"), _is_page),
    "config": Kind("a config", (".yaml", ".yml"), _is_zoom_config),
    "bench": Kind("a benchmark table", (".json",), _is_bench),
}


def _what_is(path: Path) -> str:
    """What is at ``path``, for a refusal: "an atlas file", "a stability study file", … of
    the kinds atlas writes, else "a folder" or "a file that atlas did not write"."""
    for name in ("atlas", "study", "figure", "page"):
        if KINDS[name].recognises(path):
            return f"{KINDS[name].what} file" if name in ("atlas", "study") else \
                f"{KINDS[name].what} of atlas"
    return "a folder" if path.is_dir() else "a file that atlas did not write"


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(os.path.abspath(a)) == Path(os.path.abspath(b))


def check_output(path: str | Path, kind: str, *, inputs: Iterable[str | Path] = (),
                 force: bool = False, option: str = "-o", command: str | None = None) -> None:
    """Refuse (:class:`~atlas.errors.OutputInTheWay`, one line, exit status 2) to write a
    file of ``kind`` (a key of :data:`KINDS`) at ``path`` where it is one of ``inputs``
    (whatever ``force`` says), lacks the kind's suffix, or holds something other than a
    file of that kind that atlas wrote (by ``command``, for a figure: "atlas plot", "atlas
    orbit", "atlas figures"; unless ``force``); ``option`` is the command-line option that
    names the path, for the hint. Nothing is created."""
    path, spec = Path(path), KINDS[kind]
    for source in inputs:
        if _same(path, Path(source)):
            raise OutputInTheWay(f"{path}: {spec.what} would be written over the input "
                                 f"file itself, {_what_is(path)}; name another output with "
                                 f"{option}")
    if path.is_dir() and kind not in ("atlas", "study"):  # those may be Zarr stores
        raise OutputInTheWay(f"{path}: the output path is a directory; name a file with "
                             f"{option}")
    check_suffix(path, kind, option)
    if force or not (path.exists() or path.is_symlink()):
        return
    if kind == "figure" and command is not None and spec.recognises(path) \
            and not _is_figure(path, command):
        raise OutputInTheWay(f"{path}: a figure of another atlas command is in the way of "
                             f"{command}'s; move it, or name another output with {option}")
    if not spec.recognises(path):
        hint = " (--force writes over it)" if kind in ("atlas", "study") else ""
        raise OutputInTheWay(f"{path}: {_what_is(path)} is in the way of {spec.what}; move "
                             f"it, or name another output with {option}{hint}")


def check_suffix(path: str | Path, kind: str, option: str = "-o") -> None:
    """Refuse (:class:`~atlas.errors.OutputInTheWay`) a name for a file of ``kind`` that
    does not end in one of the kind's suffixes: another command would take it for a file of
    its own kind (``atlas run -o q.png``: ``atlas plot`` would write the basin map over it)."""
    path, spec = Path(path), KINDS[kind]
    if path.suffix.lower() not in spec.suffixes:
        names = ", ".join("NAME" + s for s in spec.suffixes)
        got = f"'{path.suffix}'" if path.suffix else "a name without a suffix"
        raise OutputInTheWay(f"{path}: {spec.what} is written as {names}, not {got} (another "
                             f"atlas command could write over it); name it with {option}")


def figure_metadata(suffix: str, command: str) -> dict[str, str]:
    """The metadata that marks a figure as drawn by atlas's ``command`` ("atlas plot", …),
    for matplotlib's ``savefig(metadata=…)`` in the format of ``suffix`` (.png:
    ``Software``; .svg and .pdf: ``Creator``)."""
    from atlas._version import __version__

    maker = f"{MAKER} {__version__} ({command})"
    return {"Software": maker} if suffix.lower() == ".png" else {"Creator": maker}
