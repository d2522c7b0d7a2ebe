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
    """Exact flow of y' = A y with the matrix exponential (independent of atlas.linear)."""
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
