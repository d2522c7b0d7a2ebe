"""Ctrl-C and SIGTERM in a run: they take effect at once, whatever is computing (no pool that
waits for its calls in flight), and the run says what it kept: its finished tiles, or that
none was finished."""

from __future__ import annotations

import subprocess
import sys
import threading

import pytest

import atlas
from atlas.pipeline.schedule import each_in_background
from atlas.pipeline.sweep import kept_after_interrupt, layout_of
from atlas.store.partial import partial_path
from tests.helpers import REPO, SMALL, crash_on_tile, write_config


def test_each_in_background_gives_every_result_in_order_a_few_at_a_time():
    lock, running, most = threading.Lock(), [0], [0]

    def square(x):
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
        try:
            return x * x
        finally:
            with lock:
                running[0] -= 1

    assert list(each_in_background(square, range(20), 3)) == [x * x for x in range(20)]
    assert 1 <= most[0] <= 3


def test_each_in_background_keeps_every_worker_busy_behind_a_slow_call():
    """A free worker takes the next call whatever results are still to be taken in order:
    behind a slow first call, the other worker runs the fast ones meanwhile (taking the
    results in order before starting the next call left it idle: a study ran 6 % longer)."""
    import time

    first_done, started_while_first_ran = threading.Event(), []

    def call(x):
        if x == 0:
            time.sleep(0.5)
            first_done.set()
        else:
            started_while_first_ran.append(not first_done.is_set())
        return x

    assert list(each_in_background(call, range(6), 2)) == list(range(6))
    assert all(started_while_first_ran) and len(started_while_first_ran) == 5


def test_each_in_background_raises_a_calls_error_in_its_turn():
    def fails_at_3(x):
        if x == 3:
            raise ValueError("three")
        return x

    results = each_in_background(fails_at_3, range(6), 2)
    assert [next(results) for _ in range(3)] == [0, 1, 2]
    with pytest.raises(ValueError, match="three"):
        next(results)


#: First in each child below: SIGINT handled and not blocked, as a terminal gives it,
#: whatever the test process left it with (a pytest started in the background ignores it,
#: and an earlier test in the same worker can leave it blocked; a child inherits both).
_AS_ON_A_TERMINAL = """\
import signal
signal.signal(signal.SIGINT, signal.default_int_handler)
signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
"""

#: A process that maps (CALL) a call that never returns, and is sent SIGINT while the call
#: runs: it must leave, through KeyboardInterrupt and the interpreter's normal exit, with the
#: call still in flight. Under a ThreadPoolExecutor it would wait for that call for ever.
_STUCK = _AS_ON_A_TERMINAL + """\
import os, signal, threading
from atlas.pipeline.schedule import each_in_background, point_results

started = threading.Event()

def never_returns(*item):
    started.set()
    threading.Event().wait()

def interrupt():
    started.wait()
    os.kill(os.getpid(), signal.SIGINT)

threading.Thread(target=interrupt, daemon=True).start()
try:
    list(CALL)
except KeyboardInterrupt:
    print("interrupted while a call was in flight:", started.is_set())
"""


@pytest.mark.parametrize("call", [
    "each_in_background(never_returns, range(4), 2)",
    "point_results(never_returns, [(i,) for i in range(16)], workers=2)",  # a study's points
], ids=["each_in_background", "point_results"])
def test_ctrl_c_leaves_the_calls_in_flight(call):
    proc = subprocess.run([sys.executable, "-c", _STUCK.replace("CALL", call)], cwd=REPO,
                          capture_output=True, text=True, timeout=600)  # a hang: never ends
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "interrupted while a call was in flight: True"


def _small(tmp_path):
    return atlas.load_config(write_config(tmp_path / "c.yaml", SMALL.format(
        sep="false", output=tmp_path / "x.h5")))


