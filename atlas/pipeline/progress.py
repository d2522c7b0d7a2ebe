"""What a run says while it works: a progress bar for each long phase (the exact boundaries,
the separatrices, the certificates, the tiles) and a line when Numba compiles kernels.

All of it goes to stderr, and only where someone watches: never with ``--quiet``, and on a
stream that is not a terminal (a log file, a pipe) only with ``-v`` (the ``atlas`` logger at
INFO). The bars are tqdm's, cleared when their phase ends (the ``-v`` log keeps each phase's
time). Warnings are not progress: they are logged whatever ``--quiet`` says.
"""

from __future__ import annotations

import contextlib
import logging
import sys
from collections.abc import Iterable, Iterator

__all__ = ["watched", "bar", "tracked", "say", "compile_notice", "COMPILING"]

log = logging.getLogger("atlas.pipeline")

#: The line said when Numba compiles a kernel whose cache was cold or stale.
COMPILING = "atlas: compiling kernels (first run only)…"


def watched(quiet: bool) -> bool:
    """Whether progress is shown: not ``quiet``, and stderr a terminal or ``-v`` asked."""
    return not quiet and (sys.stderr.isatty() or log.isEnabledFor(logging.INFO))


def bar(total: int, desc: str, unit: str, quiet: bool, initial: int = 0):
    """A tqdm bar on stderr for ``total`` ``unit``s of the phase ``desc`` (disabled where
    :func:`watched` says no); off a terminal it redraws every 5 s, not 10 times a second."""
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit=unit, unit_scale=unit == "orbit",
                smoothing=0.1, disable=not watched(quiet), leave=False, file=sys.stderr,
                mininterval=0.1 if sys.stderr.isatty() else 5.0)


def tracked(items: Iterable, total: int, desc: str, quiet: bool,
            unit: str = "point") -> Iterator:
    """``items`` (``total`` of them), with a bar that advances as each is taken."""
    with bar(total, desc, unit, quiet) as b:
        for item in items:
            yield item
            b.update()


def say(line: str) -> None:
    """One line on stderr that does not tear a bar being drawn."""
    from tqdm import tqdm

    tqdm.write(line, file=sys.stderr)


@contextlib.contextmanager
def compile_notice(quiet: bool):
    """Within the block, say :data:`COMPILING` once, when Numba first compiles one of atlas's
    cached kernels (:func:`atlas.kernels.on_cold_compile`), if progress is :func:`watched`;
    the kernels compiled are named at ``-vv``."""
    if not watched(quiet):
        yield
        return
    from atlas.kernels import on_cold_compile

    said = []

    def notice(name: str) -> None:
        if not said:
            said.append(name)
            say(COMPILING)
        log.debug("compiling %s", name)

    with on_cold_compile(notice):
        yield
