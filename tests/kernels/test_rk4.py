"""The RK4 step: fourth-order convergence against the exact linear solution."""

import math

import numba as nb
import numpy as np
import pytest
from scipy.linalg import expm

from atlas.kernels.rk4 import make_rk4_step, propagate_straightforward


@nb.njit(inline="always")
def _identity(x):
    return x


_linear_step = make_rk4_step(_identity)  # θ̈ = −ω0²θ − 2αθ̇: the linearised equation


@nb.njit
def _integrate_linear(theta, theta_dot, alpha, omega0, dt, n):
    for _ in range(n):
        theta, theta_dot = _linear_step(theta, theta_dot, alpha, omega0, dt)
    return theta, theta_dot


def _exact_linear(y0, t, alpha, omega0):
    """Exact flow of y' = A y with the matrix exponential (independent of atlas.physics.linear)."""
    a = np.array([[0.0, 1.0], [-omega0**2, -2 * alpha]])
    return expm(a * t) @ np.asarray(y0)


@pytest.mark.parametrize("alpha,omega0", [(0.1, 1.0), (1.0, 1.0), (2.5, 1.0), (0.0, 2.0)])
def test_rk4_converges_with_order_four(alpha, omega0):
    t_end, y0 = 5.0, (0.5, -0.3)
    exact = _exact_linear(y0, t_end, alpha, omega0)
    steps = np.array([50, 100, 200, 400, 800])
    errors = []
    for n in steps:
        got = _integrate_linear(*y0, alpha, omega0, t_end / n, n)
        errors.append(np.hypot(*(np.array(got) - exact)))
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 3.9 < slope < 4.1, (slope, errors)


def test_propagate_matches_repeated_steps_and_nonlinear_reference():
    from scipy.integrate import solve_ivp

    theta = np.array([0.3, 2.0, -3.0])
    theta_dot = np.array([0.0, 1.5, 2.5])
    th, v = theta.copy(), theta_dot.copy()
    propagate_straightforward(th, v, 0.1, 1.0, 0.01, 1000)
    for i in range(theta.size):
        sol = solve_ivp(lambda _, y: [y[1], -math.sin(y[0]) - 0.2 * y[1]], (0, 10.0),
                        [theta[i], theta_dot[i]], method="DOP853", rtol=1e-12, atol=1e-12)
        # global RK4 error at dt = 0.01 over 10 s: O(dt⁴) ~ 1e-8
        assert abs(th[i] - sol.y[0, -1]) < 1e-7
        assert abs(v[i] - sol.y[1, -1]) < 1e-7


def _dop853(theta0, theta_dot0, alpha, omega0, t_end):
    """Eq. (1) by scipy's DOP853 at rtol 1e-13 (error ~1e-12, far below RK4's at these dt)."""
    from scipy.integrate import solve_ivp

    w2, a2 = omega0**2, 2 * alpha
    sol = solve_ivp(lambda _, y: [y[1], -w2 * math.sin(y[0]) - a2 * y[1]], (0.0, t_end),
                    [theta0, theta_dot0], method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[:, -1]


# large-amplitude orbits (libration near the separatrix, rotation) of the nonlinear equation
NONLINEAR = [(2.5, 0.8), (0.3, 2.3), (-3.0, -1.2)]


@pytest.mark.parametrize("method", ["rk4", "rk4-trigfree"])
@pytest.mark.parametrize("alpha,omega0", [(0.1, 1.0), (0.5, 2.0)])
def test_methods_converge_with_order_four_on_the_nonlinear_equation(method, alpha, omega0):
    """Fitted global order against DOP853 over t = 8 s, dt = 0.02 … 0.0025, where both methods
    are in their asymptotic range (at dt = 0.04 the near-separatrix orbit is not yet), with
    the trig-free method's re-synchronisation every SYNC_EVERY steps included: the kernels'
    own code."""
    from atlas.kernels.lanes import propagate_lanes, propagate_trigfree

    propagate = propagate_trigfree if method == "rk4-trigfree" else propagate_lanes
    t_end = 8.0
    exact = np.array([_dop853(t, v, alpha, omega0, t_end) for t, v in NONLINEAR]).T
    steps = np.array([400, 800, 1600, 3200])
    errors = []
    for n in steps:
        th = np.array([t for t, _ in NONLINEAR])
        v = np.array([v for _, v in NONLINEAR])
        propagate(th, v, alpha, omega0, t_end / n, int(n))
        errors.append(np.max(np.hypot(th - exact[0], v - exact[1])))
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 3.9 < slope < 4.1, (slope, errors)


def test_trigfree_scalar_form_is_the_same_discretisation():
    """record_trigfree (libm re-synchronisation) and the lane kernel (polynomial) agree to
    rounding, and both differ from classical RK4 by O(dt⁴) only."""
    from atlas.kernels.lanes import propagate_trigfree
    from atlas.kernels.trigfree import record_trigfree

    th0 = np.array([t for t, _ in NONLINEAR])
    v0 = np.array([v for _, v in NONLINEAR])
    out = np.empty((2, 2, th0.size))
    record_trigfree(th0, v0, 0.1, 1.0, 0.01, 1000, out)
    th, v = th0.copy(), v0.copy()
    propagate_trigfree(th, v, 0.1, 1.0, 0.01, 1000)
    np.testing.assert_allclose(th, out[0, 1], rtol=0, atol=1e-11)
    np.testing.assert_allclose(v, out[1, 1], rtol=0, atol=1e-11)
    ref_th, ref_v = th0.copy(), v0.copy()
    propagate_straightforward(ref_th, ref_v, 0.1, 1.0, 0.01, 1000)
    gap = np.max(np.abs(th - ref_th))
    assert 1e-12 < gap < 1e-7  # a different discretisation of the same order
