"""The pendulum with constant torque (the swing equation) as an atlas: files, certificates
and exact fractions, end to end, against independent references (DOP853 runs classified by
the same certificates, the untilted atlas, the published basin stability of bSTAB)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.kernels import RUNNING, TRAPPED
from atlas.layout import at_point, point_group, points
from atlas.physics.pendulum import Pendulum
from atlas.physics.running import contains
from tests.helpers import run_cli, small_atlas

MAP = ("attractor", "status", "t_trap", "boundary_distance")


@pytest.mark.slow
def test_zero_torque_is_the_untilted_atlas(tmp_path):
    """τ = 0, given or not, and the τ = 0 point of a sweep over τ: the same arrays, bit for
    bit, as the untilted atlas; the sweep's other point is tilted and has its own node."""
    untilted = {"alpha": 0.1, "omega0": 1.0}
    window = {"theta": ("-3pi", "3pi"), "speed": (-4.0, 4.0), "num": (40, 32),
              "t_max": 200.0, "separatrices": False}
    plain = small_atlas(tmp_path, "plain", untilted, **window).to_dataset(inherit=False)
    zero = small_atlas(tmp_path, "zero", {**untilted, "torque": 0.0}, **window)
    swept = small_atlas(tmp_path, "swept", {**untilted, "torque": [0.0, 0.3]}, **window)
    sweep_root = swept.to_dataset(inherit=False)
    assert sweep_root["attractor"].dims == ("torque", "theta_dot0", "theta0")
    first = at_point(sweep_root, {"alpha": 0.1, "omega0": 1.0, "torque": 0.0})
    for other in (zero.to_dataset(inherit=False), first):
        for name in (*MAP, "basin_fraction_exact", "basin_fraction", "d_cert"):
            np.testing.assert_array_equal(plain[name].values, other[name].values)
    tilted = point_group(swept, "critical_points", {"alpha": 0.1, "omega0": 1.0, "torque": 0.3})
    np.testing.assert_allclose(tilted["theta"].values[tilted["n"].values == 0],
                               math.asin(0.3))


def _dop853_label(p: Pendulum, theta0, theta_dot0, barrier, t_end, spacing=0.05, piece=20.0):
    """The exact equation's fate by the same certificates, applied along a DOP853 orbit
    (rtol 1e-12) sampled every ``spacing`` s: the first sample at which the orbit is inside a
    well's energy trap (below the lower saddle's energy, between the well's saddles) gives its
    k; the first inside the running barrier, 'running'; None if neither by t_end. The orbit is
    integrated ``piece`` seconds at a time and stops at the first piece with a decided sample
    (the fate is the first such sample, so the rest of the orbit cannot change it)."""
    def rhs(_, y):
        return [y[1], p.torque - p.omega0**2 * math.sin(y[0]) - 2 * p.alpha * y[1]]

    y, start, end, per = [theta0, theta_dot0], 0, round(t_end / spacing), round(piece / spacing)
    while start < end:
        stop = min(start + per, end)
        sol = solve_ivp(rhs, (start * spacing, stop * spacing), y, method="DOP853", rtol=1e-12,
                        atol=1e-12, dense_output=True)
        if sol.status != 0:  # the integration failed: the samples it reached
            stop = math.ceil(sol.t[-1] / spacing)
        theta, theta_dot = sol.sol(np.arange(start, stop) * spacing)
        k = p.well(theta)
        trapped = p.energy(theta, theta_dot, k) < p.saddle_energy
        running = contains(barrier, theta, theta_dot) if barrier is not None else \
            np.zeros_like(trapped)
        if trapped.any() or running.any():
            first_trap = np.argmax(trapped) if trapped.any() else trapped.size
            first_run = np.argmax(running) if running.any() else running.size
            return int(k[first_trap]) if first_trap < first_run else "running"
        if sol.status != 0:
            return None
        y, start = sol.y[:, -1], stop
    return None


@pytest.mark.slow
@pytest.mark.parametrize("alpha, omega0, torque", [(0.05, 1.0, 0.5), (0.1, 1.0, 0.4),
                                                   (0.2, 1.5, -1.0)])
