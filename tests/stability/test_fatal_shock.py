"""The minimal fatal shock (Halekotte & Feudel, Sci. Rep. 10, 11783, 2020): against an
independent scipy DOP853 integration of the stable manifolds, and in the limit α → 0 against
the undamped separatrix θ̇ = ±2ω0 cos(θ/2), whose distance from the rest state is
min over θ of √(θ² + 4ω0² cos²(θ/2)) (2ω0 for ω0 ≤ 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from atlas.boundaries.exact import exact_boundaries
from atlas.physics.pendulum import Pendulum
from atlas.stability.shocks import minimal_fatal_shock

pytestmark = pytest.mark.slow  # integrates manifolds


def _reference_distance(alpha, omega0, torque, point, speed=6.0):
    """Distance from ``point`` to the stable manifolds of the saddles next to it, each
    branch integrated by scipy's DOP853 (rtol = atol = 1e-12) in reversed time from 1e-8
    along the stable eigenvector, then minimised on the dense output."""
    theta_s = math.pi - math.asin(torque / omega0**2)
    kappa = omega0**2 * math.cos(math.asin(torque / omega0**2))
    lam = -alpha - math.sqrt(alpha**2 + kappa)  # stable eigenvalue: direction (1, lam)
    norm = math.hypot(1.0, lam)

    def back(_, y):
        return [-y[1], -(torque - omega0**2 * math.sin(y[0]) - 2 * alpha * y[1])]

    def fast(_, y):
        return abs(y[1]) - speed

    fast.terminal = True
    best = math.inf
    for shift in (0.0, -2 * math.pi):
        for sign in (-1.0, 1.0):
            y0 = [theta_s + shift + sign * 1e-8 / norm, sign * 1e-8 * lam / norm]
            sol = solve_ivp(back, (0, 1e3), y0, method="DOP853", rtol=1e-12, atol=1e-12,
                            dense_output=True, events=fast)
            t = np.linspace(0, sol.t[-1], 20001)
            th, v = sol.sol(t)
            i = int(np.argmin(np.hypot(th - point[0], v - point[1])))
            lo, hi = t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]
            res = minimize_scalar(lambda s, f=sol.sol: np.hypot(*(f(s) - np.array(point))),
                                  bounds=(lo, hi), method="bounded",
                                  options={"xatol": 1e-14})
            best = min(best, float(res.fun), float(np.hypot(th[i] - point[0],
                                                            v[i] - point[1])))
    return best


WINDOW = ((-math.pi, math.pi), (-4.0, 4.0))


@pytest.mark.parametrize("alpha, torque, tol", [(0.2, 0.0, 1e-9), (0.05, 0.5, 1e-9),
                                                (0.3, 0.2, 1e-9)])
def test_the_shock_against_scipy_dop853(alpha, torque, tol):
    b = exact_boundaries(Pendulum(alpha, 1.0, torque), WINDOW)
    shock = minimal_fatal_shock(b)
    rest = (math.asin(torque), 0.0)
    assert abs(shock.distance - _reference_distance(alpha, 1.0, torque, rest)) < tol
    # the point is on a boundary: its distance from the rest state is the shock, and the
    # boundaries are nearer to it than anything else (distance ≈ 0)
    assert abs(math.hypot(shock.theta - rest[0], shock.theta_dot) - shock.distance) < 1e-12
    assert float(b.distance(shock.theta, shock.theta_dot)[0]) <= b.reference_error + 1e-12
    # the metric of boundary_distance: the same number as the exact distance of the rest
    # state, to the error of the curves boundary_distance measures (with torque polylines)
    assert abs(float(b.distance(*rest)[0]) - shock.distance) <= b.reference_error + 1e-12
    # the error claimed is an honest one: the scipy reference lies within it and 1e-11
    assert abs(shock.distance - _reference_distance(alpha, 1.0, torque, rest)) \
        <= shock.error + 1e-11


def _undamped(omega0):
    """min over θ of √(θ² + 4ω0² cos²(θ/2)): the undamped separatrix's distance."""
    res = minimize_scalar(lambda t: t * t + 4 * omega0**2 * math.cos(t / 2) ** 2,
                          bounds=(0.0, math.pi), method="bounded", options={"xatol": 1e-12})
    return math.sqrt(min(res.fun, 4 * omega0**2))


@pytest.mark.parametrize("omega0", [0.8, 1.0, 2.0])
def test_the_shock_tends_to_the_undamped_separatrix(omega0):
    limit = _undamped(omega0)
    if omega0 <= 1.0:
        assert limit == pytest.approx(2 * omega0, rel=1e-12)
    gaps = []
    alphas = np.array([0.008, 0.004, 0.002]) * omega0
    for alpha in alphas:
        b = exact_boundaries(Pendulum(alpha, omega0), ((-math.pi, math.pi), (-1.0, 1.0)))
        gaps.append(minimal_fatal_shock(b).distance - limit)
    gaps = np.abs(gaps)
    # the damped separatrix lies O(α) from the undamped one: the gap halves with α
    order = np.polyfit(np.log(alphas), np.log(gaps), 1)[0]
    assert 0.8 < order < 1.2, (gaps, order)
    assert gaps[-1] < 0.05 * omega0
