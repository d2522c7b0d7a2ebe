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
from atlas.stability.shocks import minimal_fatal_shock, running_fatal_shock

pytestmark = pytest.mark.slow  # integrates manifolds


def _scipy_branches(alpha, omega0, torque, speed, rtol):
    """Both stable branches of the saddle (π − arcsin τ, 0) by scipy's DOP853 (rtol = atol =
    ``rtol``) in reversed time from 1e-8 along the stable eigenvector until |θ̇| > speed:
    the two solutions, with dense output."""
    theta_s = math.pi - math.asin(torque / omega0**2)
    kappa = omega0**2 * math.cos(math.asin(torque / omega0**2))
    lam = -alpha - math.sqrt(alpha**2 + kappa)  # stable eigenvalue: direction (1, lam)
    norm = math.hypot(1.0, lam)

    def back(_, y):
        return [-y[1], -(torque - omega0**2 * math.sin(y[0]) - 2 * alpha * y[1])]

    def fast(_, y):
        return abs(y[1]) - speed

    fast.terminal = True
    return [solve_ivp(back, (0, 1e3), [theta_s + sign * 1e-8 / norm, sign * 1e-8 * lam / norm],
                      method="DOP853", rtol=rtol, atol=rtol, dense_output=True, events=fast)
            for sign in (-1.0, 1.0)]


def _reference_distance(alpha, omega0, torque, point, speed=6.0):
    """Distance from ``point`` to the stable manifolds of the saddles next to it (θs and
    θs − 2π), each branch by :func:`_scipy_branches` at rtol 1e-12, then minimised on the
    dense output."""
    best = math.inf
    for sol in _scipy_branches(alpha, omega0, torque, speed, 1e-12):
        for shift in (0.0, -2 * math.pi):
            here = np.array([point[0] - shift, point[1]])  # the point, seen from the copy
            t = np.linspace(0, sol.t[-1], 20001)
            th, v = sol.sol(t)
            i = int(np.argmin(np.hypot(th - here[0], v - here[1])))
            lo, hi = t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]
            res = minimize_scalar(lambda s, f=sol.sol, p=here: np.hypot(*(f(s) - p)),
                                  bounds=(lo, hi), method="bounded",
                                  options={"xatol": 1e-14})
            best = min(best, float(res.fun), float(np.hypot(th[i] - here[0],
                                                            v[i] - here[1])))
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


def _scipy_cycle(alpha, omega0, torque):
    """The running limit cycle by scipy alone: the fixed point of the Poincaré map
    θ̇(θs) ↦ θ̇(θs + 2π) at the saddle's angle θs by scipy's brentq, each turn by scipy's
    DOP853 (rtol = atol = 1e-12); then one turn densely sampled: (θ, θ̇), 20,001 points."""
    from scipy.optimize import brentq

    theta_s = math.pi - math.asin(torque / omega0**2)

    def flow(_, y):
        return [y[1], torque - omega0**2 * math.sin(y[0]) - 2 * alpha * y[1]]

    def around(_, y):
        return y[0] - theta_s - 2 * math.pi

    around.terminal = True

    def turn(v):
        return solve_ivp(flow, (0.0, 1e3), [theta_s, v], method="DOP853", rtol=1e-12,
                         atol=1e-12, events=around, dense_output=True)

    def excess(v):  # P(v) − v; an orbit that does not get round counts as P = 0
        sol = turn(v)
        return (sol.y[1, -1] if sol.status == 1 else 0.0) - v

    v = brentq(excess, 1e-6, 2.0 * torque / (2 * alpha) + 1.0, xtol=1e-14)
    sol = turn(v)
    return sol.sol(np.linspace(0.0, sol.t[-1], 20001))


@pytest.mark.parametrize("alpha, torque", [(0.05, 0.5), (0.1, 0.5), (0.05, 0.2), (0.05, 0.136)])
def test_the_running_cycles_shock_against_scipy(alpha, torque):
    """The running cycle's minimal fatal shock against an independent construction: the
    cycle and the boundaries by scipy alone, the nearest pair of their samples refined by
    scipy's bounded minimisation of the distance from the cycle to the nearest boundary
    sample's neighbourhood; within the sampling's resolution (1e-8) and the shock's own
    error."""
    from scipy.spatial import cKDTree

    b = exact_boundaries(Pendulum(alpha, 1.0, torque), WINDOW)
    shock = running_fatal_shock(b)
    ct, cv = _scipy_cycle(alpha, 1.0, torque)
    # both branches of the saddles j = −1 … 2, densely sampled
    points = np.concatenate([np.column_stack((th + 2 * math.pi * j, v))
                             for sol in _scipy_branches(alpha, 1.0, torque, 12.0, 1e-13)
                             for th, v in [sol.sol(np.linspace(0, sol.t[-1], 100001))]
                             for j in range(-1, 3)])
    tree = cKDTree(points)
    d, _ = tree.query(np.column_stack([ct, cv]))
    i = int(np.argmin(d))
    # refine along the cycle: the distance to the boundary samples near the best one
    near = points[tree.query_ball_point([ct[i], cv[i]], d[i] + 0.05)]
    s = np.linspace(max(i - 3, 0), min(i + 3, ct.size - 1), 6001)
    th, v = np.interp(s, np.arange(ct.size), ct), np.interp(s, np.arange(ct.size), cv)
    reference = float(np.min(np.hypot(th[:, None] - near[None, :, 0],
                                      v[:, None] - near[None, :, 1])))
    assert abs(shock.distance - reference) < 1e-6 + shock.error, (shock, reference)
    # the pair: a point of the cycle, and a point on a boundary (its distance ≈ 0)
    assert math.hypot(shock.theta - shock.target_theta,
                      shock.theta_dot - shock.target_theta_dot) == pytest.approx(
        shock.distance, abs=1e-12)
    assert float(b.distance(shock.target_theta, shock.target_theta_dot)[0]) \
        <= b.reference_error + 1e-12
    assert shock.error < 1e-8


@pytest.mark.parametrize("torque", [0.3, -0.7])
def test_the_running_shock_is_the_same_with_the_sampled_cycle_given(torque):
    """Without the sampled cycle the shock integrates no turn of its own: it takes the turn
    the cycle's fixed-point search ended on; with the cycle given (a grid run's) it
    integrates that turn from the cycle's crossing. The same doubles either way."""
    from atlas.physics.running import limit_cycle

    p = Pendulum(0.05, 1.0, torque)
    alone = running_fatal_shock(exact_boundaries(p, WINDOW))
    given = running_fatal_shock(exact_boundaries(p, WINDOW,
                                                 cycle=limit_cycle(0.05, 1.0, torque)))
    assert tuple(alone) == tuple(given)
    assert math.isfinite(alone.distance)


def test_no_running_cycle_no_running_shock():
    """Below the homoclinic torque, and without torque, there is no running cycle."""
    for torque in (0.0, 0.1):
        b = exact_boundaries(Pendulum(0.05, 1.0, torque), WINDOW)
        assert all(math.isnan(x) for x in running_fatal_shock(b))
