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


@contextlib.contextmanager
def output_lock(output: Path):
    """Hold ``<output>.lock`` for the duration of the block; refuse if a live run holds it."""
    lock = output.with_name(output.name + ".lock")
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            break
        except FileExistsError:
            pid = _holder(lock)
            if pid is not None and pid != os.getpid() and _alive(pid):
                raise OutputLocked(f"{output}: another atlas run (pid {pid}) is writing this "
                                   f"output; wait for it or remove {lock} if it is stale"
                                   ) from None
            lock.unlink(missing_ok=True)  # stale: its writer is gone
    else:
        raise OutputLocked(f"{output}: could not take the lock {lock}")
    try:
        os.write(fd, str(os.getpid()).encode())
        os.close(fd)
        yield
    finally:
        lock.unlink(missing_ok=True)
