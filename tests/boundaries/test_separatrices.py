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
from atlas.boundaries.bisection import NO_LABEL, bisect_across
from atlas.boundaries.check import SYMMETRY_BOUND, check_against_stable_manifold
from atlas.boundaries.trace import trace
from atlas.errors import AtlasError, SeparatrixError
from atlas.limits import MIN_MAX_SPACING, MIN_TOL_ULPS, check_separatrix_settings
from atlas.physics.pendulum import Pendulum
from atlas.store.separatrices import branches, max_discrepancy, warnings
from atlas.views.info import separatrix_lines

PI = math.pi
DEFAULT_WINDOW = (defaults.THETA0_WINDOW, defaults.THETA_DOT0_WINDOW)
TOL = defaults.SEPARATRIX_TOL
REGIMES = {"underdamped": 0.1, "critically damped": 1.0, "overdamped": 2.0}  # ω0 = 1


@pytest.fixture(scope="module")
def traced():
    """The default-window trace of each regime, at default settings (computed once)."""
    return {a: trace(Pendulum(a, 1.0), *DEFAULT_WINDOW) for a in REGIMES.values()}


def certified(p: Pendulum, theta, theta_dot, dt=0.01, t_max=400.0):
    """Labels of atlas.label for bisect_across: NO_LABEL where not trapped."""
    res = atlas.label(theta, theta_dot, alpha=p.alpha, omega0=p.omega0, dt=dt, t_max=t_max)
    return np.where(res.status == 0, res.attractor, NO_LABEL)


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
    for n, branch, theta, theta_dot in branches(ds):
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


@pytest.mark.slow
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
    assert warnings(ds) == []
    # the polyline between vertices, not only the vertices, follows the curve
    assert ds.attrs["polyline_error"] < ds.attrs["max_spacing"] ** 2 / 8


def window_margin(window, theta, theta_dot):
    """Distance inside the window along the axes (≥ 0 inside, < 0 outside)."""
    (t_lo, t_hi), (v_lo, v_hi) = window
    return np.minimum(np.minimum(theta - t_lo, t_hi - theta),
                      np.minimum(theta_dot - v_lo, v_hi - theta_dot))


def test_points_cover_each_branch_from_saddle_to_window_edge(traced):
    ds = traced[0.1]
    spacing_max = ds.attrs["max_spacing"]
    found = {}
    for n, b, th, v in branches(ds):
        found.setdefault((n, b), []).append((th, v))
    # saddles ±π, ±3π inside; the right branch of 3π and the left branch of −3π lie outside,
    # and the left branches of 5π, 7π (right of −5π, −7π) enter from beyond the window
    assert set(found) == {(-7, "right"), (-5, "right"), (-3, "right"), (-1, "left"),
                          (-1, "right"), (1, "left"), (1, "right"), (3, "left"), (5, "left"),
                          (7, "left")}
    assert ds.attrs["n_boundaries"] == 8
    for (n, b), pieces in found.items():
        for th, v in pieces:
            assert np.all(np.sign(v) == (1 if b == "left" else -1))
            assert np.all(np.diff(th) < 0) if b == "left" else np.all(np.diff(th) > 0)
            assert np.hypot(np.diff(th), np.diff(v)).max() <= spacing_max
            margin = window_margin(DEFAULT_WINDOW, th, v)
            assert np.all(margin[1:-1] > -1e-9)  # inside, or on an edge within the curve's accuracy
            # each end: next to the saddle, on the window's edge, or the one point beyond it
            for end in (0, -1):
                at_saddle = math.hypot(th[end] - n * PI, v[end]) < spacing_max
                assert at_saddle or -spacing_max < margin[end] < 1e-9
        # the branch of a saddle inside the window starts next to it
        if abs(n) <= 3:
            assert math.hypot(pieces[0][0][0] - n * PI, pieces[0][1][0]) < spacing_max


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