def test_certified_labels_are_the_exact_equations(tmp_path, alpha, omega0, torque):
    """Bistable swing pendulums (a running cycle and rest states): grid points certified for
    the exact equation (status trapped or running, farther than 10·d_cert from every
    boundary) get the same fate from DOP853 runs classified by the same certificates."""
    from atlas.physics.running import running_barrier

    p = Pendulum(alpha, omega0, torque)
    tree = small_atlas(tmp_path, "b", {"alpha": alpha, "omega0": omega0, "torque": torque},
                speed=(-8.0, 8.0), num=(28, 24))
    ds = tree.to_dataset(inherit=False)
    status, d = ds["status"].values, ds["boundary_distance"].values
    d_cert = float(ds["d_cert"])
    assert 0 < d_cert < 1e-6
    # the 2π shift holds for the RK4 map's boundaries: copies located on their own labels
    sep = tree["separatrices"]
    assert int(sep.attrs["shift_pairs"]) > 0
    assert float(sep.attrs["shift_error"]) <= 4 * float(sep.attrs["tol"])
    assert np.isnan(float(sep.attrs["symmetry_error"]))  # the point reflection is broken
    assert (status == RUNNING).any() and (status == TRAPPED).any()  # both kinds certified
    rng = np.random.default_rng(7)
    barrier = running_barrier(alpha, omega0, torque)
    sample = []
    for kind in (TRAPPED, RUNNING):  # eight of each: both certificates meet DOP853
        far = np.argwhere((status == kind) & (d > 10 * d_cert))
        assert len(far) >= 8, kind
        sample += list(far[rng.choice(len(far), min(8, len(far)), replace=False)])
    for j, i in sample:
        theta0, theta_dot0 = float(ds["theta0"][i]), float(ds["theta_dot0"][j])
        fate = _dop853_label(p, theta0, theta_dot0, barrier, 400.0)
        stored = "running" if status[j, i] == RUNNING else int(ds["attractor"].values[j, i])
        assert fate == stored, (theta0, theta_dot0, fate, stored)


@pytest.mark.slow
def test_without_rest_states_every_orbit_runs(tmp_path):
    """|τ| ≥ ω0²: no critical point, no boundary; every orbit is certified running, the
    running basin is the whole window, and atlas info says so plainly."""
    tree = small_atlas(tmp_path, "runs", {"alpha": 0.1, "omega0": 1.0, "torque": 1.5},
                speed=(-4.0, 4.0), t_max=200.0)
    ds = tree.to_dataset(inherit=False)
    assert np.all(ds["status"].values == RUNNING)
    assert float(ds["running_fraction_exact"]) == 1.0 and float(ds["running_fraction"]) == 1.0
    assert np.all(np.isinf(ds["boundary_distance"].values))
    assert tree["critical_points"].sizes["point"] == 0
    assert float(tree["limit_cycle"].attrs["period"]) > 0
    info = run_cli("info", tmp_path / "runs.h5")
    assert info.returncode == 0, info.stderr
    assert "none: |torque| > omega0^2, every orbit runs" in info.stdout


#: bSTAB's torque sweep and its published basin stability of the rest states (see below).
PUBLISHED = {0.16: 0.483, 0.31: 0.2756, 0.5: 0.152, 0.81: 0.0391}


@pytest.fixture(scope="module")
def bstab(tmp_path_factory):
    """bSTAB's pendulum over its torque sweep in its window (separatrices off), built once:
    the published basin stability and the swing plot read it (each torque point costs seconds
    of exact boundaries and certificates, whatever the grid)."""
    return small_atlas(tmp_path_factory.mktemp("bstab"), "bstab",
                       {"alpha": 0.05, "omega0": 1.0, "torque": list(PUBLISHED)},
                       speed=(-10.0, 10.0), num=(24, 24), separatrices=False)


