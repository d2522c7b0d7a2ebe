"""Faults: disk full mid-run, Ctrl-C, SIGTERM, a second writer, locks of dead runs, racing
lockers, unwritable outputs.

Each runs the real CLI in a subprocess where the behaviour is about exit status, messages
and files."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import atlas
from atlas.store.reader import describe
from tests.helpers import REPO, lock_is_free, run_cli, write_config

pytestmark = pytest.mark.slow  # every test runs atlas in subprocesses and waits

SLOW = """\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 48}}
  theta_dot0: {{start: -4, stop: 4, num: 160}}
integrator: {{t_max: 200, dt: {dt}}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 48}}
output: {output}
"""
#: The same orbits' window in 48 rows (48 tiles): for the faults that need many tiles and an
#: assembled file larger than a tile, not 160 of them (each tile costs a durable write).
TILES_48 = SLOW.replace("num: 160", "num: 48")
#: The step [s] of a SLOW run that must still be running when the test acts on it (a signal,
#: a second writer) after its 5th tile: at dt = 0.001 s its 160 tiles took 1.3–1.6 s in all,
#: and a test process descheduled that long on a loaded machine (the full suite on 2 cores)
#: saw the run finish first (exit 0 instead of 130); at 5e-5 s they take some 10 s (the test
#: stops the run after its 5th tile, about a third of a second).
_STILL_RUNNING_DT = 5e-5


def _interruptible():
    """In the child before ``exec``: SIGINT at its default disposition and not blocked, as a
    terminal gives it, whatever the test process was left with (a test run earlier in the
    same pytest worker can leave SIGINT ignored or blocked, and a child inherits both: in a
    full suite such a run once ignored the SIGINT sent 8 s before it finished)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})


def _start(cfg, *extra):
    """Start ``atlas run -vv`` and return the process once it has written 5 tiles."""
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "atlas.cli", "run", "-vv", str(cfg),
                             "--quiet", *extra], env=env, cwd=REPO, stderr=subprocess.PIPE,
                            text=True, preexec_fn=_interruptible)
    for line in proc.stderr:
        if "tile 5 of 160 written" in line:
            return proc
    raise AssertionError("the run ended before writing 5 tiles")


def _labels(path):
    ds = atlas.open(path).to_dataset(inherit=False)
    return [ds[n].values for n in ("attractor", "status", "t_trap")]


def _reference(cfg, output):
    """The clean result of the config file ``cfg`` written to ``output``, computed here (the
    runs under test go through the CLI; their reference need not pay for another process)."""
    atlas.run(atlas.load_config(cfg, output=output), quiet=True)
    return output


