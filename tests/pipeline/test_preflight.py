"""The pre-flight estimate of a big run (atlas.pipeline.preflight): what it measures, what it
says, when it asks, and that a run declined writes nothing."""

from __future__ import annotations

import io
import logging

import numpy as np
import pytest

import atlas
from atlas.errors import AtlasError
from atlas.models.pendulum.plan import begin
from atlas.pipeline import preflight, sweep
from atlas.pipeline.output import BYTES_PER_ORBIT
from tests.helpers import SMALL, write_config


class _Terminal(io.StringIO):
    """A stdin that is a terminal holding the user's typed answer."""

    def isatty(self):
        return True


class _Pipe(io.StringIO):
    def isatty(self):
        return False


def _small(tmp_path, sep=False):
    return atlas.load_config(write_config(tmp_path / "c.yaml", SMALL.format(
        sep=str(sep).lower(), output=tmp_path / "small.h5")))


def _estimate(**kw):
    base = dict(orbits=400_000_000, points=1, seconds=3600.0, sample=4096,
                disk_bytes=4_400_000_000)
    return preflight.Estimate(**{**base, **kw})


def test_the_rate_is_the_per_orbit_cost_without_a_calls_fixed_cost(tmp_path, monkeypatch):
    """A machine whose every label call costs a fixed 50 ms plus 20 µs an orbit (a fake clock
    advanced by a fake kernel): the calibration must find 50 000 orbits/s, the fixed cost
    taken off, from stretches of the run's own grid rows."""
    import atlas.labels.labelling as labelling

    cfg = _small(tmp_path)
    layout = sweep.layout_of(cfg)
    clock, calls = [0.0], []

    def fake_label(theta0, theta_dot0, *, t_max, **kw):
        calls.append((theta0, theta_dot0, t_max))
        clock[0] += 0.05 + (0.0 if t_max == cfg.integrator.dt else 20e-6 * theta0.size)

    monkeypatch.setattr(labelling, "label", fake_label)
    monkeypatch.setattr(preflight.time, "perf_counter", lambda: clock[0])
    rate, timed = preflight.measure_rate(cfg, layout, begin(cfg, layout))
    assert rate == pytest.approx(50_000, rel=1e-9)
    assert timed >= preflight.FIRST_SAMPLE
    width = min(preflight.STRETCH, layout.x0.size)
    for theta0, theta_dot0, _ in calls:
        rows, cols = theta0.reshape(-1, width), theta_dot0.reshape(-1, width)
        for th, v in zip(rows, cols):  # consecutive θ0 of one grid row, as in a tile
            start = int(np.flatnonzero(layout.x0 == th[0])[0])
            np.testing.assert_array_equal(th, layout.x0[start:start + width])
            assert np.all(v == v[0]) and v[0] in layout.v0


def test_every_kernel_the_timed_calls_take_is_loaded_before_timing(tmp_path, monkeypatch):
    """A batch's size chooses the kernel (one chunk runs a serial twin, compiled on its own:
    atlas.kernels.lanes.n_chunks), and so does the point (τ = 0 without a running barrier
    runs the untilted specialisation), so the untimed first calls must be as large as the
    timed ones, at every point timed; a small one at the first point left the timed calls
    to compile theirs (a first big run once announced 37 min for a 5 s sweep)."""
    import atlas.labels.labelling as labelling
    from atlas.kernels.lanes import n_chunks

    cfg = atlas.load_config(write_config(tmp_path / "c.yaml", SMALL.format(
        sep="false", output=tmp_path / "small.h5").replace(
        "pendulum: {alpha: 0.1, omega0: 1.0}",
        "pendulum: {alpha: 0.1, omega0: 1.0, torque: [0.0, 0.1, 0.5, 0.9]}")))
    layout = sweep.layout_of(cfg)
    begun = begin(cfg, layout)
    assert begun[0].barrier is None and begun[-1].barrier is not None
    loaded, late = set(), []

    def fake_label(theta0, theta_dot0, *, t_max, torque, running, **kw):
        kernel = (torque == 0.0 and running is None, n_chunks(theta0.size) == 1)
        if t_max == cfg.integrator.dt:
            loaded.add(kernel)
        elif kernel not in loaded:
            late.append(kernel)

    monkeypatch.setattr(labelling, "label", fake_label)
    monkeypatch.setattr(preflight, "MAX_POINTS", layout.n_params)  # every point timed
    preflight.measure_rate(cfg, layout, begun)
    assert len(loaded) == 2 and not late, (loaded, late)