@pytest.mark.slow
def test_halving_dt_shifts_points_as_rk4_order_four():
    """The located curve is RK4's basin boundary: its offset from the exact manifold is
    C·dt⁴. Re-bisect across the same lines at dt = 0.08, 0.04, 0.02, 0.01: successive shifts
    fall 16-fold, and the Richardson estimate of the dt = 0.01 error matches the DOP853
    discrepancy."""
    p = Pendulum(0.1, 1.0)
    window = ((0.0, PI), (0.0, 3.0))  # the left branch of the saddle π down to θ = 0
    ds = trace(p, *window)
    base = np.column_stack([ds["theta"].values, ds["theta_dot"].values])
    normal = field_normal(p, base[:, 0], base[:, 1])
    k = (ds["saddle_n"].values + 1) // 2
    offset = {}
    for dt in (0.08, 0.04, 0.02, 0.01):
        lo, hi = bisect_across(lambda th, v, dt=dt: certified(p, th, v, dt=dt), base,
                                   normal, k, tol=TOL, half_width=1e-11)
        offset[dt] = 0.5 * (lo + hi)
    shifts = [np.abs(offset[a] - offset[a / 2]).max() for a in (0.08, 0.04, 0.02)]
    orders = np.log2(np.array(shifts[:-1]) / np.array(shifts[1:]))
    np.testing.assert_allclose(orders, 4.0, atol=0.25)
    assert np.abs(offset[0.01]).max() < TOL  # the traced points are the dt = 0.01 boundary
    richardson = np.abs(offset[0.02] - offset[0.01]).max() / 15
    assert 0.5 * richardson < ds.attrs["discrepancy"] < 2 * richardson + 2 * TOL


@pytest.mark.parametrize("alpha", REGIMES.values())
def test_point_reflection_symmetry(traced, alpha):
    """The right branch of −π is the point reflection of the left branch of π: its points are
    the reflections where both are needed (the RK4 map is odd), and every 8th is located
    again on its own: those lie within the bisection tolerance of the reflections, as the
    attribute says (over that many pairs), and the stored copies (in the symmetric default
    window, vertex by vertex) show."""
    ds = traced[alpha]
    assert 0.0 <= ds.attrs["symmetry_error"] < TOL
    shared = np.intersect1d(ds["vertex"].values[ds["branch"].values == 0],
                            ds["vertex"].values[ds["branch"].values == 1]).size
    assert 0 < ds.attrs["symmetry_pairs"] <= shared // 4
    assert ds.attrs["symmetry_bound"] == SYMMETRY_BOUND * TOL
    n, b, vertex = (ds[name].values for name in ("saddle_n", "branch", "vertex"))
    theta, theta_dot = ds["theta"].values, ds["theta_dot"].values
    for key in set(zip(n.tolist(), b.tolist(), strict=True)):
        here = np.flatnonzero((n == key[0]) & (b == key[1]))
        there = np.flatnonzero((n == -key[0]) & (b == 1 - key[1]))
        here, there = here[np.argsort(vertex[here])], there[np.argsort(vertex[there])]
        np.testing.assert_array_equal(vertex[here], vertex[there])
        np.testing.assert_allclose(-theta[there], theta[here], rtol=0, atol=TOL)
        np.testing.assert_allclose(-theta_dot[there], theta_dot[here], rtol=0, atol=TOL)


@pytest.mark.slow
def test_approaches_undamped_separatrix_as_alpha_vanishes():
    """θ̇ = ±2ω0 cos(θ/2) at α = 0. Damping adds the energy 2α∫|θ̇|dθ along the branch, to
    first order 2α·4ω0 between the saddle and the well bottom, where θ̇ = 2ω0: so |θ̇| exceeds
    the undamped curve by at most ≈ 4α there (ω0 = 1)."""
    window = ((-PI, PI), (-3.0, 3.0))
    alphas = np.array([0.2, 0.1, 0.05])
    deviation = []
    for alpha in alphas:
        ds = trace(Pendulum(alpha, 1.0), *window)
        th, v, n = ds["theta"].values, ds["theta_dot"].values, ds["saddle_n"].values
        half = np.abs(th - n * PI) <= PI  # from the saddle to the bottom of the well
        assert half.sum() > 50
        deviation.append(np.max(np.abs(np.abs(v) - 2 * np.abs(np.cos(th / 2)))[half]))
    assert np.all(np.diff(deviation) < 0)
    np.testing.assert_allclose(np.array(deviation) / alphas, 4.0, rtol=0.1)


