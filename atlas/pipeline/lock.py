"""One writer per output: an exclusive ``flock`` on ``<output>.lock``, removed when the run ends.

The kernel releases a ``flock`` when its process ends, however it ends (exit, crash,
``kill -9``, a rebooted machine), so a lock is never stale and there is nothing to take over:
no PID checks, no race between two runs clearing a dead run's lock. The holder's host and PID
are written next to it (``<output>.lock.owner``) for the message a second run gets.

The lock file is removed by its holder before it lets go, so a finished, failed or
interrupted run leaves none behind (only a process killed with SIGKILL leaves one, which the
next run takes and removes). Removing a lock file is safe only with the check that makes the
lock the *file at the path*: a run that opened the file just before its holder removed it
could lock that removed file while a third run creates and locks a new one. So a run that
gets the ``flock`` then checks that the path still names the file it locked (same device and
inode) and otherwise starts over with the file now there (the protocol of, e.g., Linux's
``flock(1)`` users and of lockfile libraries that delete on release).

On a shared cluster file system the lock is as good as the file system's ``flock`` (NFSv4,
Lustre and GPFS forward it to the server); where the file system has none, the run stops
with one line naming the lock file (:class:`~atlas.errors.StorageError`).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import os
import socket
from pathlib import Path

from atlas.errors import EnvironmentFailure, StorageError

__all__ = ["output_lock", "lock_path", "OutputLocked", "EXIT_LOCKED"]

#: Exit status of a run refused because another run holds the output's lock.
EXIT_LOCKED = 3


class OutputLocked(EnvironmentFailure):
    """Another atlas run is writing the same output (an environment failure: exit 3)."""

    exit_code = EXIT_LOCKED


def lock_path(output: Path) -> Path:
    """The lock file of ``output``: ``<output>.lock``, present only while a run holds it."""
    return output.with_name(output.name + ".lock")


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


def _is_at(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the open file ``fd`` (same device and inode)."""
    try:
        there = os.stat(path)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (mine.st_dev, mine.st_ino) == (there.st_dev, there.st_ino)


def _acquire(path: Path, output: Path, sidecar: Path) -> int:
    """The open, ``flock``-ed descriptor of the lock file at ``path``; OutputLocked at once if
    another process holds it."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise OutputLocked(f"{output}: another atlas run ({_owner(sidecar)}) is "
                                   "writing this output; wait for it to finish") from None
            raise StorageError(f"{path}: cannot lock the output ({os.strerror(exc.errno)}); "
                               "write it on a file system with flock") from None
        if _is_at(fd, path):
            return fd
        os.close(fd)  # we locked a file its holder removed meanwhile: lock the one there now


@contextlib.contextmanager
def output_lock(output: Path):
    """Hold ``<output>.lock`` for the duration of the block and remove it at the end; refuse
    at once (:class:`OutputLocked`) if another run holds it."""
    path = lock_path(output)
    sidecar = output.with_name(output.name + ".lock.owner")
    fd = _acquire(path, output, sidecar)
    try:
        _write_owner(sidecar)
        yield
    finally:
        sidecar.unlink(missing_ok=True)
        with contextlib.suppress(OSError):
            path.unlink()  # while still holding it: see the module docstring
        os.close(fd)  # releases the flock