def test_the_sample_grows_to_about_one_call_of_call_s(tmp_path, monkeypatch):
    """On a machine that labels 100 000 orbits/s (a fake clock), the sample grows until a
    call takes CALL_S, aimed at the rate seen: every timed call of the final size takes
    between CALL_S and 1.25·CALL_S plus one stretch (fourfold growth would take up to four
    times CALL_S, at every point)."""
    import atlas.labels.labelling as labelling

    cfg = _small(tmp_path)
    layout = sweep.layout_of(cfg)
    clock, spent = [0.0], []

    def fake_label(theta0, theta_dot0, *, t_max, **kw):
        if t_max != cfg.integrator.dt:
            spent.append(10e-6 * theta0.size)
            clock[0] += spent[-1]

    monkeypatch.setattr(labelling, "label", fake_label)
    monkeypatch.setattr(preflight.time, "perf_counter", lambda: clock[0])
    rate, timed = preflight.measure_rate(cfg, layout, begin(cfg, layout))
    assert rate == pytest.approx(100_000, rel=1e-9)
    final = spent[-min(preflight.MAX_POINTS, layout.n_params):]
    stretch = 10e-6 * min(preflight.STRETCH, layout.x0.size)
    assert all(preflight.CALL_S <= s <= 1.25 * preflight.CALL_S + stretch for s in final), spent


def test_the_time_is_measured_only_where_the_run_may_be_big(tmp_path, monkeypatch):
    cfg = _small(tmp_path)
    layout = sweep.layout_of(cfg)
    measured = []
    monkeypatch.setattr(preflight, "measure_rate",
                        lambda *a, **k: measured.append(1) or (1000.0, 64))
    small = preflight.estimate(cfg, layout, [None], 384, "cpu", "cpu")
    assert small.seconds is None and not measured and not small.big and not small.asks
    big = preflight.estimate(cfg, layout, [None], preflight.PREFLIGHT_ORBITS, "cpu", "cpu")
    assert measured and big.seconds == preflight.PREFLIGHT_ORBITS / 1000.0 and big.big
    gpu = preflight.estimate(cfg, layout, [None], preflight.PREFLIGHT_ORBITS, "cuda", "cuda")
    assert gpu.seconds is None and "time not estimated" in gpu.line()


def test_the_line_says_orbits_time_and_disk():
    line = _estimate(points=3).line()
    assert line.startswith("atlas: 400 M orbits at 3 parameter points")
    assert "about 60 min on this machine" in line and "measured on 4096" in line
    assert "about 10 h" in _estimate(seconds=36000.0).line()
    assert "up to 4.4 GB on disk" in line


def test_when_a_run_asks():
    assert _estimate().asks
    assert not _estimate(seconds=60.0, disk_bytes=10**6).asks
    assert _estimate(seconds=1.0, disk_bytes=preflight.CONFIRM_BYTES).asks
    assert _estimate(orbits=10**6, seconds=preflight.LINE_S, disk_bytes=1).big
    assert not _estimate(orbits=10**6, seconds=1.0, disk_bytes=1).big


@pytest.mark.parametrize(("answer", "start"), [("y\n", True), ("yes\n", True), ("n\n", False),
                                                ("\n", False), ("", False)])
def test_the_question_on_a_terminal(answer, start, capsys):
    assert preflight.ask(stdin=_Terminal(answer))(_estimate()) is start
    err = capsys.readouterr().err
    assert "400 M orbits" in err and "Start? [y/N]" in err


def test_no_question_with_yes_or_off_a_terminal(capsys):
    never = _Terminal()
    never.readline = None  # reading the answer would fail
    assert preflight.ask(yes=True, stdin=never)(_estimate())
    assert "400 M orbits" in capsys.readouterr().err
    assert preflight.ask(stdin=_Pipe())(_estimate())
    assert "stdin is not a terminal: starting without asking" in capsys.readouterr().err
    assert preflight.ask(quiet=True, stdin=_Pipe())(_estimate())
    assert capsys.readouterr().err == ""


