"""The torque RK4 step's order, fitted: the kernels' own step with τ ≠ 0 (rk4_step_torque,
what every torque kernel inlines) converges at order 4 against scipy's DOP853 at rtol 1e-13.
A slip of O(dt²) in the torque term (say τ left out of one stage) makes the global error
O(dt²) and the fitted slope ≈ 2, which this test refuses."""

import math

import numba as nb
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.kernels.rk4 import rk4_step_torque


@nb.njit
def _integrate(theta, theta_dot, alpha, omega0, dt, n, torque):
    for _ in range(n):
        theta, theta_dot = rk4_step_torque(theta, theta_dot, alpha, omega0, dt, torque)
    return theta, theta_dot


def _dop853(y0, alpha, omega0, torque, t_end):
    w2, a2 = omega0**2, 2 * alpha
    sol = solve_ivp(lambda _, y: [y[1], torque - w2 * math.sin(y[0]) - a2 * y[1]],
                    (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[:, -1]


# a libration in a tilted well, an orbit over the saddle, a running orbit; τ < 0 mirrored
ORBITS = [(0.2, 1.1), (2.0, 0.9), (-1.0, 3.0)]


@pytest.mark.parametrize("alpha,omega0,torque", [(0.05, 1.0, 0.5), (0.3, 1.5, -1.2),
                                                 (0.1, 1.0, 1.6)])
def test_torque_step_converges_with_order_four(alpha, omega0, torque):
    t_end = 4.0
    exact = np.array([_dop853(list(y0), alpha, omega0, torque, t_end) for y0 in ORBITS])
    # dt = 0.02 … 0.005: asymptotic, and the errors (≥ 1e-11) far above the reference's
    steps = np.array([200, 400, 800])
    errors = np.array([[np.hypot(*(np.array(_integrate(t, v, alpha, omega0, t_end / n, int(n),
                                                       torque)) - y))
                        for n in steps] for (t, v), y in zip(ORBITS, exact)])
    for orbit, e in zip(ORBITS, errors):
        slope = -np.polyfit(np.log(steps), np.log(e), 1)[0]
        assert 3.9 < slope < 4.2, (orbit, slope, e)
    errors = errors.max(axis=0)
    # the torque matters here: without it the orbits end far from the reference
    untilted = np.array([_integrate(t, v, alpha, omega0, t_end / 200, 200, 0.0)
                         for t, v in ORBITS])
    assert np.max(np.hypot(*(untilted - exact).T)) > 1e3 * errors[0]