def test_alpha_zero_is_rejected_with_the_reason():
    with pytest.raises(ValueError, match="energy is conserved"):
        trace(Pendulum(0.0, 1.0), *DEFAULT_WINDOW)


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
    """One crossing per boundary entering the window (saddles ±1, …, ±7), also those beyond
    the window's θ̇ range; each where DOP853 puts that saddle's own branch on θ = 0, within
    RK4's offset from the exact manifold at dt = 0.01 (the discrepancy, ≈ 6e-10)."""
    p = Pendulum(0.1, 1.0)
    ds = traced[0.1]
    crossing = ds["crossing_theta_dot"].values
    # the boundary between basins k − 1 and k on θ0 = 0 is the manifold of the saddle 2k − 1
    np.testing.assert_array_equal(ds["k_above"].values, [-3, -2, -1, 0, 1, 2, 3, 4])
    np.testing.assert_array_equal(2 * ds["k_above"].values - 1, np.unique(ds["saddle_n"]))
    reference = [dop853_axis_crossing(p, 2 * k - 1) for k in ds["k_above"].values]
    np.testing.assert_allclose(crossing, reference, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(ds["crossing_in_window"].values,
                                  np.abs(crossing) <= DEFAULT_WINDOW[1][1])
    assert ds["crossing_in_window"].values.sum() == 4
    np.testing.assert_array_equal(ds["k_above"].values - ds["k_below"].values, 1)
    assert np.all(ds["crossing_bracket_width"].values < TOL)
    for side, k in ((-1, ds["k_below"].values), (+1, ds["k_above"].values)):
        res = atlas.label(0.0, crossing + side * TOL, alpha=p.alpha, omega0=p.omega0,
                          t_max=ds.attrs["t_max"])
        assert np.all(res.status == 0)
        np.testing.assert_array_equal(res.attractor, k)


def test_axis_crossing_matches_dop853_manifold():
    """Where the left branch of π meets θ = 0, with no saddle in the window: the window
    holds a piece of that branch only, and its crossing."""
    p = Pendulum(0.1, 1.0)
    ds = trace(p, (-0.5, 0.5), (0.0, 3.0))
    assert set(zip(ds["saddle_n"].values.tolist(), ds["branch"].values.tolist())) == {(1, 0)}
    assert ds.sizes["point"] > 10 and ds.attrs["n_boundaries"] == 1
    np.testing.assert_allclose(ds["crossing_theta_dot"].values, [dop853_axis_crossing(p, 1)],
                               rtol=0, atol=1e-9)
    assert ds["crossing_in_window"].values.tolist() == [1]
    assert math.isnan(ds.attrs["symmetry_error"])  # θ̇ ≥ 0: the right branch is not needed


def test_bisect_across_on_a_known_boundary_with_an_uncertified_band():
    """Synthetic labels: basin 1 above θ̇ = 0.3 + 0.1θ, basin 0 below, no certified label
    within 1e-13 of the line (like orbits stuck at a saddle in floating point)."""
    def labels(theta, theta_dot):
        gap = theta_dot - (0.3 + 0.1 * theta)
        return np.where(np.abs(gap) < 1e-13, NO_LABEL, (gap > 0).astype(np.int64))

    theta = np.linspace(-1, 1, 50)
    boundary = 3e-10 * np.sin(7 * theta)  # offsets up to 30 first half-widths
    base = np.column_stack([theta, 0.3 + 0.1 * theta - boundary])
    direction = np.broadcast_to([0.0, 1.0], base.shape)
    lo, hi = bisect_across(labels, base, direction, 1, tol=TOL, half_width=1e-11)
    assert np.all((lo < boundary) & (boundary < hi) & (hi - lo < TOL))
    with pytest.raises(SeparatrixError, match="raise tol") as failure:
        bisect_across(labels, base, direction, 1, tol=1e-13, half_width=1e-11)
    assert isinstance(failure.value, AtlasError) and "\n" not in str(failure.value)


def test_discrepancy_above_bound_is_reported():
    """At dt = 0.1 RK4's boundary lies ~1e-5 from the manifold: the summary must say so."""
    ds = trace(Pendulum(0.1, 1.0), (0.0, PI), (0.0, 3.0), dt=0.1)
    assert ds.attrs["discrepancy"] > ds.attrs["discrepancy_bound"]
    assert warnings(ds) and "lower dt" in warnings(ds)[0]
    assert any("EXCEEDS" in line for line in separatrix_lines(ds))


def test_dataset_round_trips_through_h5netcdf(traced, tmp_path):
    ds = traced[0.1]
    path = tmp_path / "sep.h5"
    ds.to_netcdf(path, engine="h5netcdf")
    with xr.open_dataset(path, engine="h5netcdf") as back:
        xr.testing.assert_identical(back.load(), ds)
        # the stored group carries everything the independent check needs
        again = check_against_stable_manifold(back)
    assert again.discrepancy == max_discrepancy(ds)
    assert again.polyline_error == ds.attrs["polyline_error"]
    assert all(v.dtype != object for v in ds.variables.values())
    assert ds["branch"].attrs["flag_meanings"] == "left right"
    for name in ("theta", "theta_dot", "bracket_width", "crossing_theta_dot"):
        assert {"units", "long_name"} <= set(ds[name].attrs)
    for name in ("tol", "max_spacing", "dt", "discrepancy", "discrepancy_bound", "method"):
        assert name in ds.attrs
    lines = separatrix_lines(ds)
    assert "8 basin boundaries" in lines[0] and "10 branches" in lines[0]
    assert "symmetry" in lines[1] and "within bound" in lines[1]
    assert "within bound" in lines[2]
    assert f"{ds['crossing_theta_dot'].values[4]:+.10f} (0|1)," in lines[3]
    assert f"{ds['crossing_theta_dot'].values[7]:+.10f} (3|4)*" in lines[3]


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
        trace(Pendulum(0.1, 1.0), *DEFAULT_WINDOW, tol=tol, max_spacing=max_spacing)


def test_the_bounds_scale_with_the_window_and_are_inclusive():
    check_separatrix_settings(*DEFAULT_WINDOW, TOL, defaults.MAX_SPACING)  # the defaults pass
    smallest = MIN_TOL_ULPS * np.spacing(3 * PI)
    check_separatrix_settings(*DEFAULT_WINDOW, smallest, MIN_MAX_SPACING)
    with pytest.raises(ValueError, match="tol"):
        check_separatrix_settings(*DEFAULT_WINDOW, np.nextafter(smallest, 0), MIN_MAX_SPACING)
    with pytest.raises(ValueError, match=r"\|θ̇\| ≤ 40"):  # θ̇ sets the scale here
        check_separatrix_settings((-1.0, 1.0), (-40.0, 40.0), smallest, MIN_MAX_SPACING)


@pytest.mark.slow
def test_smallest_accepted_tol_runs_to_the_end():
    """At the bound, orbits stuck at the saddle in floating point can keep brackets wider
    than tol (α = 2): trace stores their widths and says so, it does not raise."""
    window = ((0.0, PI), (0.0, 3.0))
    tol = MIN_TOL_ULPS * np.spacing(PI)
    ds = trace(Pendulum(2.0, 1.0), *window, tol=tol)
    wide = int(np.sum(ds["bracket_width"].values >= tol))
    assert ds.sizes["point"] > 50 and ds.attrs["discrepancy"] < ds.attrs["discrepancy_bound"]
    assert (wide == 0) == (warnings(ds) == [])


def test_a_failure_during_the_run_is_one_line_for_the_cli(monkeypatch):
    from atlas.boundaries import predictor

    monkeypatch.setattr(predictor, "_MAX_VERTICES", 10)
    with pytest.raises(SeparatrixError, match="raise separatrices.max_spacing") as failed:
        trace(Pendulum(0.1, 1.0), *DEFAULT_WINDOW)
    assert isinstance(failed.value, AtlasError) and failed.value.exit_code == 1
    assert "\n" not in str(failed.value)


# --------------------------------------------------------------------------- completeness

OFF_CENTRE = ((PI / 3, 11 * PI / 2), (-4.0, 4.0))
#: (α, ω0, dt, window): each regime, ω0 ≠ 1 (at a dt that keeps RK4's offset below the
#: discrepancy bound), a window off the origin, one holding θ̇ > 0 only.
MAPS = {
    "underdamped": (0.1, 1.0, 0.01, DEFAULT_WINDOW),
    "critically damped": (1.0, 1.0, 0.01, DEFAULT_WINDOW),
    "overdamped": (2.0, 1.0, 0.01, DEFAULT_WINDOW),
    "omega0 = 2": (0.3, 2.0, 0.005, ((-3 * PI, 3 * PI), (-8.0, 8.0))),
    "off-centre": (0.1, 1.0, 0.01, OFF_CENTRE),
    "theta_dot > 0": (0.1, 1.0, 0.01, ((-3 * PI, 3 * PI), (1.0, 4.0))),
}
GRID = 96


def distance_to_polylines(ds: xr.Dataset, q: np.ndarray) -> np.ndarray:
    """Distance [rad-ish] from each point q (N, 2) to the nearest segment of the stored
    polylines (:func:`atlas.store.separatrices.branches`)."""
    pieces = [np.column_stack([th, v]) for *_, th, v in branches(ds) if th.size > 1]
    a = np.concatenate([c[:-1] for c in pieces])
    e = np.concatenate([c[1:] for c in pieces]) - a
    best = np.empty(len(q))
    for chunk in np.array_split(np.arange(len(q)), max(1, len(q) // 128)):
        d = q[chunk, None, :] - a[None]
        t = np.clip((d * e).sum(-1) / (e * e).sum(-1), 0.0, 1.0)
        best[chunk] = np.linalg.norm(d - t[..., None] * e, axis=-1).min(axis=1)
    return best


@pytest.fixture(scope="module", params=list(MAPS))
def mapped(request):
    """(pendulum, dt, window, trace, cell centres, certified labels on a GRID² basin map)."""
    alpha, omega0, dt, window = MAPS[request.param]
    p = Pendulum(alpha, omega0)
    ds = trace(p, *window, dt=dt)
    (t_lo, t_hi), (v_lo, v_hi) = window
    theta = t_lo + (np.arange(GRID) + 0.5) * (t_hi - t_lo) / GRID
    theta_dot = v_lo + (np.arange(GRID) + 0.5) * (v_hi - v_lo) / GRID
    th, v = np.meshgrid(theta, theta_dot, indexing="ij")
    res = atlas.label(th, v, alpha=alpha, omega0=omega0, dt=dt, t_max=200.0)
    k = np.where(res.status == 0, res.attractor.astype(np.int64), NO_LABEL)
    return p, dt, window, ds, (th, v), k


@pytest.mark.slow
def test_every_label_change_on_a_basin_map_lies_on_a_stored_boundary(mapped):
    """Completeness: between any two 4-neighbouring cells with different certified labels a
    basin boundary passes, so a stored polyline comes within one cell diagonal of the pair's
    midpoint (it crosses the segment joining their centres)."""
    p, dt, window, ds, (th, v), k = mapped
    assert warnings(ds) == []
    diagonal = math.hypot(th[1, 0] - th[0, 0], v[0, 1] - v[0, 0])
    mids = []
    for axis in (0, 1):
        a = [slice(None)] * 2
        b = [slice(None)] * 2
        a[axis], b[axis] = slice(None, -1), slice(1, None)
        a, b = tuple(a), tuple(b)
        change = (k[a] != k[b]) & (k[a] != NO_LABEL) & (k[b] != NO_LABEL)
        mids.append(np.column_stack([0.5 * (th[a] + th[b])[change],
                                     0.5 * (v[a] + v[b])[change]]))
    mids = np.concatenate(mids)
    assert len(mids) > 100
    assert distance_to_polylines(ds, mids).max() <= diagonal


@pytest.mark.slow
def test_every_stored_segment_separates_neighbouring_basins(mapped):
    """Soundness: across the middle of every segment inside the window, offset ±δ along the
    normal (δ four times the chord-error bound max_spacing²/8), the certified labels differ by
    one, the higher — (n + 1)/2 for the saddle nπ — on the larger-θ̇ side."""
    p, dt, window, ds, _, _ = mapped
    delta = ds.attrs["max_spacing"] ** 2 / 2
    assert ds.attrs["polyline_error"] < delta / 4
    mids, above = [], []
    for n, _, th, v in branches(ds):
        inside = window_margin(window, th, v) >= 0
        both = inside[:-1] & inside[1:]
        mids.append(np.column_stack([0.5 * (th[:-1] + th[1:])[both],
                                     0.5 * (v[:-1] + v[1:])[both]]))
        above.append(np.full(int(both.sum()), (n + 1) // 2))
    mids, above = np.concatenate(mids), np.concatenate(above)
    assert len(mids) > 100
    normal = field_normal(p, mids[:, 0], mids[:, 1])
    for side, k in ((+1, above), (-1, above - 1)):
        res = atlas.label(mids[:, 0] + side * delta * normal[:, 0],
                          mids[:, 1] + side * delta * normal[:, 1], alpha=p.alpha,
                          omega0=p.omega0, dt=dt, t_max=ds.attrs["t_max"])
        assert np.all(res.status == 0)
        np.testing.assert_array_equal(res.attractor, k)


def test_crossing_table_lists_every_boundary_entering_an_off_centre_window():
    """θ0 ∈ [π/3, 11π/2] holds the saddles 1, 3, 5 and meets the right branches of −3π, −π and
    the left branches of 7π, 9π: each has its crossing of θ0 = 0 (outside this window), where
    DOP853 puts that saddle's own branch, within RK4's offset at dt = 0.01 (≈ 6e-10)."""
    p = Pendulum(0.1, 1.0)
    ds = trace(p, *OFF_CENTRE)
    saddles = np.unique(ds["saddle_n"].values)
    np.testing.assert_array_equal(saddles, [-3, -1, 1, 3, 5, 7, 9])
    assert ds.attrs["n_boundaries"] == saddles.size
    np.testing.assert_array_equal(ds["k_above"].values, (saddles + 1) // 2)
    np.testing.assert_array_equal(ds["k_below"].values, (saddles - 1) // 2)
    reference = [dop853_axis_crossing(p, n) for n in saddles]
    np.testing.assert_allclose(ds["crossing_theta_dot"].values, reference, rtol=0, atol=1e-9)
    assert not ds["crossing_in_window"].values.any()
    assert np.all(ds["crossing_bracket_width"].values < TOL)


def test_a_window_below_theta_dot_zero_uses_right_branches_only():
    ds = trace(Pendulum(0.1, 1.0), DEFAULT_WINDOW[0], (-4.0, -1.0))
    assert {b for _, b, *_ in branches(ds)} == {"right"}
    assert np.all(ds["theta_dot"].values < 0)
    assert math.isnan(ds.attrs["symmetry_error"])
    assert "not checked" in separatrix_lines(ds)[1]
    assert warnings(ds) == []


def test_a_window_that_no_boundary_enters_gives_empty_tables():
    """θ̇ ∈ [2.6, 2.7] at θ ∈ [0, 0.1] lies between the left branches of π (θ̇ ≈ 2.41 there) and
    3π (≈ 3.51): no curve, no crossing, nothing bisected."""
    ds = trace(Pendulum(0.1, 1.0), (0.0, 0.1), (2.6, 2.7))
    assert ds.sizes["point"] == ds.sizes["crossing"] == 0
    assert ds.attrs["n_boundaries"] == 0 and ds.attrs["n_orbits"] == 0
    assert warnings(ds) == [] and "none" in separatrix_lines(ds)[3]


@pytest.mark.parametrize("lines", [5, 300])  # few lines: multisection; many: bisection
def test_bisect_across_works_with_any_labeller(lines):
    """bisect_across on its own, without the pendulum: basins k − 1 below and k above the
    curve θ̇ = 0.5 + 0.3 sin 2θ, located across it along slanted lines; each final bracket
    holds the crossing (Brent's method on the same line) and is narrower than tol."""
    k, tol = 3, 1e-12

    def curve(theta):
        return 0.5 + 0.3 * np.sin(2 * theta)

    def labels(theta, theta_dot):
        return (theta_dot > curve(theta)).astype(np.int64) + k - 1

    rng = np.random.default_rng(7)
    theta = rng.uniform(-3.0, 3.0, lines)
    base = np.column_stack([theta, curve(theta) + rng.uniform(-2e-9, 2e-9, lines)])
    direction = np.broadcast_to([0.6, 0.8], base.shape)  # a unit vector, across the curve
    lo, hi = bisect_across(labels, base, direction, k, tol=tol, half_width=1e-11)
    root = np.array([brentq(lambda s, b=b: b[1] + 0.8 * s - curve(b[0] + 0.6 * s), -1e-6, 1e-6,
                            xtol=1e-20) for b in base])
    assert np.all((lo < hi) & (hi - lo < tol))
    assert np.all((lo - 1e-15 <= root) & (root <= hi + 1e-15))
    for s, side in ((lo, k - 1), (hi, k)):
        np.testing.assert_array_equal(labels(*(base + s[:, None] * direction).T), side)
