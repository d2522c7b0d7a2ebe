"""Bad input to ``atlas stability`` refused before any work, with one line on stderr (exit
status 2, nothing written): ranges with num < 2 or start >= stop, a parameter given twice, more
than a million points without --force, an output that is not a study; and ranges in grid
configs."""

from __future__ import annotations

import numpy as np
import pytest

from atlas.cli import main
from tests.helpers import STUDY_BODY as BODY
from tests.helpers import study_config, write_config


@pytest.mark.parametrize("torque, message", [
    ("{start: 0, stop: 1, num: 1}", "range num must be between 2"),
    ("{start: 1, stop: 0, num: 5}", "must be less than stop"),
    ("{start: 0, stop: 1}", "num is missing"),
    ("{start: 0, stop: 1, num: 3, step: 1}", "unknown key 'step'"),
    ("{start: 0, stop: 1, num: 2.5}", "integer"),
])
def test_bad_ranges_are_refused(tmp_path, capsys, torque, message):
    out = tmp_path / "x.h5"
    cfg = write_config(tmp_path / "x.yaml", BODY.format(torque=torque, output=out))
    assert main(["stability", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pendulum.torque" in err and message in err
    assert not out.exists()


def test_a_parameter_given_twice_is_refused(tmp_path, capsys):
    """A 2-D study over torque given twice (as two keys) would be ambiguous: refused."""
    out = tmp_path / "x.h5"
    cfg = write_config(tmp_path / "x.yaml", (
        "pendulum:\n  alpha: {start: 0.1, stop: 0.2, num: 3}\n"
        "  torque: {start: 0, stop: 0.5, num: 3}\n  torque: [0.1, 0.2]\n"
        f"output: {out}\n"))
    assert main(["stability", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'torque' given twice" in err
    assert not out.exists()


def test_more_than_a_million_points_needs_force(tmp_path, capsys):
    out = tmp_path / "x.h5"
    cfg = write_config(tmp_path / "x.yaml", (
        "pendulum:\n  alpha: {start: 0.1, stop: 0.2, num: 1001}\n"
        "  torque: {start: 0, stop: 0.5, num: 1000}\n"
        f"output: {out}\n"))
    assert main(["stability", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1,001,000 parameter points" in err and "--force" in err
    assert not out.exists()


def test_an_output_that_is_not_a_study_is_kept(tmp_path, capsys):
    out = tmp_path / "x.h5"
    out.write_text("precious")
    cfg = write_config(tmp_path / "x.yaml", BODY.format(torque="[0.0, 1.5]", output=out))
    assert main(["stability", str(cfg)]) == 2
    assert "a file that atlas did not write is in the way of a study" in capsys.readouterr().err
    assert out.read_text() == "precious"


def test_ranges_work_in_grid_configs_too(tmp_path):
    """A range is num values from start to stop inclusive, evenly spaced."""
    import atlas

    cfg = write_config(tmp_path / "g.yaml", BODY.format(
        torque="{start: 0.1, stop: 0.4, num: 4}", output=tmp_path / "g.h5"))
    values = np.array(atlas.load_config(cfg).pendulum.torques)
    assert values.size == 4 and values[0] == 0.1 and values[-1] == 0.4
    assert np.allclose(np.diff(values), 0.1, rtol=1e-14)


def test_a_grid_run_over_a_range_has_a_point_per_value(tmp_path):
    """A grid run of a torque range across the homoclinic torque (≈ 0.49 at α = 0.2): one
    point per value, each with the exact fractions a study stores for it, the running
    basin's where the cycle exists."""
    import atlas
    from atlas.stability.study import StudySettings, compute_point

    cfg = write_config(tmp_path / "g.yaml", BODY.format(
        torque="{start: 0.3, stop: 0.9, num: 3}", output=tmp_path / "g.h5"))
    run = atlas.load_config(cfg)
    ds = atlas.basins(run)["/"].to_dataset()
    np.testing.assert_array_equal(ds["torque"].values, run.pendulum.torques)
    np.testing.assert_allclose(ds["torque"].values, [0.3, 0.6, 0.9], rtol=1e-15)
    window = ((-np.pi, np.pi), (-3.0, 3.0))
    running = []
    for i, torque in enumerate(ds["torque"].values):
        point = compute_point(0.2, 1.0, float(torque), StudySettings(window=window))
        stored = ds.isel(torque=i)
        assert abs(float(stored["running_fraction_exact"]) - point.running) < 1e-12
        exact = stored["basin_fraction_exact"]
        for k, fraction in zip(point.k, point.fraction):
            assert abs(float(exact.sel(k=k)) - fraction) < 1e-12
        running.append(point.running)
    assert running[0] == 0.0 and 0.0 < running[1] < running[2] < 1.0


@pytest.mark.parametrize("grid, extra, key", [
    ("{start: -1.0e+6, stop: 1.0e+6, num: 2}", "check_radians: false\n", "grid:"),
    ("{start: -pi, stop: pi, num: 2}\n  theta_dot0: {start: -1.0e+6, stop: 1.0e+6, num: 2}",
     "", "grid:"),
    ("{start: -pi, stop: pi, num: 2}", "stability: {sigma_theta: 1.0e+6, sigma_theta_dot: 1}\n",
     "stability.sigma_theta, sigma_theta_dot:"),
    ("{start: -pi, stop: pi, num: 2}", "stability: {sigma_theta: 1, sigma_theta_dot: 1.0e+6}\n",
     "stability.sigma_theta, sigma_theta_dot:"),
])
def test_a_window_or_gaussian_beyond_the_indexed_wells_is_refused(tmp_path, grid, extra, key):
    """Windows and Gaussian boxes whose boundaries run beyond the wells an atlas indexes
    (found by the fuzzer: they ran for hours, or until the memory ran out) are refused at
    once in one line naming the key (exit 2, nothing written)."""
    from tests.helpers import run_cli

    out = tmp_path / "w.h5"
    body = BODY.format(torque="[0.0, 0.3]", output=out).replace(
        "{start: -pi, stop: pi, num: 2}\n  theta_dot0: {start: -3, stop: 3, num: 2}",
        grid if "theta_dot0" in grid else grid + "\n  theta_dot0: {start: -3, stop: 3, num: 2}")
    cfg = write_config(tmp_path / "w.yaml", body + extra)
    proc = run_cli("stability", cfg, timeout=120)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and f"w.yaml: {key} orbits from this window" in lines[0], lines
    assert "beyond the wells" in lines[0] and not out.exists()


def test_a_window_too_narrow_for_exact_fractions_is_refused(tmp_path, capsys):
    """A study's fractions are exact areas of curves good to about 1e-12: a window 1e-11 wide
    is refused in one line naming the axis (exit 2, nothing written); 1e-3 wide is computed."""
    out = tmp_path / "n.h5"
    cfg = write_config(tmp_path / "n.yaml", BODY.format(torque="[0.0, 0.3]", output=out)
                       .replace("{start: -pi, stop: pi, num: 2}",
                                "{start: 3.14159265358979, stop: 3.14159265358980, num: 2}"))
    assert main(["stability", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "grid.theta0" in err and "narrower than 0.0001" in err
    assert not out.exists()
    cfg.write_text(cfg.read_text().replace("3.14159265358980", "3.14259265358979"))
    assert main(["stability", str(cfg)]) == 0 and out.exists()


def test_what_a_study_cannot_give_is_refused_in_one_line(tmp_path, capsys):
    """Tipping probabilities need a 1-D study (a 2-D one is refused before any point is
    computed: it once computed the polygons for nothing); a study of one point has no
    figure (`atlas plot` says so instead of exiting 0 with nothing written)."""
    from atlas.cli import main

    out = tmp_path / "t.h5"
    cfg = study_config(tmp_path / "t.yaml", "alpha: [0.1, 0.2], omega0: 1.0, "
                       "torque: [0.3, 0.5]", out, "stability: {tipping: true}\n")
    assert main(["stability", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "stability.tipping" in err and "alpha and torque" in err
    assert not out.exists()
    cfg = study_config(tmp_path / "t1.yaml", "alpha: 0.1, omega0: 1.0, torque: [0.3]", out,
                       "stability: {tipping: true}\n")
    assert main(["stability", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "one value of torque" in err
    assert not out.exists()
    for torque in ("0.3", "[0.3]"):  # one point, as a number or a list of one
        one = write_config(tmp_path / "one.yaml", BODY.format(torque=torque,
                                                              output=tmp_path / "o.h5"))
        assert main(["stability", str(one), "--force"]) == 0
        capsys.readouterr()
        assert main(["plot", str(tmp_path / "o.h5"), "--outdir", str(tmp_path / "fig")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "has no figure" in err
        assert not (tmp_path / "fig").exists()


def test_a_parameter_listed_with_one_value_is_plotted_as_fixed(tmp_path, capsys):
    """α: [0.1] with a torque range is a curve over τ at α = 0.1, not a map one row high."""
    from atlas.cli import main

    cfg = study_config(tmp_path / "a.yaml", "alpha: [0.1], omega0: 1.0, torque: [0.2, 0.5]",
                       tmp_path / "a.h5")
    assert main(["stability", str(cfg)]) == 0
    assert main(["plot", str(tmp_path / "a.h5")]) == 0
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["a_fatal_shock.png",
                                                            "a_stability.png"]
