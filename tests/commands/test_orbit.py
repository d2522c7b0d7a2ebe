"""``atlas orbit``: one orbit's label equals the kernel's, its certificate agrees with the
file's, its pictures are written, and bad input is one line with exit status 2."""

from __future__ import annotations

import numpy as np
import pytest

import atlas
from atlas.cli import main
from atlas.commands.orbit_integrate import integrate
from atlas.labels.trap import energy_cap
from tests.helpers import SWING


@pytest.fixture(scope="module")
def atlas_file(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("orbit")
    cfg = atlas.Config.model_validate({
        "name": "orbit test", "pendulum": {"alpha": 0.1, "omega0": 1.0},
        "grid": {"theta0": {"start": "-3pi", "stop": "3pi", "num": 48},
                 "theta_dot0": {"start": -4, "stop": 4, "num": 32}},
        "output": str(tmp / "a.h5")})
    atlas.run(cfg, quiet=True)
    sweep = atlas.Config.model_validate({
        "name": "sweep", "pendulum": {"alpha": [0.1, 0.5], "omega0": 1.0},
        "grid": {"theta0": {"start": -3, "stop": 3, "num": 8},
                 "theta_dot0": {"start": -2, "stop": 2, "num": 8}},
        "separatrices": {"enabled": False}, "output": str(tmp / "s.h5")})
    atlas.run(sweep, quiet=True)
    return cfg.output, sweep.output


def test_integrate_gives_the_kernels_labels():
    rng = np.random.default_rng(0)
    th, v = rng.uniform(-9, 9, 150), rng.uniform(-4, 4, 150)
    for alpha, omega0, dt in ((0.1, 1.0, 0.01), (0.7, 2.0, 0.005)):
        ref = atlas.label(th, v, alpha=alpha, omega0=omega0, dt=dt, kernel="straightforward")
        orbits = [integrate(a, b, alpha=alpha, omega0=omega0, dt=dt) for a, b in zip(th, v)]
        np.testing.assert_array_equal([o.status for o in orbits], ref.status)
        np.testing.assert_array_equal([o.k for o in orbits], ref.attractor)
        t = np.array([o.t_trap for o in orbits])
        assert np.mean(np.isclose(t, ref.t_trap)) > 0.98
        saddle_energy = omega0**2 * (1 - np.cos(np.pi))  # E at (π, 0): the top of each well
        for o in orbits:  # the trap really holds where it is reported, and the curve is whole
            i = o.trap_index
            phi = o.theta[i:] - 2 * np.pi * o.k
            energy = 0.5 * o.theta_dot[i:] ** 2 + omega0**2 * (1 - np.cos(phi))
            # the kernels' trap level, below the saddle energy, and the orbit is under it
            assert energy[0] < o.cap == energy_cap(dt, alpha, omega0) < saddle_energy
            # from the trap on, the orbit stays in well k below the saddle energy, and it
            # settles at (2πk, 0)
            assert np.all(np.abs(phi) < np.pi) and np.all(energy < saddle_energy)
            assert energy[-1] < 1e-3 * saddle_energy
            assert o.t[i] == pytest.approx(o.t_trap) and o.t.size == o.theta.size


def test_orbit_on_a_file_agrees_with_the_stored_label(atlas_file, tmp_path, capsys):
    path, _ = atlas_file
    ds = atlas.open(path).to_dataset(inherit=False)
    j, i = np.argwhere(ds["status"].values == 0)[len(ds["status"].values.ravel()) // 3]
    th, v = float(ds["theta0"][i]), float(ds["theta_dot0"][j])
    k = int(ds["attractor"].values[j, i])
    out = tmp_path / "o.png"
    assert main(["orbit", str(path), repr(th), repr(v), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"label        k = {k:+d}" in text and "the same as atlas.label" in text
    assert "certified for the exact equation" in text and "Certifier" in text
    assert f"stored k = {k:+d}, status trapped" in text
    assert f"boundary distance {float(ds['boundary_distance'].values[j, i]):.4g}" in text
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_orbit_outside_the_window_warns_first(atlas_file, tmp_path, capsys):
    """A start outside the atlas window is said on the first line, before the label, with
    the window's bounds; a start inside gets no such line."""
    path, _ = atlas_file
    assert main(["orbit", str(path), "0.5", "5.5", "-o", str(tmp_path / "o.png")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("warning") and "outside the atlas window" in lines[0]
    assert "[-4, 4] rad/s" in lines[0]
    assert main(["orbit", str(path), "0.5", "1.5", "-o", str(tmp_path / "i.png")]) == 0
    assert "outside the atlas window" not in capsys.readouterr().out


def test_orbit_on_a_trigfree_file_steps_with_its_method(tmp_path, capsys):
    """A file computed with method "rk4-trigfree": atlas orbit integrates with that method
    (and says so), so its label and t_trap are the stored ones at a grid point."""
    cfg = atlas.Config.model_validate({
        "name": "trig-free", "pendulum": {"alpha": 0.1, "omega0": 1.0},
        "grid": {"theta0": {"start": "-3pi", "stop": "3pi", "num": 24},
                 "theta_dot0": {"start": -4, "stop": 4, "num": 16}},
        "integrator": {"method": "rk4-trigfree"}, "separatrices": {"enabled": False},
        "output": str(tmp_path / "tf.h5")})
    atlas.run(cfg, quiet=True)
    ds = atlas.open(cfg.output).to_dataset(inherit=False)
    j, i = 11, 7
    th, v = float(ds["theta0"][i]), float(ds["theta_dot0"][j])
    assert main(["orbit", str(cfg.output), repr(th), repr(v), "-o",
                 str(tmp_path / "o.png")]) == 0
    text = capsys.readouterr().out
    assert "method rk4-trigfree" in text and "the same as atlas.label" in text
    orbit = integrate(th, v, alpha=0.1, omega0=1.0, method="rk4-trigfree")
    assert orbit.k == int(ds["attractor"].values[j, i])
    assert np.float32(orbit.t_trap) == ds["t_trap"].values[j, i]
    assert f"t_trap       {orbit.t_trap:.3g} s" in text


def test_orbit_without_a_file(tmp_path, capsys):
    out = tmp_path / "free.png"
    assert main(["orbit", "--alpha", "0.2", "--omega0", "1", "-o", str(out), "--",
                 "-pi/2", "3.3"]) == 0
    text = capsys.readouterr().out
    ref = atlas.label(-np.pi / 2, 3.3, alpha=0.2, omega0=1.0)
    assert f"k = {int(ref.attractor):+d}" in text
    assert f"t_trap       {float(ref.t_trap):.2f}" in text
    assert "energy trap" in text and "d_cert needs" in text and out.exists()


def test_orbit_picks_a_parameter_point(atlas_file, tmp_path, capsys):
    _, sweep = atlas_file
    assert main(["orbit", str(sweep), "0", "1.5", "--alpha", "0.5",
                 "-o", str(tmp_path / "s.png")]) == 0
    assert "alpha = 0.5 1/s" in capsys.readouterr().out


@pytest.mark.parametrize("args, fragment", [
    (["orbit", "1"], "give THETA0 THETA_DOT0"),
    (["orbit", "1", "abc", "--alpha", "0.1", "--omega0", "1"], "theta_dot0: cannot read 'abc'"),
    (["orbit", "1", "2"], "give --alpha and --omega0"),
    (["orbit", "missing.h5", "1", "2"], "missing.h5: no such file"),
    (["orbit", "1", "2", "--alpha", "0", "--omega0", "1"], "alpha = 0"),
    (["orbit", "1", "2", "--alpha", "0.1", "--omega0", "1", "--dt", "3"], "stability limit"),
    (["orbit", "{sweep}", "1", "2"], "a parameter atlas of 2 points"),
    (["orbit", "{sweep}", "1", "2", "--alpha", "0.3"], "no single parameter point"),
    (["orbit", "{file}", "1", "2", "--dt", "0.02"], "was computed with dt = 0.01"),
    (["orbit", "--alpha", "0.05", "--omega0", "1", "--torque", "1", "0", "1"], "saddle-node"),
])
def test_bad_input_is_one_line_and_exit_2(atlas_file, capsys, tmp_path, args, fragment):
    path, sweep = atlas_file
    args = [a.format(file=path, sweep=sweep) for a in args] + ["-o", str(tmp_path / "x.png")]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("atlas: error: ") and fragment in err and "\n" not in err, err
    assert not (tmp_path / "x.png").exists()


# ---- with a torque τ ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def swing_file(swing_atlas):
    """The small swing atlas of conftest (shared with test_view; read only)."""
    return swing_atlas


@pytest.mark.parametrize("torque", [0.5, -0.5])
def test_integrate_with_torque_gives_the_kernels_labels(torque):
    """Random points of the bistable swing pendulum (τ = ±0.5, α = 0.05, ω0 = 1): the same
    status, well, direction and t_trap as atlas.label with the same running barrier, trapped
    and running ones alike; and each certificate holds along the orbit from where it fired."""
    from atlas.commands.orbit import running_barrier_for
    from atlas.physics.pendulum import Pendulum
    from atlas.physics.running import contains

    alpha, omega0, dt = SWING["alpha"], SWING["omega0"], 0.01
    barrier, cycle = running_barrier_for(alpha, omega0, torque, dt)
    assert barrier is not None and barrier.direction == np.sign(torque)
    rng = np.random.default_rng(3)
    th, v = rng.uniform(-4, 4, 60), rng.uniform(-6, 6, 60)
    ref = atlas.label(th, v, alpha=alpha, omega0=omega0, torque=torque, running=barrier, dt=dt,
                      kernel="straightforward")
    orbits = [integrate(a, b, alpha=alpha, omega0=omega0, torque=torque, running=barrier,
                        dt=dt) for a, b in zip(th, v)]
    status = np.array([o.status for o in orbits])
    np.testing.assert_array_equal(status, ref.status)
    assert (status == 0).sum() >= 5 and (status == 4).sum() >= 5  # both kinds are tested
    np.testing.assert_array_equal([o.k if o.k is not None else ref.attractor[i]
                                   for i, o in enumerate(orbits)], ref.attractor)
    np.testing.assert_array_equal([o.direction for o in orbits], ref.direction)
    np.testing.assert_array_equal(np.array([o.t_trap for o in orbits], np.float32), ref.t_trap)
    p = Pendulum(alpha, omega0, torque)
    for o in orbits:
        i = o.trap_index
        assert o.t[i] == pytest.approx(o.t_trap) and o.t.size == o.theta.size
        if o.status == 0:  # below the lower saddle's energy, between the well's saddles
            assert o.cap == energy_cap(dt, alpha, omega0, torque) < p.saddle_energy
            energy = p.energy(o.theta[i:], o.theta_dot[i:], o.k)
            phi = o.theta[i:] - 2 * np.pi * o.k
            assert energy[0] < o.cap and np.all(energy < p.saddle_energy)
            assert np.all((phi >= -np.pi - p.rest_angle) & (phi < np.pi - p.rest_angle))
            assert energy[-1] < 1e-3 * p.saddle_energy
        else:  # in the band from the certificate on, rotating in sign(τ)
            assert o.k is None and o.direction == np.sign(torque)
            assert np.all(contains(barrier, o.theta[i:], o.theta_dot[i:]))
            assert abs(o.theta[-1] - o.theta[i]) >= 4 * np.pi  # followed on for 2 turns


@pytest.mark.slow
def test_orbit_on_a_torque_file(swing_file, tmp_path, capsys):
    """The orbit takes τ and the running barrier from the file: a point the file labels
    running is certified running by the barrier, a trapped one in the file's well, each the
    same as atlas.label; both certified for the exact equation by the tilted boundaries, as
    the file's statuses say."""
    ds = atlas.open(swing_file).to_dataset(inherit=False)
    status = ds["status"].values
    for code in (4, 0):  # running, trapped: both certified for the exact equation
        j, i = np.argwhere(status == code)[np.sum(status == code) // 2]
        th, v = float(ds["theta0"][i]), float(ds["theta_dot0"][j])
        out = tmp_path / f"o{code}.png"
        assert main(["orbit", str(swing_file), repr(th), repr(v), "-o", str(out)]) == 0
        text = capsys.readouterr().out
        assert "torque = 0.5 rad/s^2" in text and "the same as atlas.label" in text
        assert "stable manifolds of the tilted saddles" in text
        assert "> d_cert" in text and "certified for the exact equation" in text
        if code == 4:
            assert "label        running" in text and "status running" in text
            assert "certificate  running barrier" in text
            assert "stays in the band around the limit cycle (direction +1)" in text
        else:
            k = int(ds["attractor"].values[j, i])
            assert f"label        k = {k:+d}" in text and f"stored k = {k:+d}" in text
            assert "tilted energy trap" in text
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_orbit_reads_the_certificate_its_file_stores(swing_file, tmp_path):
    """atlas orbit takes the running barrier, the trap's cap and margin from the file, as the
    run stored them (format 4), and rebuilds nothing: with them changed in a copy, the orbit
    is certified with the changed numbers, and the text says whose barrier it is."""
    from atlas.commands.orbit import report
    from tests.views.test_view import rewritten, tamper

    path = rewritten(swing_file, tmp_path / "tampered.h5", tamper)
    tree = atlas.open(path)
    node, root = tree["limit_cycle"].to_dataset(), tree.to_dataset(inherit=False)
    status = root["status"].values
    j, i = np.argwhere(status == 4)[np.sum(status == 4) // 2]
    orbit, lines, context = report(float(root["theta0"][i]), float(root["theta_dot0"][j]),
                                   file=path)
    context["tree"].close()
    np.testing.assert_array_equal(orbit.barrier.g, node["barrier_g"].values)
    assert orbit.barrier.top == node.attrs["barrier_top"]
    assert orbit.cap == float(root["trap_energy_cap"])
    assert orbit.margin == float(root["trap_margin"])
    assert orbit.status == 4 and any("the run's, as its file stores it" in line for line in lines)
    tree.close()


def test_orbit_refuses_a_format_3_file_with_one_line(swing_file, tmp_path, capsys):
    """A file of format 3 stores no certificate: atlas orbit FILE refuses it with one line
    saying how to upgrade it (exit 2, no figure); without a file the barrier is built."""
    from tests.views.test_view import as_format_3, rewritten

    path = rewritten(swing_file, tmp_path / "old.h5", as_format_3)
    out = tmp_path / "o.png"
    assert main(["orbit", str(path), "0", "1", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("atlas: error: ") and "\n" not in err
    assert "written in format 3, which does not store the certificate" in err
    assert "(`atlas run CONFIG`)" in err and not out.exists()


@pytest.mark.slow
def test_orbit_with_torque_without_a_file(tmp_path, capsys):
    out = tmp_path / "free.png"
    assert main(["orbit", "--alpha", "0.05", "--omega0", "1", "--torque", "-0.5", "-o",
                 str(out), "--", "0", "-5"]) == 0
    text = capsys.readouterr().out
    assert "label        running" in text and "(direction -1)" in text and out.exists()
    assert main(["orbit", "--alpha", "0.05", "--omega0", "1", "--torque", "1.5", "-o",
                 str(out), "--", "0", "0"]) == 0  # |τ| > ω0²: no well, every orbit runs
    text = capsys.readouterr().out
    assert "label        running" in text
    assert "boundary distance inf" in text and "no basin boundary" in text
    assert main(["orbit", "--alpha", "0.05", "--omega0", "1", "--torque", "abc", "0", "1"]) == 2
    assert "--torque: cannot read 'abc'" in capsys.readouterr().err
