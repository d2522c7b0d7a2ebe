"""Separatrices: bisection on certified labels against independent references.

References: scipy's DOP853 (rtol = atol = 1e-13) integrating the stable manifold of each saddle
in reversed time, written here per branch without the module's symmetry shortcut; the
undamped separatrix θ̇ = ±2ω0 cos(θ/2) (α → 0); RK4's order 4 (Richardson); the point
reflection (θ, θ̇) → (−θ, −θ̇); and the labels themselves at ±tol across every point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import atlas
from atlas import defaults
from atlas import separatrices as sep
from atlas.errors import AtlasError
from atlas.limits import MIN_MAX_SPACING, MIN_TOL_ULPS, check_separatrix_settings
from atlas.model import Pendulum

PI = math.pi
DEFAULT_WINDOW = (defaults.THETA0_WINDOW, defaults.THETA_DOT0_WINDOW)
TOL = defaults.SEPARATRIX_TOL
REGIMES = {"underdamped": 0.1, "critically damped": 1.0, "overdamped": 2.0}  # ω0 = 1


@pytest.fixture(scope="module")
def traced():
    """The default-window trace of each regime, at default settings (computed once)."""
    return {a: sep.trace(Pendulum(a, 1.0), *DEFAULT_WINDOW) for a in REGIMES.values()}


def certified(p: Pendulum, theta, theta_dot, dt=0.01, t_max=400.0):
    """Labels of atlas.label for bisect_across: sep.NO_LABEL where not trapped."""
    res = atlas.label(theta, theta_dot, alpha=p.alpha, omega0=p.omega0, dt=dt, t_max=t_max)
    return np.where(res.status == 0, res.attractor, sep.NO_LABEL)


def field_normal(p: Pendulum, theta, theta_dot):
    """Unit normal to the vector field of eq. (1), pointing to larger θ̇."""
    f0, f1 = theta_dot, -p.omega0**2 * np.sin(theta) - 2 * p.alpha * theta_dot
    norm = np.hypot(f0, f1) * np.sign(f0)
    return np.column_stack([-f1 / norm, f0 / norm])


def dop853_distances(p: Pendulum, ds: xr.Dataset, every: int = 7) -> np.ndarray:
    """Distance from every ``every``-th point of each branch to that branch's own stable
    manifold, integrated in reversed time by DOP853 from 1e-7 along the eigenvector until it
    leaves the θ window (or exceeds the window's energy); foot points on the dense output."""
    u2 = p.alpha + math.hypot(p.alpha, p.omega0)
    e = np.array([1.0, -u2]) / math.hypot(1.0, u2)
    (t_lo, t_hi), (v_lo, v_hi) = DEFAULT_WINDOW
    e_max = 0.5 * max(v_lo**2, v_hi**2) + 2 * p.omega0**2
    out = []
    for n, branch, theta, theta_dot in sep.branches(ds):
        side = -1.0 if branch == "left" else 1.0

        def rhs(_, y):
            return [-y[1], p.omega0**2 * math.sin(y[0]) + 2 * p.alpha * y[1]]

        def gone(_, y, side=side):
            energy = 0.5 * y[1] ** 2 + p.omega0**2 * (1 - math.cos(y[0]))
            return min(y[0] - t_lo if side < 0 else t_hi - y[0], e_max - energy)

        gone.terminal = True
        y0 = np.array([n * PI, 0.0]) + side * 1e-7 * e
        sol = solve_ivp(rhs, (0, 1e3), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                        dense_output=True, events=gone)
        grid = np.linspace(0, sol.t[-1], 20_000)
        curve = sol.sol(grid)
        for q in zip(theta[::every], theta_dot[::every], strict=True):
            # foot point: root of (c(t) − q)·c'(t) between the neighbours of the nearest sample
            i = int(np.argmin(np.hypot(curve[0] - q[0], curve[1] - q[1])))
            lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
            foot = brentq(lambda t, sol=sol, q=q: np.dot(sol.sol(t) - q, rhs(t, sol.sol(t))),
                          lo, hi, xtol=1e-16)
            out.append(np.hypot(*(sol.sol(foot) - q)))
    return np.array(out)


@pytest.mark.parametrize("regime", REGIMES)
def test_bisection_agrees_with_backward_integration(traced, regime):
    alpha = REGIMES[regime]
    p = Pendulum(alpha, 1.0)
    ds = traced[alpha]
    assert ds.sizes["point"] > 300
    assert np.all(ds["bracket_width"].values < TOL)
    # this test's own DOP853 reference, one integration per branch
    independent = dop853_distances(p, ds)
    assert independent.max() < 1e-8
    # the module's check reports the same kind of number, for every point
    assert ds.attrs["discrepancy"] < ds.attrs["discrepancy_bound"] == 1e-8
    assert ds.attrs["discrepancy"] >= independent.max() - 1e-12
    assert sep.warnings(ds) == []
    # the polyline between vertices, not only the vertices, follows the curve
    assert ds.attrs["polyline_error"] < ds.attrs["max_spacing"] ** 2 / 8


def test_points_cover_each_branch_from_saddle_to_window_edge(traced):
    ds = traced[0.1]
    (t_lo, t_hi), (v_lo, v_hi) = DEFAULT_WINDOW
    found = {(n, b): (th, v) for n, b, th, v in sep.branches(ds)}
    # saddles ±π, ±3π; the right branch of 3π and the left branch of −3π lie outside
    assert set(found) == {(-3, "right"), (-1, "left"), (-1, "right"), (1, "left"),
                          (1, "right"), (3, "left")}
    for (n, b), (th, v) in found.items():
        assert math.hypot(th[0] - n * PI, v[0]) < ds.attrs["max_spacing"]  # near the saddle
        assert np.all(np.sign(v) == (1 if b == "left" else -1))
        assert np.all(np.diff(th) < 0) if b == "left" else np.all(np.diff(th) > 0)
        edge = min(th[-1] - t_lo, t_hi - th[-1], v[-1] - v_lo, v_hi - v[-1])
        assert abs(edge) < 1e-9
        spacing = np.hypot(np.diff(th), np.diff(v))
        assert spacing.max() <= ds.attrs["max_spacing"]


@pytest.mark.parametrize("alpha", [0.1, 2.0])
def test_labels_differ_at_plus_minus_tol_across_every_point(traced, alpha):
    p = Pendulum(alpha, 1.0)
    ds = traced[alpha]
    theta, theta_dot = ds["theta"].values, ds["theta_dot"].values
    normal = field_normal(p, theta, theta_dot)
    n = ds["saddle_n"].values
    t_max = ds.attrs["t_max"]
    for side, k in ((+1, (n + 1) // 2), (-1, (n - 1) // 2)):
        res = atlas.label(theta + side * TOL * normal[:, 0],
                          theta_dot + side * TOL * normal[:, 1],
                          alpha=p.alpha, omega0=p.omega0, t_max=t_max)
        assert np.all(res.status == 0)
        np.testing.assert_array_equal(res.attractor, k)


def test_halving_dt_shifts_points_as_rk4_order_four():
    """The located curve is RK4's basin boundary: its offset from the exact manifold is
    C·dt⁴. Re-bisect across the same lines at dt = 0.08, 0.04, 0.02, 0.01: successive shifts
    fall 16-fold, and the Richardson estimate of the dt = 0.01 error matches the DOP853
    discrepancy."""
    p = Pendulum(0.1, 1.0)
    window = ((0.0, PI), (0.0, 3.0))  # the left branch of the saddle π down to θ = 0
    ds = sep.trace(p, *window)
    base = np.column_stack([ds["theta"].values, ds["theta_dot"].values])
    normal = field_normal(p, base[:, 0], base[:, 1])
    k = (ds["saddle_n"].values + 1) // 2
    offset = {}
    for dt in (0.08, 0.04, 0.02, 0.01):
        lo, hi = sep.bisect_across(lambda th, v, dt=dt: certified(p, th, v, dt=dt), base,
                                   normal, k, tol=TOL, half_width=1e-11)
        offset[dt] = 0.5 * (lo + hi)
    shifts = [np.abs(offset[a] - offset[a / 2]).max() for a in (0.08, 0.04, 0.02)]
    orders = np.log2(np.array(shifts[:-1]) / np.array(shifts[1:]))
    np.testing.assert_allclose(orders, 4.0, atol=0.25)
    assert np.abs(offset[0.01]).max() < TOL  # the traced points are the dt = 0.01 boundary
    richardson = np.abs(offset[0.02] - offset[0.01]).max() / 15
    assert 0.5 * richardson < ds.attrs["discrepancy"] < 2 * richardson + 2 * TOL


def test_point_reflection_symmetry(traced):
    found = {(n, b): (th, v) for n, b, th, v in sep.branches(traced[0.1])}
    for (n, b), (th, v) in found.items():
        mirror = found[(-n, "right" if b == "left" else "left")]
        assert mirror[0].size == th.size
        np.testing.assert_allclose(-mirror[0], th, rtol=0, atol=TOL)
        np.testing.assert_allclose(-mirror[1], v, rtol=0, atol=TOL)


def test_approaches_undamped_separatrix_as_alpha_vanishes():
    """θ̇ = ±2ω0 cos(θ/2) at α = 0. Damping adds the energy 2α∫|θ̇|dθ along the branch, to
    first order 2α·4ω0 between the saddle and the well bottom, where θ̇ = 2ω0: so |θ̇| exceeds
    the undamped curve by at most ≈ 4α there (ω0 = 1)."""
    window = ((-PI, PI), (-3.0, 3.0))
    alphas = np.array([0.2, 0.1, 0.05])
    deviation = []
    for alpha in alphas:
        ds = sep.trace(Pendulum(alpha, 1.0), *window)
        th, v, n = ds["theta"].values, ds["theta_dot"].values, ds["saddle_n"].values
        half = np.abs(th - n * PI) <= PI  # from the saddle to the bottom of the well
        assert half.sum() > 50
        deviation.append(np.max(np.abs(np.abs(v) - 2 * np.abs(np.cos(th / 2)))[half]))
    assert np.all(np.diff(deviation) < 0)
    np.testing.assert_allclose(np.array(deviation) / alphas, 4.0, rtol=0.1)


def test_alpha_zero_is_rejected_with_the_reason():
    with pytest.raises(ValueError, match="energy is conserved"):
        sep.trace(Pendulum(0.0, 1.0), *DEFAULT_WINDOW)


def dop853_axis_crossing(p: Pendulum, n: int) -> float:
    """θ̇ where the stable manifold of the saddle nπ that arrives from the side of θ = 0 (the
    left branch for n > 0, the right one for n < 0) meets θ = 0: DOP853 in reversed time
    from 1e-7 along the stable eigenvector, event θ = 0 (no symmetry used)."""
    u2 = p.alpha + math.hypot(p.alpha, p.omega0)
    side = -1.0 if n > 0 else 1.0
    y0 = np.array([n * PI, 0.0]) + side * 1e-7 * np.array([1.0, -u2]) / math.hypot(1.0, u2)

    def axis(_, y):
        return y[0]

    axis.terminal = True
    sol = solve_ivp(lambda _, y: [-y[1], p.omega0**2 * math.sin(y[0]) + 2 * p.alpha * y[1]],
                    (0, 1e3), y0, method="DOP853", rtol=1e-13, atol=1e-13, events=axis)
    return float(sol.y_events[0][0, 1])


def test_axis_crossings_straddle_a_label_change(traced):
    p = Pendulum(0.1, 1.0)
    ds = traced[0.1]
    crossing = ds["crossing_theta_dot"].values
    # the boundary between basins k − 1 and k on θ0 = 0 is the manifold of the saddle 2k − 1
    np.testing.assert_array_equal(ds["k_above"].values, [-1, 0, 1, 2])
    reference = [dop853_axis_crossing(p, 2 * k - 1) for k in ds["k_above"].values]
    np.testing.assert_allclose(crossing, reference, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(ds["k_above"].values - ds["k_below"].values, 1)
    assert np.all(ds["crossing_bracket_width"].values < TOL)
    for side, k in ((-1, ds["k_below"].values), (+1, ds["k_above"].values)):
        res = atlas.label(0.0, crossing + side * TOL, alpha=p.alpha, omega0=p.omega0,
                          t_max=ds.attrs["t_max"])
        assert np.all(res.status == 0)
        np.testing.assert_array_equal(res.attractor, k)


def test_axis_crossing_matches_dop853_manifold():
    """Where the left branch of π meets θ = 0, with no saddle in the window."""
    p = Pendulum(0.1, 1.0)
    ds = sep.trace(p, (-0.5, 0.5), (0.0, 3.0))  # no saddle inside: only the crossing table
    assert ds.sizes["point"] == 0
    np.testing.assert_allclose(ds["crossing_theta_dot"].values, [dop853_axis_crossing(p, 1)],
                               rtol=0, atol=1e-9)


def test_bisect_across_on_a_known_boundary_with_an_uncertified_band():
    """Synthetic labels: basin 1 above θ̇ = 0.3 + 0.1θ, basin 0 below, no certified label
    within 1e-13 of the line (like orbits stuck at a saddle in floating point)."""
    def labels(theta, theta_dot):
        gap = theta_dot - (0.3 + 0.1 * theta)
        return np.where(np.abs(gap) < 1e-13, sep.NO_LABEL, (gap > 0).astype(np.int64))

    theta = np.linspace(-1, 1, 50)
    boundary = 3e-10 * np.sin(7 * theta)  # offsets up to 30 first half-widths
    base = np.column_stack([theta, 0.3 + 0.1 * theta - boundary])
    direction = np.broadcast_to([0.0, 1.0], base.shape)
    lo, hi = sep.bisect_across(labels, base, direction, 1, tol=TOL, half_width=1e-11)
    assert np.all((lo < boundary) & (boundary < hi) & (hi - lo < TOL))
    with pytest.raises(sep.SeparatrixError, match="raise tol") as failure:
        sep.bisect_across(labels, base, direction, 1, tol=1e-13, half_width=1e-11)
    assert isinstance(failure.value, AtlasError) and "\n" not in str(failure.value)


def test_discrepancy_above_bound_is_reported():
    """At dt = 0.1 RK4's boundary lies ~1e-5 from the manifold: the summary must say so."""
    ds = sep.trace(Pendulum(0.1, 1.0), (0.0, PI), (0.0, 3.0), dt=0.1)
    assert ds.attrs["discrepancy"] > ds.attrs["discrepancy_bound"]
    assert sep.warnings(ds) and "lower dt" in sep.warnings(ds)[0]
    assert any("EXCEEDS" in line for line in sep.summary(ds))


def test_dataset_round_trips_through_h5netcdf(traced, tmp_path):
    ds = traced[0.1]
    path = tmp_path / "sep.h5"
    ds.to_netcdf(path, engine="h5netcdf")
    with xr.open_dataset(path, engine="h5netcdf") as back:
        xr.testing.assert_identical(back.load(), ds)
        # the stored group carries everything the independent check needs
        again = sep.check_against_stable_manifold(back)
    assert again.discrepancy == sep.max_discrepancy(ds)
    assert again.polyline_error == ds.attrs["polyline_error"]
    assert all(v.dtype != object for v in ds.variables.values())
    assert ds["branch"].attrs["flag_meanings"] == "left right"
    for name in ("theta", "theta_dot", "bracket_width", "crossing_theta_dot"):
        assert {"units", "long_name"} <= set(ds[name].attrs)
    for name in ("tol", "max_spacing", "dt", "discrepancy", "discrepancy_bound", "method"):
        assert name in ds.attrs
    lines = sep.summary(ds)
    assert "4 saddles" in lines[0] and "6 branches" in lines[0]
    assert "within bound" in lines[1]
    assert f"{ds['crossing_theta_dot'].values[2]:+.10f} (0|1)" in lines[2]


@pytest.mark.parametrize(("tol", "max_spacing", "culprit"), [
    (1e-14, 0.05, r"tol = 1e-14 is below .* \|θ\| ≤ 9.42 \(needs ≥ 1.2e-13\)"),
    (0.0, 0.05, "tol must be"),
    (1e-12, 5e-5, "max_spacing = 5e-05 is below 0.0001"),
    (1e-12, math.inf, "max_spacing must be"),
])
def test_unusable_settings_are_refused_before_any_work(tol, max_spacing, culprit):
    with pytest.raises(ValueError, match=culprit) as refused:
        check_separatrix_settings(*DEFAULT_WINDOW, tol, max_spacing)
    assert "\n" not in str(refused.value)
    with pytest.raises(ValueError, match=culprit):
        sep.trace(Pendulum(0.1, 1.0), *DEFAULT_WINDOW, tol=tol, max_spacing=max_spacing)


def test_the_bounds_scale_with_the_window_and_are_inclusive():
    check_separatrix_settings(*DEFAULT_WINDOW, TOL, defaults.MAX_SPACING)  # the defaults pass
    smallest = MIN_TOL_ULPS * np.spacing(3 * PI)
    check_separatrix_settings(*DEFAULT_WINDOW, smallest, MIN_MAX_SPACING)
    with pytest.raises(ValueError, match="tol"):
        check_separatrix_settings(*DEFAULT_WINDOW, np.nextafter(smallest, 0), MIN_MAX_SPACING)
    with pytest.raises(ValueError, match=r"\|θ̇\| ≤ 40"):  # θ̇ sets the scale here
        check_separatrix_settings((-1.0, 1.0), (-40.0, 40.0), smallest, MIN_MAX_SPACING)


def test_smallest_accepted_tol_runs_to_the_end():
    """At the bound, orbits stuck at the saddle in floating point can keep brackets wider
    than tol (α = 2): trace stores their widths and says so, it does not raise."""
    window = ((0.0, PI), (0.0, 3.0))
    tol = MIN_TOL_ULPS * np.spacing(PI)
    ds = sep.trace(Pendulum(2.0, 1.0), *window, tol=tol)
    wide = int(np.sum(ds["bracket_width"].values >= tol))
    assert ds.sizes["point"] > 50 and ds.attrs["discrepancy"] < ds.attrs["discrepancy_bound"]
    assert (wide == 0) == (sep.warnings(ds) == [])


def test_a_failure_during_the_run_is_one_line_for_the_cli(monkeypatch):
    monkeypatch.setattr(sep, "_MAX_VERTICES", 10)
    with pytest.raises(sep.SeparatrixError, match="raise separatrices.max_spacing") as failed:
        sep.trace(Pendulum(0.1, 1.0), *DEFAULT_WINDOW)
    assert isinstance(failed.value, AtlasError) and failed.value.exit_code == 1
    assert "\n" not in str(failed.value)
