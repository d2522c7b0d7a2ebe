"""The separatrix tracer's small numerical tools against scipy: the not-a-knot spline that
predicts bisection offsets, and the crossing of a speed level on the dense output."""

import math

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from atlas.manifold import StableManifold
from atlas.model import Pendulum
from atlas.separatrices import _not_a_knot_spline, _speed_crossing


@pytest.mark.parametrize("n", [4, 5, 12, 60])
def test_not_a_knot_spline_is_scipys_cubic_spline(n):
    rng = np.random.default_rng(n)
    x = np.sort(rng.uniform(0.0, 10.0, n)) + np.arange(n) * 0.05  # distinct knots
    y = np.sin(x) + 0.1 * rng.normal(size=n)
    at = np.linspace(x[0], x[-1], 777)
    np.testing.assert_allclose(_not_a_knot_spline(x, y, at), CubicSpline(x, y)(at),
                               rtol=0, atol=1e-12)


def test_not_a_knot_spline_reproduces_cubics():
    """Not-a-knot conditions make the spline exact for a cubic (a natural spline is not)."""
    x = np.array([0.0, 0.3, 1.1, 1.5, 2.6, 3.0])
    cubic = np.poly1d([0.7, -1.2, 0.4, 2.0])
    at = np.linspace(0.0, 3.0, 101)
    np.testing.assert_allclose(_not_a_knot_spline(x, cubic(x), at), cubic(at), atol=1e-13)


def test_speed_crossing_matches_brent():
    m = StableManifold(Pendulum(alpha=0.1, omega0=1.0), 4.0)
    i = int(np.flatnonzero(np.diff(np.sign(m.theta_dot - 2.5)))[0])
    a, b = float(m.tau[i]), float(m.tau[i + 1])
    tau = _speed_crossing(m, 2.5, a, b)
    ref = brentq(lambda s: m.at(s)[1] - 2.5, a, b, xtol=1e-15)
    assert abs(tau - ref) <= 4 * math.ulp(ref) + 1e-15
    assert m.at(tau)[1] == pytest.approx(2.5, abs=1e-13)
