"""The trig-free step's order, fitted: RK4 on the extended system (θ, θ̇, c, s) of
:mod:`atlas.kernels.trigfree`, with and without torque (the step every trig-free kernel
inlines), converges at order 4 against scipy's DOP853 at rtol 1e-13 on eq. (1) itself. The
global error at t = 4 s is fitted against dt over 0.02 … 0.005 s; the slope must lie in
3.9 … 4.2 (the asymptotic regime: the fitted slopes are 3.93–4.07). A slip of O(dt²) in one
stage (τ or a c, s update left out of it) makes the slope ≈ 2, and an equation of the wrong
system (c and s not carried) makes it ≈ 0: this test refuses both."""

import math

import numba as nb
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.kernels.trigfree import trigfree_step, trigfree_step_torque


@nb.njit
def _integrate(theta, theta_dot, alpha, omega0, dt, n, torque):
    """``n`` trig-free steps from (θ, θ̇), (c, s) = (cos θ, sin θ) at the start and never
    re-synchronised (so that the step alone is measured)."""
    c, s = math.cos(theta), math.sin(theta)
    for _ in range(n):
        if torque == 0.0:
            theta, theta_dot, c, s = trigfree_step(theta, theta_dot, c, s, alpha, omega0, dt)
        else:
            theta, theta_dot, c, s = trigfree_step_torque(theta, theta_dot, c, s, alpha,
                                                          omega0, dt, torque)
    return theta, theta_dot


def _dop853(y0, alpha, omega0, torque, t_end):
    w2, a2 = omega0**2, 2 * alpha
    sol = solve_ivp(lambda _, y: [y[1], torque - w2 * math.sin(y[0]) - a2 * y[1]],
                    (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[:, -1]


# a libration, an orbit over the saddle, a running orbit
ORBITS = [(0.2, 1.1), (2.0, 0.9), (-1.0, 3.0)]


@pytest.mark.parametrize("alpha,omega0,torque", [(0.1, 1.0, 0.0), (0.05, 1.0, 0.5),
                                                 (0.3, 1.5, -1.2), (0.1, 1.0, 1.6)])
def test_trigfree_step_converges_with_order_four(alpha, omega0, torque):
    t_end = 4.0
    exact = np.array([_dop853(list(y0), alpha, omega0, torque, t_end) for y0 in ORBITS])
    steps = np.array([200, 400, 800])  # dt = 0.02 … 0.005 s
    errors = np.array([[np.hypot(*(np.array(_integrate(t, v, alpha, omega0, t_end / n, int(n),
                                                       torque)) - y))
                        for n in steps] for (t, v), y in zip(ORBITS, exact)])
    assert errors.min() > 1e-12  # ten times the reference's own error and more
    for orbit, e in zip(ORBITS, errors):
        slope = -np.polyfit(np.log(steps), np.log(e), 1)[0]
        assert 3.9 < slope < 4.2, (orbit, slope, e)
    if torque:  # the torque matters: without it the orbits end far from the reference
        untilted = np.array([_integrate(t, v, alpha, omega0, t_end / 200, 200, 0.0)
                             for t, v in ORBITS])
        assert np.max(np.hypot(*(untilted - exact).T)) > 1e3 * errors.max(axis=0)[0]
