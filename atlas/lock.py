"""One writer per output: an exclusive lock file ``<output>.lock`` holding the writer's PID.

A lock whose process is gone (killed, crashed, machine rebooted) is stale and is taken over,
so a dead run never blocks the next one.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from .errors import AtlasError

__all__ = ["output_lock", "OutputLocked"]


class OutputLocked(AtlasError):
    """Another live atlas process is writing the same output."""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def _holder(lock: Path) -> int | None:
    try:
        return int(lock.read_text().strip() or "0") or None
    except (OSError, ValueError):
        return None


def _try_lock(lock: Path) -> bool:
    """Atomically create ``lock`` already holding our PID: write a private file, then
    hard-link it into place (link fails if the lock exists), so no other process ever sees
    a lock without its PID."""
    tmp = lock.with_name(f"{lock.name}.{os.getpid()}.tmp")
    tmp.write_text(str(os.getpid()))
    try:
        os.link(tmp, lock)
        return True
    except FileExistsError:
        return False
    finally:
        tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def output_lock(output: Path):
    """Hold ``<output>.lock`` for the duration of the block; refuse if a live run holds it."""
    lock = output.with_name(output.name + ".lock")
    for _ in range(2):
        if _try_lock(lock):
            break
        pid = _holder(lock)
        if pid is not None and _alive(pid):
            raise OutputLocked(f"{output}: another atlas run (pid {pid}) is writing this "
                               f"output; wait for it or remove {lock} if it is stale")
        lock.unlink(missing_ok=True)  # stale: its writer is gone (or the file is unreadable)
    else:
        raise OutputLocked(f"{output}: could not take the lock {lock}")
    try:
        yield
    finally:
        if _holder(lock) == os.getpid():
            lock.unlink(missing_ok=True)
