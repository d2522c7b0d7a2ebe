"""One writer per output: an exclusive ``flock`` on ``<output>.lock`` (the ``filelock`` package).

The kernel releases the lock when its process ends, however it ends (exit, crash, ``kill -9``,
a rebooted machine), so a lock is never stale and there is nothing to take over: no PID
checks, no race between two runs clearing a dead run's lock. The lock file stays in place
(removing it would let two runs lock two different files); the holder's host and PID are
written next to it (``<output>.lock.owner``) for the message a second run gets.

On a shared cluster file system the lock is as good as the file system's ``flock`` (NFSv4,
Lustre and GPFS forward it to the server; on a file system without ``flock`` filelock falls
back to its own soft lock).
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
from pathlib import Path

from filelock import FileLock, Timeout

from atlas.errors import AtlasError

__all__ = ["output_lock", "OutputLocked", "EXIT_LOCKED"]

#: Exit status of a run refused because another run holds the output's lock.
EXIT_LOCKED = 3


class OutputLocked(AtlasError):
    """Another atlas run is writing the same output (an environment failure: exit 3)."""

    exit_code = EXIT_LOCKED


def _owner(sidecar: Path) -> str:
    try:
        who = json.loads(sidecar.read_text())
        return f"host {who['host']}, pid {who['pid']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "host ?, pid ?"


def _write_owner(sidecar: Path) -> None:
    """Record who holds the lock; only informative, so a failure (disk full) is ignored."""
    tmp = sidecar.with_name(f".{sidecar.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(json.dumps({"host": socket.gethostname(), "pid": os.getpid()}))
        os.replace(tmp, sidecar)
    except OSError:
        tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def output_lock(output: Path):
    """Hold ``<output>.lock`` for the duration of the block; refuse at once if another run
    holds it."""
    path = output.with_name(output.name + ".lock")
    sidecar = output.with_name(output.name + ".lock.owner")
    lock = FileLock(path, timeout=0)
    try:
        lock.acquire()
    except Timeout:
        raise OutputLocked(f"{output}: another atlas run ({_owner(sidecar)}) is writing this "
                           "output; wait for it to finish") from None
    try:
        _write_owner(sidecar)
        yield
    finally:
        sidecar.unlink(missing_ok=True)
        lock.release()
