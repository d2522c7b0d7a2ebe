"""The separatrix tracer's small numerical tools against scipy: the not-a-knot spline that
predicts bisection offsets, and the crossing of a speed level on the dense output."""

import math

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from atlas.boundaries.manifold import StableManifold
from atlas.boundaries.predictor import not_a_knot_spline
from atlas.physics.pendulum import Pendulum


@pytest.mark.parametrize("n", [4, 5, 12, 60])
def test_not_a_knot_spline_is_scipys_cubic_spline(n):
    rng = np.random.default_rng(n)
    x = np.sort(rng.uniform(0.0, 10.0, n)) + np.arange(n) * 0.05  # distinct knots
    y = np.sin(x) + 0.1 * rng.normal(size=n)
    at = np.linspace(x[0], x[-1], 777)
    np.testing.assert_allclose(not_a_knot_spline(x, y, at), CubicSpline(x, y)(at),
                               rtol=0, atol=1e-12)


def test_not_a_knot_spline_reproduces_cubics():
    """Not-a-knot conditions make the spline exact for a cubic (a natural spline is not)."""
    x = np.array([0.0, 0.3, 1.1, 1.5, 2.6, 3.0])
    cubic = np.poly1d([0.7, -1.2, 0.4, 2.0])
    at = np.linspace(0.0, 3.0, 101)
    np.testing.assert_allclose(not_a_knot_spline(x, cubic(x), at), cubic(at), atol=1e-13)


def test_speed_crossing_matches_brent():
    m = StableManifold(Pendulum(alpha=0.1, omega0=1.0), 4.0)
    i = int(np.flatnonzero(np.diff(np.sign(m.theta_dot - 2.5)))[0])
    a, b = float(m.tau[i]), float(m.tau[i + 1])
    tau = float(m.speed_crossing(2.5, a, b))
    ref = brentq(lambda s: m.at(s)[1] - 2.5, a, b, xtol=1e-15)
    assert abs(tau - ref) <= 4 * math.ulp(ref) + 1e-15
    assert m.at(tau)[1] == pytest.approx(2.5, abs=1e-13)


def test_boundary_index_saddles_within_is_a_ball_query():
    """The bucket search for the saddles near points equals a k-d tree's ball query."""
    from scipy.spatial import cKDTree

    from atlas.boundaries.exact import exact_boundaries
    from atlas.boundaries.manifold import SAMPLE_SPACING

    ex = exact_boundaries(Pendulum(alpha=0.1, omega0=1.0), ((-3 * math.pi, 3 * math.pi),
                                                             (-4.0, 4.0)))
    index = ex._index(1.0)
    rng = np.random.default_rng(0)
    theta, theta_dot = rng.uniform(-10, 10, 5000), rng.uniform(-5, 5, 5000)
    tree = cKDTree(np.column_stack([index.theta, index.theta_dot]))
    for radius in (0.01, 0.4):
        lo, hi = index.saddles_within(theta, theta_dot, radius)
        ref_lo, ref_hi = np.zeros_like(lo), np.zeros_like(hi)
        balls = tree.query_ball_point(np.column_stack([theta, theta_dot]),
                                      radius + SAMPLE_SPACING)
        for i, near in enumerate(balls):
            if near:
                ref_lo[i], ref_hi[i] = index.n[near].min(), index.n[near].max()
        assert (ref_lo != 0).sum() > 100  # the test sees boundaries
        np.testing.assert_array_equal(lo, ref_lo)
        np.testing.assert_array_equal(hi, ref_hi)


def test_foot_points_start_from_the_nearest_sample():
    from scipy.spatial import cKDTree

    m = StableManifold(Pendulum(alpha=0.1, omega0=1.0), 4.0)
    rng = np.random.default_rng(1)
    x = m.theta[::3] + rng.normal(0, 0.01, m.theta[::3].size)
    v = m.theta_dot[::3] + rng.normal(0, 0.01, x.size)
    tau, dist = m.foot_points(x, v)
    _, i = cKDTree(np.column_stack([m.theta, m.theta_dot])).query(np.column_stack([x, v]))
    ref_tau, ref_dist = m._foot(x, v, i)
    np.testing.assert_array_equal(tau, ref_tau)
    np.testing.assert_array_equal(dist, ref_dist)


def test_tilted_saddles_within_is_a_ball_query():
    """With torque: the binned vertices near the window (and all of them, for points outside
    it) give what a k-d tree's ball query over every vertex gives."""
    from scipy.spatial import cKDTree

    from atlas.boundaries.exact import exact_boundaries
    from atlas.boundaries.tilted import MAX_SEGMENT

    window = ((-5 * math.pi / 6, 7 * math.pi / 6), (-10.0, 10.0))
    ex = exact_boundaries(Pendulum(alpha=0.05, omega0=1.0, torque=0.5), window)
    curves = ex.tilted.curves(clip=False)
    xy = np.concatenate([np.column_stack([t, v]) for _, _, t, v in curves])
    n = np.concatenate([np.full(t.size, 2 * j + 1) for j, _, t, _ in curves])
    tree = cKDTree(xy)
    rng = np.random.default_rng(2)
    inside = (rng.uniform(*window[0], 3000), rng.uniform(*window[1], 3000))
    outside = (rng.uniform(-8.0, 8.0, 300), rng.uniform(-14.0, 14.0, 300))
    for (theta, theta_dot), radius in ((inside, 0.03), (outside, 0.03), (inside, 0.7)):
        lo, hi = ex.saddles_within(theta, theta_dot, radius)
        ref_lo, ref_hi = np.zeros_like(lo), np.zeros_like(hi)
        for i, near in enumerate(tree.query_ball_point(np.column_stack([theta, theta_dot]),
                                                       radius + MAX_SEGMENT)):
            if near:
                ref_lo[i], ref_hi[i] = n[near].min(), n[near].max()
        assert (ref_lo != 0).sum() > 10
        np.testing.assert_array_equal(lo, ref_lo)
        np.testing.assert_array_equal(hi, ref_hi)
