"""The exact basin boundaries and areas (atlas.boundaries.manifold) against independent references.

References: scipy's ``solve_ivp`` DOP853 with its own dense output (not atlas's evaluator),
integrating each boundary branch of each saddle separately, without the module's symmetry
shortcut; Monte-Carlo estimates of the areas from 10⁶ random RK4 labels, whose binomial
error is honest there (independent uniform samples); the symmetries of eq. (1).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import atlas
from atlas.boundaries.manifold import StableManifold, basin_areas, to_left_branch
from atlas.physics.pendulum import Pendulum

PI = math.pi
#: (α, ω0, θ window, θ̇ window): underdamped, critically damped, overdamped, ω0 ≠ 1, and a
#: window off-centre.
CASES = {
    "underdamped": (0.1, 1.0, (-3 * PI, 3 * PI), (-4.0, 4.0)),
    "critical": (1.0, 1.0, (-3 * PI, 3 * PI), (-4.0, 4.0)),
    "overdamped": (2.0, 1.0, (-3 * PI, 3 * PI), (-6.0, 6.0)),
    "omega0=2": (0.3, 2.0, (-2 * PI, 2 * PI), (-8.0, 8.0)),
    "off-centre": (0.1, 1.0, (PI / 3, 11 * PI / 2), (-4.0, 4.0)),
}


def branch_by_dop853(p: Pendulum, n: int, side: str, speed: float):
    """One branch of the stable manifold of the saddle (nπ, 0), integrated on its own in
    reversed time from 1e-9 along the eigenvector until |θ̇| > speed + 1: (samples (2, M),
    their times, scipy's own dense output) — independent of atlas.boundaries.manifold: no
    symmetry."""
    u2 = p.alpha + math.hypot(p.alpha, p.omega0)
    e = np.array([1.0, -u2]) / math.hypot(1.0, u2)
    sign = -1.0 if side == "left" else 1.0
    w2, a2 = p.omega0**2, 2 * p.alpha

    def rhs(_, y):
        return [-y[1], w2 * math.sin(y[0]) + a2 * y[1]]

    def fast(_, y):
        return abs(y[1]) - (speed + 1.0)

    fast.terminal = True
    sol = solve_ivp(rhs, (0, 1e4), np.array([n * PI, 0.0]) + sign * 1e-9 * e,
                    method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True, events=fast)
    t = np.linspace(0, sol.t[-1], 200_000)
    return sol.sol(t), t, sol.sol


@pytest.mark.parametrize("case", ["underdamped", "overdamped", "off-centre"])
def test_boundaries_are_the_independently_integrated_manifolds(case):
    alpha, omega0, theta_window, speed_window = CASES[case]
    p = Pendulum(alpha, omega0)
    m = StableManifold(p, 6.0)
    for n in (-3, 1, 5):
        for side in ("left", "right"):
            curve, *_ = branch_by_dop853(p, n, side, 5.0)
            keep = np.abs(curve[1]) < 5.0
            ref_theta, ref_speed = curve[0][keep], curve[1][keep]
            picked = slice(None, None, max(1, ref_theta.size // 300))
            # S_n at the reference's own θ: the two integrations agree to ≈ 1e-10
            np.testing.assert_allclose(m.boundary(n, ref_theta[picked]), ref_speed[picked],
                                       rtol=0, atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["underdamped", "omega0=2", "off-centre"])
def test_distance_to_the_nearest_boundary_against_brute_force(case):
    alpha, omega0, theta_window, speed_window = CASES[case]
    p = Pendulum(alpha, omega0)
    rng = np.random.default_rng(3)
    theta = rng.uniform(*theta_window, 40)
    speed = rng.uniform(*speed_window, 40)
    reach = max(abs(v) for v in speed_window) + 3.0
    m = StableManifold(p, reach)
    box = ((theta_window[0] - 3, theta_window[1] + 3), (speed_window[0] - 3, speed_window[1] + 3))
    dist, n = m.index(box).nearest(theta, speed)
    # brute force: every branch of every saddle near the window, sampled densely
    best = np.full(theta.size, np.inf)
    best_n = np.zeros(theta.size, int)
    n_lo = 2 * math.floor((theta_window[0] - 8 * PI) / (2 * PI)) + 1
    branches = []
    for saddle in range(n_lo, int(theta_window[1] / PI) + 9, 2):
        for side in ("left", "right"):
            c, t, curve = branch_by_dop853(p, saddle, side, reach)
            d2 = (c[0][None, :] - theta[:, None]) ** 2 + (c[1][None, :] - speed[:, None]) ** 2
            j = np.argmin(d2, axis=1)
            gap = np.hypot(*np.diff(c, axis=1)).max()  # the widest step between two samples
            branches.append((saddle, t, curve, j, np.sqrt(d2[np.arange(theta.size), j]), gap))
    # the resampled distance to a branch lies between its nearest sample's distance minus the
    # widest step and that distance itself: only branches within that of the best sample can
    # hold the nearest point, the others need no resampling
    closest = np.min([near for *_, near, _ in branches], axis=0)
    for saddle, t, curve, nearest, near, gap in branches:
        for i in np.flatnonzero(near <= closest + 2 * gap):
            j = nearest[i]  # resample around the nearest sample
            fine = curve(np.linspace(t[max(j - 1, 0)], t[min(j + 1, t.size - 1)], 20_001))
            d = np.hypot(fine[0] - theta[i], fine[1] - speed[i]).min()
            if d < best[i]:
                best[i], best_n[i] = d, saddle
    # resampled 10⁴-fold finer, the brute force is exact to ≈ 1e-12 (the two integrations
    # start 1e-9 and 1e-7 from the saddle and differ by about that much)
    np.testing.assert_allclose(dist, best, rtol=0, atol=1e-11)
    np.testing.assert_array_equal(n, best_n)


@pytest.mark.parametrize("case", list(CASES))
def test_sides_are_the_rk4_labels_away_from_boundaries(case):
    alpha, omega0, theta_window, speed_window = CASES[case]
    p = Pendulum(alpha, omega0)
    areas = basin_areas(p, theta_window, speed_window)
    m = StableManifold(p, max(abs(v) for v in speed_window) + 1.0)
    theta = np.linspace(*theta_window, 90)[None, :]
    speed = np.linspace(*speed_window, 70)[:, None]
    side = m.side(theta, speed, areas.saddles)
    res = atlas.label(theta, speed, alpha=alpha, omega0=omega0, t_max=400.0)
    far = m.index(((theta_window[0] - 1, theta_window[1] + 1),
                   (speed_window[0] - 1, speed_window[1] + 1))).nearest(
        *np.broadcast_arrays(theta, speed))[0] > 1e-6
    assert np.all(res.status[far] == 0)
    np.testing.assert_array_equal(side[far], res.attractor[far])
    assert set(np.unique(side)) <= set(areas.k.tolist())


@pytest.mark.parametrize("case", list(CASES))
def test_exact_fractions_sum_to_one_within_their_error(case):
    alpha, omega0, theta_window, speed_window = CASES[case]
    a = basin_areas(Pendulum(alpha, omega0), theta_window, speed_window)
    assert np.all(a.fraction >= -a.error) and np.all(a.error < 1e-11)
    assert abs(a.fraction.sum() - 1.0) <= a.error.sum() + 1e-15
    assert np.all(np.diff(a.k) == 1)


@pytest.mark.parametrize("case", ["underdamped", "critical", "overdamped", "omega0=2"])
def test_exact_fractions_are_symmetric_under_point_reflection(case):
    alpha, omega0, theta_window, speed_window = CASES[case]
    a = basin_areas(Pendulum(alpha, omega0), theta_window, speed_window)
    np.testing.assert_array_equal(a.k, -a.k[::-1])
    np.testing.assert_array_less(np.abs(a.fraction - a.fraction[::-1]),
                                 a.error + a.error[::-1] + 1e-15)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["underdamped", "off-centre"])
def test_exact_fractions_against_monte_carlo(case):
    """10⁶ uniform random initial conditions labelled by RK4: each fraction within 4.5
    binomial standard errors (RK4 labels differ from the exact ones only within ~1e-9 of a
    boundary, an area far below the Monte-Carlo error)."""
    alpha, omega0, theta_window, speed_window = CASES[case]
    a = basin_areas(Pendulum(alpha, omega0), theta_window, speed_window)
    rng = np.random.default_rng(2026)
    n = 1_000_000
    res = atlas.label(rng.uniform(*theta_window, n), rng.uniform(*speed_window, n),
                      alpha=alpha, omega0=omega0, t_max=400.0)
    assert np.all(res.status == 0)
    for k, f in zip(a.k, a.fraction):
        estimate = np.count_nonzero(res.attractor == k) / n
        sigma = math.sqrt(max(f * (1 - f), 1.0 / n) / n)
        assert abs(estimate - f) <= 4.5 * sigma, (k, estimate, f)


def test_window_without_a_boundary_is_one_basin():
    a = basin_areas(Pendulum(0.1, 1.0), (-0.5, 0.5), (-0.5, 0.5))
    np.testing.assert_array_equal(a.k, [0])
    assert a.fraction[0] == pytest.approx(1.0, abs=1e-15)


def test_extended_continues_the_same_curve():
    """extended keeps the integrated steps (the same curve up to tau_end) and goes on to the
    requested θ, where the independent integration agrees with it as before."""
    p = Pendulum(0.1, 1.0)
    m = StableManifold(p, 4.0)
    longer = m.extended(m.theta_end - 6.0)
    assert longer.theta_end < m.theta_end - 6.0 < m.theta_end and longer.tau_end > m.tau_end
    assert m.extended(m.theta_end + 1.0) is m
    tau = np.linspace(0.0, m.tau_end, 400)
    np.testing.assert_allclose(np.array(longer.at(tau)), np.array(m.at(tau)), rtol=0, atol=1e-14)
    curve, *_ = branch_by_dop853(p, 1, "left", 8.0)
    beyond = (curve[0] > longer.theta_end) & (curve[0] < m.theta_end)
    assert beyond.sum() > 100
    np.testing.assert_allclose(longer.left(curve[0][beyond][::50]), curve[1][beyond][::50],
                               rtol=0, atol=1e-9)
    assert np.all(np.isinf(m.left(curve[0][beyond])))


def test_foot_points_on_the_left_branch():
    """Points offset by d along the normal of an independently integrated L: their distance
    to L is |d| (|d| below the radius of curvature), their foot point the point offset from."""
    p = Pendulum(0.3, 2.0)
    m = StableManifold(p, 6.0)
    curve, t, sol = branch_by_dop853(p, 1, "left", 5.0)
    away = np.hypot(curve[0] - PI, curve[1]) > 1e-2  # off the straight piece at the saddle
    pick = np.flatnonzero(away & (np.abs(curve[1]) < 5.0))[::2000]
    c = curve[:, pick]
    f0, f1 = p.field(c[0], c[1])
    normal = np.array([-f1, f0]) / np.hypot(f0, f1)
    d = np.random.default_rng(1).uniform(-1e-3, 1e-3, pick.size)
    tau, dist = m.foot_points(*(c + d * normal))
    np.testing.assert_allclose(dist, np.abs(d), rtol=0, atol=1e-11)
    np.testing.assert_allclose(np.array(m.at(tau)), c, rtol=0, atol=1e-9)


def test_copies_map_onto_the_left_branch():
    """to_left_branch takes every boundary S_n, left and right of its saddle, onto L."""
    m = StableManifold(Pendulum(0.1, 1.0), 4.0)
    for n in (-5, -1, 3):
        theta = np.linspace((n - 1) * PI, (n + 1) * PI, 41)[1:-1]
        speed = m.boundary(n, theta)
        fin = np.isfinite(speed)
        x, v = to_left_branch(n, theta[fin] > n * PI, theta[fin], speed[fin])
        np.testing.assert_allclose(v, m.left(x), rtol=0, atol=1e-12)


def test_nearest_sample_search_does_not_depend_on_the_cells():
    """The bucket search stops once no unseen sample can be nearer: with cells of another
    size (a different ring geometry) every distance and saddle is the same, for points on
    the cells' edges and corners, outside the index's box, and far from every boundary."""
    import copy

    from atlas.boundaries.manifold import bins

    p = Pendulum(0.1, 1.0)
    box = ((-3 * PI - 1, 3 * PI + 1), (-5.0, 5.0))
    index = StableManifold(p, 5.0).index(box)
    (t0, _), (v0, _) = box
    k = np.arange(-2, 40)
    rng = np.random.default_rng(9)
    theta = np.concatenate([t0 + k * index.cell, rng.uniform(-15, 15, 200),
                            [t0 - 3.0, t0 - 0.5, 12.0, 0.0]])
    speed = np.concatenate([v0 + (k % 30) * index.cell, rng.uniform(-9, 9, 200),
                            [0.0, -6.0, 7.5, 0.0]])
    dist, n = index.nearest(theta, speed)
    for cell in (0.07, 1.1):
        other = copy.copy(index)
        other.cell, other.shape, other.start, other.items = bins(
            index.theta, index.theta_dot, box, cell)
        d, m = other.nearest(theta, speed)
        np.testing.assert_array_equal(d, dist)
        np.testing.assert_array_equal(m, n)
    assert np.isfinite(dist).all() and dist.max() > 1.0