@pytest.mark.slow
def test_the_published_basin_stability_of_the_torque_pendulum(bstab):
    """bSTAB's pendulum case (M. Stender and N. Hoffmann, "bSTAB: an open-source software for
    computing the basin stability of multi-stable dynamical systems", Nonlinear Dynamics 107,
    1451-1468 (2022), doi:10.1007/s11071-021-06786-5): theta'' = -0.1 theta' + T - sin(theta),
    sampled over theta in [-pi + asin 0.5, pi + asin 0.5] x theta' in [-10, 10] with
    N = 10,000 random initial conditions. Published: S_B(rest state) = 0.152 at T = 0.5
    (standard error 0.0036), and over their T-sweep (same window) 0.483 at T = 0.16, 0.2756
    at T = 0.31, 0.0391 at T = 0.81, each with a binomial error sqrt(S(1 - S)/N). atlas's
    exact fractions (all wells together) must lie within three of those standard errors;
    the running basin takes the rest."""
    ds = bstab.to_dataset(inherit=False)
    assert sorted(point["torque"] for point in points(ds)) == sorted(PUBLISHED)
    for point in points(ds):
        one = at_point(ds, point)
        rest = float(one["basin_fraction_exact"].sum("k"))
        error = float(one["basin_fraction_exact_error"].sum("k"))
        running = float(one["running_fraction_exact"])
        s = PUBLISHED[point["torque"]]
        sigma = 0.0036 if point["torque"] == 0.5 else math.sqrt(s * (1 - s) / 1e4)
        assert abs(rest - s) < 3 * sigma, (point, rest, s)
        assert abs(rest + running - 1.0) < 1e-9 and error < 1e-6
    # and the grid counts of the same atlas sit within their own error bounds
    grid = ds["basin_fraction"].sum("k")
    bound = ds["basin_fraction_grid_error_bound"].sum("k")
    exact = ds["basin_fraction_exact"].sum("k")
    assert np.all(np.abs(grid - exact) <= bound)


@pytest.mark.slow
def test_swing_plot_draws_the_running_basin_and_the_limit_cycle(bstab):
    from atlas.views.plotting import basin_map, basin_stability

    tree = bstab
    ax = basin_map(tree, torque=2)  # the third point of the sweep: τ = 0.5
    labels = [line.get_label() for line in ax.lines]
    assert any(label.startswith("limit cycle (period") for label in labels)
    cycle = point_group(tree, "limit_cycle", {"alpha": 0.05, "omega0": 1.0, "torque": 0.5})
    line = next(ln for ln in ax.lines if ln.get_label().startswith("limit cycle"))
    np.testing.assert_array_equal(np.sort(line.get_ydata()), np.sort(cycle["theta_dot"].values))
    names = [t.get_text() for t in ax.figure.axes[-1].get_yticklabels()]
    assert "running" in names
    ax = basin_stability(tree)
    rest = next(ln for ln in ax.lines if ln.get_label() == "rest states, exact area")
    np.testing.assert_array_equal(rest.get_xdata(), list(PUBLISHED))
    np.testing.assert_allclose(
        rest.get_ydata(), tree["basin_fraction_exact"].sum("k").values, rtol=0, atol=0)


def test_the_saddle_node_torque_is_refused(tmp_path):
    """|τ| = ω0² exactly: the rest state (π/2, 0) is a degenerate saddle-node whose basin atlas
    does not certify (no rest state is not the same as every orbit running): one line, exit
    2, nothing written."""
    cfg = tmp_path / "sn.yaml"
    cfg.write_text(f"pendulum: {{alpha: 0.05, omega0: 1.0, torque: [0.5, -1.0]}}\n"
                   f"output: {tmp_path / 'sn.h5'}\n")
    proc = run_cli("run", cfg)
    assert proc.returncode == 2 and "saddle-node" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sn.yaml"]


def test_a_step_too_coarse_for_the_running_barrier_is_refused_before_work(tmp_path):
    """dt = 0.1 is fine without torque but too coarse for the running speeds of the swing
    pendulum (RK4's local error would exceed the barrier's margins): one line naming
    integrator.dt, exit 2, nothing written."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("pendulum: {alpha: 0.05, omega0: 1.0, torque: 0.5}\n"
                   "grid: {theta0: {start: -5pi/6, stop: 7pi/6, num: 8},\n"
                   "       theta_dot0: {start: -10, stop: 10, num: 8}}\n"
                   "integrator: {dt: 0.1, t_max: 400}\n"
                   f"output: {tmp_path / 'c.h5'}\n")
    proc = run_cli("run", cfg)
    assert proc.returncode == 2 and proc.stderr.startswith("atlas: error: integrator.dt:")
    assert len(proc.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]
