"""``atlas orbit`` on a driven pendulum's atlas: the label it prints is the atlas's at its grid
points (and at dt/2 its ``changes_at_half_dt``), the orbit's returns to P are the kernel's
P iterates (and the exact equation's, to RK4's error), the figure has its three panels, and
bad input is one line with exit status 2.

The atlas: the Wada case of tests/models/test_driven_pendulum.py (α = 0.1, ω0 = 1, A = 1.66,
Ω = 1) on a 6 × 6 grid at dt = T/32 (a few seconds to make), and a parameter atlas of two
amplitudes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import atlas
from atlas.cli import main
from atlas.commands.orbit import plot, report
from atlas.commands.orbit_driven import follow, open_driven_point
from atlas.kernels import driven as kernels
from atlas.models.driven.attractors import Drive
from atlas.views.info_driven import attractor_names
from tests.helpers import write_config

CONFIG = """\
name: tiny driven
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {{amplitude: {amplitude}, frequency: 1.0}}
grid:
  theta0: {{start: -pi, stop: pi, num: 6}}
  theta_dot0: {{start: -2, stop: 4, num: 6}}
integrator: {{dt: pi/16, t_max: 320}}
output: {output}
"""


@pytest.fixture(scope="module")
def driven_files(tmp_path_factory):
    """(a one-point driven atlas, a parameter atlas of amplitudes 1.2 and 1.66)."""
    tmp = tmp_path_factory.mktemp("orbit_driven")
    out = []
    for name, amplitude in (("one", "1.66"), ("two", "[1.2, 1.66]")):
        cfg = atlas.load_config(write_config(tmp / f"{name}.yaml", CONFIG.format(
            amplitude=amplitude, output=tmp / f"{name}.h5")))
        atlas.run(cfg, quiet=True)
        out.append(tmp / f"{name}.h5")
    return tuple(out)


def _grid(path, **select):
    ds = atlas.open(path).to_dataset(inherit=False)
    return ds.sel(select) if select else ds


def test_the_label_is_the_atlas_label_at_every_grid_point(driven_files):
    """At each of the 36 grid points the orbit's label, status and t_trap are the stored
    ones, and its label at dt/2 differs exactly where the file says changes_at_half_dt."""
    path, _ = driven_files
    ds = _grid(path)
    source = open_driven_point(path)
    try:
        for j, v in enumerate(ds["theta_dot0"].values):
            for i, th in enumerate(ds["theta0"].values):
                orbit = follow(source.labeller, float(th), float(v), source.t_max)
                assert orbit.attractor == int(ds["attractor"].values[j, i])
                assert orbit.status == int(ds["status"].values[j, i])
                assert np.float32(orbit.t_trap) == ds["t_trap"].values[j, i]
                assert orbit.changes_at_half_dt == bool(ds["changes_at_half_dt"].values[j, i])
                # kept up to the decision, whose period is the stored t_trap's
                assert orbit.t[-1] == pytest.approx(float(ds["t_trap"].values[j, i]), rel=1e-6)
    finally:
        source.tree.close()


def test_the_printed_label_is_the_stored_one(driven_files, tmp_path, capsys):
    path, _ = driven_files
    ds = _grid(path)
    for j, i in ((0, 0), (3, 2)):  # (3, 2): its label changes at dt/2
        th, v = float(ds["theta0"][i]), float(ds["theta_dot0"][j])
        k = int(ds["attractor"].values[j, i])
        assert main(["orbit", str(path), repr(th), repr(v), "-o", str(tmp_path / "o.png")]) == 0
        text = capsys.readouterr().out
        keys = [line.split()[0] for line in text.splitlines()]
        assert keys == ["orbit", "drive", "label", "status", "t_trap", "dt/2", "file", "wrote"]
        names = attractor_names(atlas.open(path)["attractors"].to_dataset())
        assert f"label        attractor {names[k]}, " in text
        assert f"stored attractor {names[k]}, " in text
        assert "status       converged: a return came within the capture radius" in text
        assert f"t_trap       {float(ds['t_trap'].values[j, i]):.2f} s" in text
        assert "RK4 with dt = T/32" in text and "t_max = 320 s" in text
        changes = bool(ds["changes_at_half_dt"].values[j, i])
        assert ("dt/2         changes:" in text) == changes
        assert f"changes at dt/2: {'yes' if changes else 'no'}" in text


def test_the_returns_are_the_kernels_p_iterates_and_the_exact_equations(driven_files):
    """The trajectory's states at t = nT are kernels.sample's returns, bit for bit (the
    lane kernel that labels); each state is DOP853's (rtol 1e-11) to RK4's error: at
    dt = T/32 within 1e-3 over 3 periods, at dt = T/200 within 5e-6."""
    path, _ = driven_files
    source = open_driven_point(path)
    source.tree.close()
    orbit = follow(source.labeller, 0.5, 1.0, source.t_max)
    d = orbit.drive
    n = orbit.returns.shape[0] - 1
    assert n == orbit.periods > 8
    sampled = kernels.sample(np.array([0.5]), np.array([1.0]), d.alpha, d.omega0, d.torque,
                             d.table, d.dt, 0, n)[0]
    np.testing.assert_array_equal(orbit.returns[1:], sampled)
    np.testing.assert_array_equal(orbit.returns[0], [0.5, 1.0])
    assert np.array_equal(orbit.returns, np.column_stack([orbit.theta, orbit.theta_dot])[
        ::d.steps_per_period // orbit.stride])

    for drive, tol in ((d, 1e-3), (Drive(0.1, 1.0, 0.0, 1.66, 1.0, 0.0, 200), 5e-6)):
        path = kernels.trajectory(0.5, 1.0, drive.alpha, drive.omega0, drive.torque,
                                  drive.table, drive.dt, 3)
        t = np.arange(path.shape[0]) * drive.dt

        def field(t, y, drive=drive):
            return (y[1], drive.torque + drive.amplitude * math.cos(drive.frequency * t
                                                                    + drive.phase)
                    - drive.omega0 ** 2 * math.sin(y[0]) - 2 * drive.alpha * y[1])

        exact = solve_ivp(field, (0.0, t[-1]), [0.5, 1.0], method="DOP853", rtol=1e-11,
                          atol=1e-12, t_eval=t).y.T
        assert np.abs(path - exact).max() < tol
        returns = path[::drive.steps_per_period]
        assert np.abs(returns - exact[::drive.steps_per_period]).max() < tol


def test_a_long_orbit_is_kept_every_s_th_step():
    """Past MAX_KEPT states the trajectory keeps every s-th step (s divides N), its returns
    still the same bits."""
    d = Drive(0.1, 1.0, 0.0, 1.66, 1.0, 0.0, 32)
    whole = kernels.trajectory(0.3, 0.2, d.alpha, d.omega0, d.torque, d.table, d.dt, 10)
    thin = kernels.trajectory(0.3, 0.2, d.alpha, d.omega0, d.torque, d.table, d.dt, 10, 4)
    np.testing.assert_array_equal(thin, whole[::4])
    with pytest.raises(ValueError):
        kernels.trajectory(0.3, 0.2, d.alpha, d.omega0, d.torque, d.table, d.dt, 10, 5)


def test_the_figure_has_its_three_panels(driven_files, tmp_path):
    import matplotlib

    from atlas.commands.orbit_driven_figure import driven_figure
    from atlas.views.style import STYLE

    path, _ = driven_files
    orbit, _, context = report(0.5, 1.0, file=path)
    try:
        with matplotlib.rc_context(STYLE):
            fig = driven_figure(orbit, context["tree"], context["index"], context["group"])
        out = plot(orbit, tmp_path / "o.png", context)
    finally:
        context["tree"].close()
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    by_label = {ax.get_xlabel(): ax for ax in fig.axes}
    phase = by_label["θ, θ0 [rad] (orbit: θ wrapped to [−π, π))"]
    timeline = by_label["t [s]"]
    returns = by_label["θ(nT) wrapped to [−π, π) [rad]"]
    # the phase curve over the file's basin map (its image), in units
    assert phase.images and phase.get_ylabel() == "θ̇, θ̇0 [rad/s]"
    drawn = np.concatenate([line.get_xdata() for line in phase.lines
                            if line.get_label().startswith("orbit")])
    assert np.nanmin(drawn) >= -math.pi and np.nanmax(drawn) < math.pi
    # θ(t) unwrapped, the returns on it at t = nT
    assert timeline.get_ylabel() == "θ(t), unwrapped [rad]"
    theta_t = [line for line in timeline.lines if line.get_label() == "θ(t)"][0]
    np.testing.assert_array_equal(theta_t.get_ydata(), orbit.theta)
    # the returns on P, and the attractor's points
    assert returns.get_ylabel() == "θ̇(nT) [rad/s]"
    offsets = returns.collections[0].get_offsets()
    assert len(offsets) == orbit.returns.shape[0]
    np.testing.assert_allclose(offsets[:, 1], orbit.returns[:, 1])
    assert any("(reached): its points on P" in text.get_text()
               for text in returns.get_legend().get_texts())


def test_the_default_figure_lies_next_to_the_file(driven_files, capsys):
    _, two = driven_files
    assert main(["orbit", str(two), "0.5", "1", "--amplitude", "1.2"]) == 0
    out = two.with_name("two_orbit_amplitude_1.2_0.5_1.png")
    assert capsys.readouterr().out.splitlines()[-1] == f"wrote        {out}"
    assert out.exists()


def test_a_parameter_atlas_point_is_chosen_by_its_drive(driven_files, tmp_path, capsys):
    """Without a selector a parameter atlas is refused in one line naming its points; with
    --amplitude the point's own labels are printed."""
    _, two = driven_files
    assert main(["orbit", str(two), "0.5", "1", "-o", str(tmp_path / "o.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--amplitude" in err[0] and "amplitude = 1.2" in err[0]
    ds = _grid(two, amplitude=1.2)
    th, v = float(ds["theta0"][1]), float(ds["theta_dot0"][2])
    assert main(["orbit", str(two), repr(th), repr(v), "--amplitude", "1.2",
                 "-o", str(tmp_path / "o.png")]) == 0
    text = capsys.readouterr().out
    assert "A = 1.2 rad/s^2" in text
    k = int(ds["attractor"].values[2, 1])
    assert f"label        attractor #{k} " in text and f"stored attractor #{k} " in text


def test_a_start_outside_the_window_is_said_first(driven_files, tmp_path, capsys):
    path, _ = driven_files
    assert main(["orbit", str(path), "0", "7", "-o", str(tmp_path / "o.png")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("warning") and "outside the atlas window" in lines[0]
    assert lines[-2].endswith("(the orbit starts outside the atlas window)")


@pytest.mark.parametrize("argv, word", [
    (["0.5", "abc"], "theta_dot0"),
    (["0.5"], "THETA_DOT0 is missing"),
    (["0.5", "1", "--amplitude", "2"], "no single parameter point with amplitude = 2"),
    (["0.5", "1", "--frequency", "x"], "--frequency"),
    (["0.5", "1", "--dt", "0.1"], "--dt 0.1"),
    (["0.5", "1", "--t-max", "100"], "--t-max 100"),
])
def test_bad_input_is_one_line(driven_files, tmp_path, capsys, argv, word):
    path, _ = driven_files
    assert main(["orbit", str(path), *argv, "-o", str(tmp_path / "o.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and word in err[0], err
    assert not (tmp_path / "o.png").exists()


def test_a_drive_option_without_a_driven_atlas_is_one_line(tmp_path, capsys):
    assert main(["orbit", "0.5", "1", "--alpha", "0.1", "--omega0", "1", "--amplitude", "1",
                 "-o", str(tmp_path / "o.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--amplitude" in err[0] and "driven" in err[0], err


def test_an_orbit_without_a_label_says_so_and_is_drawn(driven_files, tmp_path):
    """An orbit undecided by t_max (here a point cut to 3 periods) prints no attractor, the
    status's meaning and why t_trap has none; its figure is drawn without a zoom."""
    from dataclasses import replace

    from atlas.commands.orbit_driven import nearest_stored
    from atlas.commands.orbit_driven_figure import plot_driven_orbit
    from atlas.commands.orbit_driven_text import driven_lines

    path, _ = driven_files
    source = open_driven_point(path)
    try:
        labeller = replace(source.labeller, max_periods=3)
        orbit = follow(labeller, 0.5, 1.0, 3 * labeller.drive.period)
        assert orbit.attractor is None and orbit.status == 1 and orbit.periods == 3
        assert orbit.returns.shape == (4, 2) and math.isnan(orbit.t_trap)
        lines = driven_lines(orbit, source.params, source.group,
                             nearest_stored(source.point, 0.5, 1.0), source.point)
        text = "\n".join(lines)
        assert "label        none (unresolved" in text
        assert "status       unresolved: no label decided before t_max" in text
        assert "t_trap       none: no label after 3 drive periods" in text
        out = plot_driven_orbit(orbit, tmp_path / "u.png", source.tree, source.index,
                                source.group)
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    finally:
        source.tree.close()
