"""Jobs run by forks of this process: a worker warms up while this process prepares the jobs,
then runs them on every core at once. ``atlas plot`` draws its figures this way
(:func:`atlas.views.plotting.plot_file`): the worker imports matplotlib and draws a small figure
while the reader opens and reads the file, so the two costs (a few tenths of a second each)
overlap.

The worker (:class:`ForkedJobs`) is a fork in its own process group, so that closing it ends
it and its own forks at once; it runs nothing unless sent the jobs. The jobs travel through a
pipe, pickled (functions by reference: the fork has the same modules); the answer is the first
exception raised, with its traceback there as the cause of the one raised here
(:class:`ForkTraceback`). Linux only (``fork`` is safe there); elsewhere the caller runs the
jobs itself.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
from collections.abc import Callable

__all__ = ["ForkedJobs", "ForkTraceback", "can_fork"]


def can_fork() -> bool:
    """Whether jobs may be run by forks here (Linux)."""
    return sys.platform.startswith("linux")


class ForkTraceback(Exception):
    """The traceback (text) of an exception raised in a forked process: the cause of the
    exception re-raised here."""

    def __str__(self) -> str:
        return "\n" + self.args[0]


class ForkedJobs:
    """A fork of this process that calls ``warm_up()`` at once, then waits for the jobs,
    runs ``run(job)`` for each in ``processes`` processes at once (itself and forks of it,
    the i-th job in process i mod n) and answers with the first exception raised (None if
    none)."""

    @classmethod
    def start(cls, warm_up: Callable[[], None], run: Callable, processes: int
              ) -> ForkedJobs | None:
        """The worker, started; None if it cannot be (no process or no pipe to spare: the
        caller then runs the jobs itself)."""
        try:
            return cls(warm_up, run, processes)
        except OSError:
            return None

    def __init__(self, warm_up: Callable[[], None], run: Callable, processes: int):
        jobs_r, jobs_w = os.pipe()
        answer_r, answer_w = os.pipe()
        try:
            self.pid = os.fork()
        except OSError:
            for fd in (jobs_r, jobs_w, answer_r, answer_w):
                os.close(fd)
            raise
        if self.pid == 0:  # pragma: no cover - runs in the fork
            os.close(jobs_w)
            os.close(answer_r)
            _worker(jobs_r, answer_w, warm_up, run, processes)
        os.close(jobs_r)
        os.close(answer_w)
        with contextlib.suppress(ProcessLookupError, PermissionError):  # or the child did
            os.setpgid(self.pid, self.pid)
        self._jobs, self._answer = os.fdopen(jobs_w, "wb"), os.fdopen(answer_r, "rb")
        self._answered = False

    def run(self, jobs: list) -> None:
        """Run ``jobs`` in the worker; raises the first exception raised in running them
        (with its traceback there as the cause)."""
        try:
            pickle.dump(jobs, self._jobs, pickle.HIGHEST_PROTOCOL)
            self._jobs.close()
            answer = pickle.load(self._answer)
        except (BrokenPipeError, EOFError):
            answer = _answer_of(RuntimeError("the worker process ended without answering"))
        self._answered = True
        if answer is not None:
            error, traceback = answer
            raise error from ForkTraceback(traceback)

    def close(self) -> None:
        """End the worker and its forks (at once unless they answered) and reap it."""
        self._jobs.close()
        self._answer.close()
        if not self._answered:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.pid, signal.SIGKILL)
        os.waitpid(self.pid, 0)


def _worker(jobs_fd: int, answer_fd: int, warm_up, run, processes: int
            ):  # pragma: no cover - runs in the fork
    """The life of the worker (it ends here): warm up, read the jobs from ``jobs_fd`` (none:
    the caller failed before sending them), run them, answer on ``answer_fd``."""
    code = 1
    try:
        os.setpgid(0, 0)
        signal.signal(signal.SIGINT, signal.SIG_DFL)  # ended by the caller, not by Ctrl-C
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.signal(signal.SIGTTOU, signal.SIG_IGN)  # a background group may still warn
        answer = None
        try:
            warm_up()
        except Exception as exc:  # the same will fail in the jobs: answer it then
            answer = _answer_of(exc)
        with os.fdopen(jobs_fd, "rb") as f:
            try:
                jobs = pickle.load(f)
            except EOFError:  # the caller failed: nothing to run
                code = 0
                return
        answer = answer or _run_all(jobs, run, processes)
        with os.fdopen(answer_fd, "wb") as f:
            f.write(pickle.dumps(answer, pickle.HIGHEST_PROTOCOL))
        code = 0
    finally:
        os._exit(code)


def _run_all(jobs: list, run, processes: int) -> tuple | None:
    """``run`` every job in n = min(jobs, ``processes``) processes at once, this one and
    n − 1 forks of it, the i-th job in process i mod n; returns :func:`_answer_of` the first
    exception raised, None if none."""
    n = min(len(jobs), processes)
    forks = []
    for i in range(1, n):
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - runs in the fork
            try:
                os.close(r)
                with os.fdopen(w, "wb") as f:
                    f.write(pickle.dumps(_run_share(jobs[i::n], run), pickle.HIGHEST_PROTOCOL))
            finally:
                os._exit(0)
        os.close(w)
        forks.append((pid, r))
    answers = [_run_share(jobs[0::n], run)]
    for pid, r in forks:
        with os.fdopen(r, "rb") as f:
            data = f.read()
        os.waitpid(pid, 0)
        answers.append(pickle.loads(data) if data else
                       _answer_of(RuntimeError("a worker process ended without answering")))
    return next((answer for answer in answers if answer is not None), None)


def _run_share(jobs: list, run) -> tuple | None:
    """``run`` the jobs one after the other; :func:`_answer_of` the exception raised, if any."""
    try:
        for job in jobs:
            run(job)
    except Exception as exc:
        return _answer_of(exc)
    return None


def _answer_of(exc: Exception) -> tuple[Exception, str]:
    """(``exc``, its traceback as text), as sent back from a forked process: ``exc`` itself
    where it pickles (an OSError keeps its errno and file name), else a RuntimeError naming
    it."""
    import traceback

    text = "".join(traceback.format_exception(exc))
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        exc = RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc, text