def test_a_closed_or_missing_stdin_is_not_a_terminal(monkeypatch, capsys):
    """A job started with stdin closed (``<&-``: sys.stdin is None) or a closed stream starts
    without asking, as off a terminal, and says so: no traceback."""
    monkeypatch.setattr("sys.stdin", None)
    assert preflight.ask()(_estimate())
    closed = _Terminal("y\n")
    closed.close()
    assert preflight.ask(stdin=closed)(_estimate())
    assert capsys.readouterr().err.count("stdin is not a terminal") == 2


def test_sigterm_at_the_question_stops_the_run_not_declines_it():
    """SIGTERM while asking (atlas.cli raises its Terminated, a KeyboardInterrupt) is passed
    on, so the run ends with 143, not as a declined run; Ctrl-C answers no."""
    from atlas.cli import Terminated

    for raised, passed_on in ((Terminated, True), (KeyboardInterrupt, False)):
        typing = _Terminal()

        def interrupted(exc=raised):
            raise exc()

        typing.readline = interrupted
        if passed_on:
            with pytest.raises(raised):
                preflight.ask(stdin=typing)(_estimate())
        else:
            assert preflight.ask(stdin=typing)(_estimate()) is False


def test_a_run_declined_writes_nothing(tmp_path, monkeypatch, capsys):
    cfg = _small(tmp_path)
    monkeypatch.setattr(preflight, "CONFIRM_BYTES", 1)
    asked = []
    with pytest.raises(AtlasError, match="not started"):
        sweep.run(cfg, confirm=lambda est: asked.append(est) or False)
    assert asked[0].orbits == 24 * 16
    assert asked[0].disk_bytes == 24 * 16 * BYTES_PER_ORBIT  # checked against a file elsewhere
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


def test_a_big_run_says_its_estimate_unless_quiet(tmp_path, monkeypatch, capsys):
    cfg = _small(tmp_path)
    monkeypatch.setattr(preflight, "PREFLIGHT_ORBITS", 100)
    monkeypatch.setattr(preflight, "measure_rate", lambda *a, **k: (1000.0, 64))
    logging.getLogger("atlas").setLevel(logging.WARNING)
    sweep.run(cfg, quiet=True, open_result=False)
    assert capsys.readouterr().err == ""
    sweep.run(cfg, open_result=False)
    err = capsys.readouterr().err
    assert "384 orbits, labelling about 0.38 s on this machine (measured on 64" in err


def test_a_resumed_run_counts_only_the_orbits_still_to_do(tmp_path, monkeypatch):
    from atlas.store.reader import describe
    from tests.helpers import crash_on_tile

    cfg = _small(tmp_path)  # 24 × 16 orbits in tiles of 4 rows (96 orbits)
    crash_on_tile(monkeypatch, 3, RuntimeError("simulated crash"))
    with pytest.raises(RuntimeError):
        sweep.run(cfg, quiet=True)
    monkeypatch.undo()
    done = describe(tmp_path / "small.h5.partial")["tiles_done"]
    assert 0 < done < 4
    monkeypatch.setattr(preflight, "CONFIRM_BYTES", 1)
    asked = []
    with pytest.raises(AtlasError, match="not started"):
        sweep.run(cfg, quiet=True, confirm=lambda est: asked.append(est) or False)
    assert asked[0].orbits == (4 - done) * 4 * 24
    assert describe(tmp_path / "small.h5.partial")["tiles_done"] == done  # kept as it was


def test_a_quiet_run_that_would_neither_say_nor_ask_measures_nothing(tmp_path, monkeypatch):
    """``atlas run -q`` off a terminal (or with --yes), and ``atlas.run(quiet=True)``: the
    estimate would be neither said nor asked about, so the calibration is not run at all
    (it cost a driven run about a second); a quiet run that may ask still measures."""
    cfg = _small(tmp_path)
    monkeypatch.setattr(preflight, "PREFLIGHT_ORBITS", 100)

    def measured(*args, **kwargs):
        raise AssertionError("measured")

    monkeypatch.setattr(preflight, "measure_rate", measured)
    sweep.run(cfg, quiet=True, open_result=False)
    for confirm in (preflight.ask(quiet=True, stdin=_Pipe()),
                    preflight.ask(yes=True, quiet=True, stdin=_Terminal())):
        assert confirm.silent
        sweep.run(cfg, quiet=True, restart=True, confirm=confirm, open_result=False)
    asking = preflight.ask(quiet=True, stdin=_Terminal())
    assert not asking.silent
    with pytest.raises(AssertionError, match="measured"):
        sweep.run(cfg, quiet=True, restart=True, confirm=asking, open_result=False)