def _one_line(proc, code, *fragments):
    assert proc.returncode == code, proc.stderr
    lines = [ln for ln in proc.stderr.strip().splitlines() if not ln.startswith("atlas: tile")]
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_disk_full_mid_run_keeps_finished_tiles_resumable(tmp_path):
    out = tmp_path / "full.h5"
    cfg = write_config(tmp_path / "c.yaml", TILES_48.format(dt=0.01, output=out))
    script = textwrap.dedent(f"""
        import errno, sys
        from atlas.store.partial import TileStore
        from atlas.cli import main
        real, calls = TileStore.write, []
        def full_disk(*args):
            calls.append(1)
            if len(calls) == 4:
                raise OSError(errno.ENOSPC, "No space left on device")
            real(*args)
        TileStore.write = full_disk
        sys.exit(main(["run", {str(cfg)!r}, "--quiet"]))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=REPO)
    _one_line(proc, 1, "No space left on device", "run the same command again",
              "full.h5.partial")
    assert not out.exists()
    assert describe(out.with_name("full.h5.partial"))["tiles_done"] == 3
    resumed = run_cli("run", cfg, "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming" in resumed.stderr and "3 of 48 tiles already done" in resumed.stderr
    for a, b in zip(_labels(out), _labels(_reference(cfg, tmp_path / "ref.h5"))):
        np.testing.assert_array_equal(a, b)


def _limit_file_size(n_bytes):
    def limit():
        import resource

        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails: EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (n_bytes, n_bytes))

    return limit


def test_a_real_write_failure_while_assembling_keeps_every_tile(tmp_path):
    """A file-size limit that the small tile files fit under but the assembled file does
    not: the kernel refuses the write (EFBIG), the run stops with one line and exit 1, every
    tile is kept, and the next run without the limit gives the clean result."""
    out = tmp_path / "big.h5"
    cfg = write_config(tmp_path / "c.yaml", TILES_48.format(dt=0.01, output=out))
    # the reference first: it also fills Numba's kernel cache, whose files would not fit
    # under the limit (a cold cache would fail the first tile, not the assembly)
    assert run_cli("run", cfg, "--quiet", "-o", tmp_path / "ref.h5").returncode == 0
    proc = subprocess.run([sys.executable, "-m", "atlas.cli", "run", str(cfg), "--quiet"],
                          capture_output=True, text=True, cwd=REPO,
                          preexec_fn=_limit_file_size(20_000))
    _one_line(proc, 1, "big.h5.partial", "File too large", "tiles finished before it are kept")
    assert not out.exists() and describe(out.with_name("big.h5.partial"))["tiles_done"] == 48
    assert run_cli("run", cfg, "--quiet").returncode == 0
    for a, b in zip(_labels(out), _labels(tmp_path / "ref.h5")):
        np.testing.assert_array_equal(a, b)


def test_a_real_full_disk_mid_run(tmp_path):
    """The output on a 64 KiB tmpfs (a private mount namespace): the disk fills up after some
    tiles; exit 1 with one line; the tmpfs is enlarged and the next run finishes it, equal to
    a clean run."""
    from tools.faults import _tmpfs_trial, _unshare_works

    if not _unshare_works(tmp_path):
        pytest.skip("unprivileged mount namespaces are not available here")
    cfg = write_config(tmp_path / "c.yaml", TILES_48.format(dt=0.01, output=tmp_path / "x.h5"))
    code, line, recovered = _tmpfs_trial(cfg, tmp_path, 64)
    assert code == 1 and "No space left on device" in line and "kept" in line, line
    assert len(line.splitlines()) == 1 and recovered
    reference = _labels(_reference(cfg, tmp_path / "ref.h5"))
    for a, b in zip(_labels(tmp_path / "full-copy.h5"), reference):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("sig, code, word", [(signal.SIGINT, 130, "interrupted"),
                                             (signal.SIGTERM, 143, "terminated (SIGTERM)")])
def test_ctrl_c_or_sigterm_stops_cleanly_and_keeps_finished_tiles(tmp_path, sig, code, word):
    out = tmp_path / "int.h5"
    cfg = write_config(tmp_path / "c.yaml", SLOW.format(dt=_STILL_RUNNING_DT, output=out))
    proc = _start(cfg)
    proc.send_signal(sig)
    stderr = proc.stderr.read()
    proc.wait()
    assert proc.returncode == code, stderr
    # -vv logs each tile written and each tile's kernel paths ("atlas: label_lanes: ..."),
    # also for the tile computing ahead when the signal came: the rest is the one line
    lines = [ln for ln in stderr.strip().splitlines()
             if not ln.startswith(("atlas: tile", "atlas: label_"))]
    assert len(lines) == 1 and word in lines[0] and "run the same command again" in lines[0]
    partial = out.with_name("int.h5.partial")
    assert not out.exists() and describe(partial)["tiles_done"] >= 5
    assert lock_is_free(out)
    info = run_cli("info", partial)
    assert info.returncode == 0 and "partial" in info.stdout and "of 160 tiles" in info.stdout


def test_a_second_writer_is_refused_while_the_first_runs(tmp_path):
    out = tmp_path / "busy.h5"
    cfg = write_config(tmp_path / "c.yaml", SLOW.format(dt=_STILL_RUNNING_DT, output=out))
    first = _start(cfg)
    try:
        second = run_cli("run", cfg, "--quiet")
        _one_line(second, 3, "another atlas run", f"pid {first.pid})", "host ")
    finally:
        first.kill()
        first.wait()


def test_the_lock_of_a_killed_run_does_not_block(tmp_path):
    """A run killed with SIGKILL while holding the lock (its owner record left behind): the
    kernel released its flock, so the next run takes the lock and finishes."""
    out = tmp_path / "stale.h5"
    cfg = write_config(tmp_path / "c.yaml", TILES_48.format(dt=0.01, output=out))
    holder = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import time
        from pathlib import Path
        from atlas.pipeline.lock import output_lock
        with output_lock(Path({str(out)!r})):
            print("locked", flush=True)
            time.sleep(600)
    """)], stdout=subprocess.PIPE, text=True, cwd=REPO)
    assert holder.stdout.readline().strip() == "locked"
    assert not lock_is_free(out)
    holder.kill()
    holder.wait()
    assert out.with_name("stale.h5.lock.owner").exists()  # the dead run's record
    proc = run_cli("run", cfg, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert out.exists() and lock_is_free(out)


def test_unwritable_output_paths(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    for output, fragment in [(blocker / "out.h5", "is not a directory"),
                             (tmp_path, "is a directory"),
                             ("/proc/atlas/out.h5", "is free on that disk")]:
        cfg = write_config(tmp_path / "c.yaml", SLOW.format(dt=0.01, output=output))
        _one_line(run_cli("run", cfg), 2, str(output), fragment)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file", "c.yaml"]


def test_a_grid_larger_than_the_free_disk_is_refused_before_it_starts(tmp_path):
    cfg = write_config(tmp_path / "c.yaml", f"""\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 1048576}}
  theta_dot0: {{start: -4, stop: 4, num: 1048576}}
output: {tmp_path / 'huge.h5'}
""")
    # 2**40 orbits of 11 bytes each: int16 + int8 + float32 + float32, the file's per-orbit
    # variables (SPEC), uncompressed
    _one_line(run_cli("run", cfg), 2, "huge.h5", "12.1 TB but only", "is free on that disk")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


def test_a_failure_while_finishing_the_file_is_resumable(tmp_path, monkeypatch):
    """Disk full at the very end (groups written, rename failing, or a group failing):
    the output is not written, every tile is kept, and running again finishes it."""
    import errno

    from atlas.errors import StorageError
    from atlas.store import hdf5 as store

    out = tmp_path / "fin.h5"
    cfg = atlas.load_config(write_config(tmp_path / "c.yaml",
                                         TILES_48.format(dt=0.01, output=out)))
    cfg = cfg.model_copy(update={"separatrices": cfg.separatrices.model_copy(
        update={"enabled": True})})

    def no_space(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    real_replace = store.os.replace
    # the clean result, once: both failures below must end in exactly this file
    fresh = atlas.run(cfg.model_copy(update={"output": tmp_path / "ref.h5"}), quiet=True)

    def no_space_for_the_output(src, dst):
        if dst == out:
            no_space()
        real_replace(src, dst)

    for broken in ("os.replace", "groups"):
        with monkeypatch.context() as m:
            if broken == "os.replace":
                m.setattr(store.os, "replace", no_space_for_the_output)
            else:  # writing a group, whichever way the writer hands it to xarray
                m.setattr(store.xr.Dataset, "to_netcdf", no_space)
                m.setattr(store.xr.Dataset, "dump_to_store", no_space)
            try:
                atlas.run(cfg, quiet=True)
            except StorageError as exc:
                assert "No space left on device" in str(exc) and "again" in str(exc)
            else:
                raise AssertionError("the simulated failure did not surface")
        partial = out.with_name("fin.h5.partial")
        info = describe(partial)
        assert not out.exists() and info["tiles_done"] == 48 and not info["complete"]
        tree = atlas.run(cfg, quiet=True)
        assert set(tree.children) == {"critical_points", "separatrices"}
        assert tree.attrs["complete"] == 1
        for name in ("attractor", "status", "t_trap", "basin_fraction", "k"):
            np.testing.assert_array_equal(tree[name].values, fresh[name].values)
        out.unlink()


def test_a_refused_run_creates_no_output_folder(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    cfg = write_config(tmp_path / "c.yaml", SLOW.format(dt=0.01, output=tmp_path / "new" / "x.h5"))
    _one_line(run_cli("run", cfg, "--backend", "cuda", env=env), 2, "backend 'cuda'")
    huge = write_config(tmp_path / "h.yaml", f"""\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 1048576}}
  theta_dot0: {{start: -4, stop: 4, num: 1048576}}
output: {tmp_path / 'deep' / 'er' / 'huge.h5'}
""")
    _one_line(run_cli("run", huge), 2, "is free on that disk")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml", "h.yaml"]


def test_concurrent_lock_attempts_admit_exactly_one(tmp_path):
    """Many processes racing for one output's lock: exactly one holds it, the others are
    refused at once."""
    script = textwrap.dedent(f"""
        import sys, time
        from pathlib import Path
        from atlas.pipeline.lock import output_lock, OutputLocked
        try:
            with output_lock(Path({str(tmp_path / 'race.h5')!r})):
                time.sleep(3.0)  # longer than the spread of the racers' start-up
                print("got it")
        except OutputLocked:
            print("refused")
    """)
    procs = [subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                              text=True, cwd=REPO) for _ in range(8)]
    answers = sorted(p.communicate()[0].strip() for p in procs)
    assert answers == ["got it"] + ["refused"] * 7
    assert lock_is_free(tmp_path / "race.h5")


def test_racing_takeovers_of_a_dead_runs_lock_never_overlap(tmp_path):
    """A holder is SIGKILLed, then 8 processes started at once each retry until they hold
    the lock, hold it briefly and record when they entered and left: all 8 get it, and no two
    holding intervals overlap (time.monotonic is one clock for all processes on Linux)."""
    out = tmp_path / "race.h5"
    holder = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import time
        from pathlib import Path
        from atlas.pipeline.lock import output_lock
        with output_lock(Path({str(out)!r})):
            print("locked", flush=True)
            time.sleep(600)
    """)], stdout=subprocess.PIPE, text=True, cwd=REPO)
    assert holder.stdout.readline().strip() == "locked"
    racer = textwrap.dedent(f"""
        import os, time
        from pathlib import Path
        from atlas.pipeline.lock import output_lock, OutputLocked
        while True:
            try:
                with output_lock(Path({str(out)!r})):
                    entered = time.monotonic()
                    time.sleep(0.05)
                    left = time.monotonic()
                break
            except OutputLocked:
                time.sleep(0.001)
        Path({str(tmp_path)!r}, f"rec-{{os.getpid()}}").write_text(f"{{entered}} {{left}}")
    """)
    procs = [subprocess.Popen([sys.executable, "-c", racer], cwd=REPO) for _ in range(8)]
    time.sleep(0.5)  # let the racers spin against the live holder first
    holder.kill()
    holder.wait()
    for p in procs:
        assert p.wait(timeout=120) == 0
    intervals = sorted(tuple(map(float, f.read_text().split()))
                       for f in tmp_path.glob("rec-*"))
    assert len(intervals) == 8
    for (_, left), (entered, _) in zip(intervals, intervals[1:]):
        assert left <= entered, intervals


@pytest.fixture(scope="module")
def taken_reference(tmp_path_factory):
    """A 48 x 48 config (48 tiles) and its clean result."""
    tmp = tmp_path_factory.mktemp("taken")
    cfg = write_config(tmp / "c.yaml", TILES_48.format(dt=0.01, output=tmp / "ref.h5"))
    return cfg, _labels(_reference(cfg, tmp / "ref.h5"))


@pytest.mark.parametrize("phase", ["tiles", "assembly", "summary", "groups"])
def test_the_disk_taken_by_another_process_at_any_phase(tmp_path, taken_reference, phase):
    """A second process (dd) fills a 4 MiB tmpfs while the run writes its tiles, assembles the
    map, writes the summary or the groups: exit 1 with one line naming the partial folder and
    the system's reason (no crash: HDF5 objects are closed before they are collected), every
    finished tile kept, nothing at the output; once the space is freed the same command
    finishes, identical to a clean run."""
    from tools.faults import _taken_trial, _unshare_works

    if not _unshare_works(tmp_path):
        pytest.skip("unprivileged mount namespaces are not available here")
    cfg, reference = taken_reference
    code, line, recovered = _taken_trial(cfg, tmp_path, phase)
    assert code == 1, line
    assert len(line.splitlines()) == 1 and "Traceback" not in line, line
    assert "out.h5.partial: writing failed (No space left on device)" in line, line
    assert "run the same command again" in line and recovered
    for a, b in zip(_labels(tmp_path / "taken-copy.h5"), reference):
        np.testing.assert_array_equal(a, b)


def test_the_fuzz_row_fails_where_its_tests_are_missing_or_run_none(tmp_path):
    """The soak's hostile-input row read as passed ("skipped … not found", with counts equal)
    after the fuzz tests moved: a missing file, or a file with no test, fails the row."""
    from tools.faults import FUZZ_TESTS, hostile_input_row

    assert (Path(__file__).resolve().parents[2] / FUZZ_TESTS).exists()  # the real tests
    what, n, recovered, identical = hostile_input_row(tmp_path, 1)
    assert "FAILED" in what and n > 0 and recovered == identical == 0
    (tmp_path / FUZZ_TESTS).parent.mkdir(parents=True)
    (tmp_path / FUZZ_TESTS).write_text('"""no test here"""\n')
    what, n, recovered, identical = hostile_input_row(tmp_path, 1)
    assert "no test ran" in what and recovered == identical == 0