@pytest.mark.parametrize("call,finished", [(1, 0), (3, 2)])
def test_an_interrupted_run_says_how_many_tiles_it_kept(tmp_path, monkeypatch, call, finished):
    """Stopped in its first tile, a run has kept nothing and says so (it said "finished tiles
    are kept" all the same); stopped in its third, it counts the two it kept."""
    cfg = _small(tmp_path)
    crash_on_tile(monkeypatch, call, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        atlas.run(cfg, quiet=True)
    total = layout_of(cfg).n_tiles
    assert total > 3
    said = kept_after_interrupt(cfg.output)
    if finished:
        assert said.startswith(f"{finished} of {total} tiles are finished and kept in "
                               f"{partial_path(cfg.output)};")
    else:
        assert said.startswith("no tile was finished;")


def test_a_run_stopped_before_its_partial_run_existed_kept_nothing(tmp_path):
    assert kept_after_interrupt(tmp_path / "never.h5").startswith("no tile was finished;")
    (tmp_path / "odd.h5.partial").write_text("not a folder")
    assert kept_after_interrupt(tmp_path / "odd.h5").startswith("no tile was finished;")


#: ``atlas run`` whose exact boundaries never return, sent SIGINT while they compute.
_RUN_STUCK = _AS_ON_A_TERMINAL + """\
import os, signal, sys, threading
from atlas.boundaries import exact

started = threading.Event()

def never_returns(*args, **kwargs):
    started.set()
    threading.Event().wait()

exact.exact_boundaries = never_returns
threading.Thread(target=lambda: (started.wait(), os.kill(os.getpid(), signal.SIGINT)),
                 daemon=True).start()
from atlas.cli import main
sys.exit(main(["run", sys.argv[1], "--quiet"]))
"""


def test_ctrl_c_while_a_point_computes_stops_the_run_at_once(tmp_path):
    """Ctrl-C in a run's first seconds (the exact boundaries, the separatrices, the kernels'
    first compilation) took effect only once the point in flight was done (half a minute
    and more on a busy machine, for ever here) and then said "finished tiles are kept"."""
    config = write_config(tmp_path / "c.yaml", SMALL.format(sep="true",
                                                            output=tmp_path / "x.h5"))
    proc = subprocess.run([sys.executable, "-c", _RUN_STUCK, config],
                          cwd=REPO, capture_output=True, text=True, timeout=600)  # a hang
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr.strip() == ("atlas: interrupted; no tile was finished; run the same "
                                   "command again to start over")


def test_a_signal_inside_a_compiled_kernel_is_an_interruption(tmp_path, monkeypatch, capsys):
    """Ctrl-C while a Numba kernel calls back into Python comes out of the kernel as a
    SystemError caused by the KeyboardInterrupt (seen about one Ctrl-C in five during a torque
    run's first seconds: a 72-line traceback and exit 1): the CLI says "interrupted" in one
    line and exits 130 (143 for SIGTERM), as for any Ctrl-C; another SystemError stays one."""
    from atlas.cli import main
    from atlas.errors import Terminated
    from atlas.models.pendulum import points

    def from_a_kernel(signal_error):
        def running_certificates(*args, **kwargs):
            try:
                raise signal_error
            except KeyboardInterrupt as exc:
                raise SystemError("CPUDispatcher(<function integrate>) returned a result "
                                  "with an exception set") from exc
        return running_certificates

    cfg = write_config(tmp_path / "c.yaml", SMALL.format(sep="false", output=tmp_path / "x.h5"))
    for error, code, word in ((KeyboardInterrupt(), 130, "interrupted"),
                              (Terminated(), 143, "terminated (SIGTERM)")):
        monkeypatch.setattr(points, "running_certificates", from_a_kernel(error))
        assert main(["run", str(cfg), "--quiet"]) == code
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"atlas: {word}; no tile was finished")

    def plain(*args, **kwargs):
        raise SystemError("a real one")

    monkeypatch.setattr(points, "running_certificates", plain)
    with pytest.raises(SystemError, match="a real one"):
        main(["run", str(cfg), "--quiet"])


CTRL_C_TO_ANOTHER_THREAD = r"""
import os, signal, sys, threading, time
signal.signal(signal.SIGINT, signal.default_int_handler)
from atlas.pipeline.schedule import each_in_background

go = threading.Event()

def killer():  # started before the main thread blocks SIGINT: the one thread that takes it
    go.wait()
    time.sleep(0.3)
    os.kill(os.getpid(), signal.SIGINT)

threading.Thread(target=killer, daemon=True).start()
signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})  # workers inherit the block
go.set()
try:
    list(each_in_background(lambda item: threading.Event().wait(), [1, 2], 2))
except KeyboardInterrupt:
    print("interrupted")
    sys.exit(0)
"""


def test_ctrl_c_delivered_to_another_thread_still_interrupts_the_wait():
    """A process-directed SIGINT may be delivered to any thread not blocking it (under load,
    a worker's or Numba's); the main thread, blocked waiting for a point that never finishes,
    must still see it (it waits in slices: atlas.pipeline.schedule.waited). Before, it waited
    forever (the suite's Ctrl-C test hung under load)."""
    proc = subprocess.run([sys.executable, "-c", CTRL_C_TO_ANOTHER_THREAD],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and proc.stdout.strip() == "interrupted", proc.stderr
