"""The compiled DOP853 (atlas.kernels.dop853.integrate) on the problems with torque that the
run path integrates, against scipy's solve_ivp(method="DOP853") on the same problems: a
tilted stable branch until it leaves a θ̇ band (REVERSED, BAND), one turn of the running
cycle's Poincaré map (FLOW, TURN) and an orbit as a function of θ (ALONG_THETA)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.kernels.dop853 import (
    ALONG_THETA,
    BAND,
    EVENT,
    FINISHED,
    FLOW,
    NONE,
    REVERSED,
    TURN,
    solve,
)
from atlas.physics.pendulum import START_DISTANCE, Pendulum

RTOL = 1e-12


def _accel(p, theta, theta_dot):
    return p.torque - p.omega0**2 * np.sin(theta) - 2 * p.alpha * theta_dot


@pytest.mark.parametrize("alpha, omega0, torque", [(0.05, 1.0, 0.5), (0.2, 1.5, 0.3),
                                                   (0.1, 1.0, 0.06)])
@pytest.mark.parametrize("sign", [-1, 1])
def test_tilted_branch_until_it_leaves_the_band(alpha, omega0, torque, sign):
    p = Pendulum(alpha, omega0, torque)
    e0, e1 = p.saddle_stable_direction()
    start = [p.saddle_angle + sign * START_DISTANCE * e0, sign * START_DISTANCE * e1]
    bottom, top = -8.0, 8.0

    def above(_, y):
        return y[1] - top

    def below(_, y):
        return y[1] - bottom

    above.terminal = below.terminal = True
    above.direction, below.direction = 1, -1
    ref = solve_ivp(lambda _, y: [-y[1], -_accel(p, *y)], (0.0, 1e5), start, method="DOP853",
                    rtol=RTOL, atol=RTOL, events=(above, below), dense_output=True)
    sol = solve(REVERSED, (alpha, omega0, torque, 0.0), BAND, (bottom, top), start, 1e5, RTOL,
                (RTOL,), dim=2)
    assert sol.status == EVENT and ref.status == 1
    # the same method and controller: the same first step, to the rounding of the field,
    # which 1e-7 from the saddle is τ − ω0² sin θ − 2αθ̇ ≈ 1e-7, a difference of O(1) terms
    # written in another order than scipy's callable (relative rounding ≈ 1e-16/1e-7)
    assert sol.t[1] == pytest.approx(ref.t[1], rel=1e-8)
    np.testing.assert_allclose(sol.y[1, :2], ref.y[:, 1], rtol=1e-13, atol=1e-15)
    # the same end (the event, where θ̇ leaves the band) and the same curve on the way: each
    # step end's foot on scipy's dense output (Newton's method on the time, from the same
    # time: the times drift apart slowly near the saddle) lies within the tolerance
    end = sol.y[-1, 1]
    assert min(abs(end - top), abs(end - bottom)) < 1e-12
    assert np.sign(end) == np.sign(ref.y[1, -1])
    assert sol.y[-1, 0] == pytest.approx(ref.y[0, -1], abs=1e-8)
    points = sol.y[:, :2].T
    t = np.clip(sol.t, 0.0, ref.t[-1])
    for _ in range(8):
        c = ref.sol(t)
        tangent = np.array([-c[1], -_accel(p, c[0], c[1])])
        t = np.clip(t - np.sum((c - points) * tangent, axis=0) / np.sum(tangent**2, axis=0),
                    0.0, ref.t[-1])
    assert np.hypot(*(ref.sol(t) - points)).max() < 1e-9


@pytest.mark.parametrize("theta_dot", [0.3, 2.0])
def test_one_turn_forward_with_the_turn_event(theta_dot):
    """From the saddle's angle: reached the next turn (fast), or turned back (slow)."""
    p = Pendulum(0.05, 1.0, 0.5)
    theta_s = p.saddle_angle
    end = theta_s + 2 * math.pi

    def arrive(_, y):
        return y[0] - end

    def stop(_, y):
        return y[1]

    arrive.terminal = stop.terminal = True
    arrive.direction, stop.direction = 1, -1
    atol = [RTOL * 2 * math.pi, RTOL * 15.0]
    ref = solve_ivp(lambda _, y: [y[1], _accel(p, *y)], (0.0, 1e4), [theta_s, theta_dot],
                    method="DOP853", rtol=RTOL, atol=atol, events=(arrive, stop))
    sol = solve(FLOW, (0.05, 1.0, 0.5, 0.0), TURN, (end,), (theta_s, theta_dot), 1e4, RTOL,
                atol, dim=2)
    assert sol.status == EVENT
    np.testing.assert_allclose(sol.y[-1, :2], ref.y[:, -1], rtol=1e-10, atol=1e-10)
    assert sol.t[-1] == pytest.approx(ref.t[-1], rel=1e-10)
    reached = ref.t_events[0].size > 0
    assert (sol.y[-1, 0] - end >= -sol.y[-1, 1]) == reached


def test_along_theta_matches_scipy_with_t_eval():
    """(θ̇, t) as functions of θ over one turn of a fast orbit, sampled as t_eval does."""
    p = Pendulum(0.05, 1.0, 0.5)
    theta = p.saddle_angle + np.linspace(0.0, 2 * math.pi, 65)
    y0 = (9.0, 0.0)
    atol = (RTOL * 15.0, RTOL * 10.0)
    ref = solve_ivp(lambda x, y: [_accel(p, x, y[0]) / y[0], 1.0 / y[0]], (theta[0], theta[-1]),
                    list(y0), method="DOP853", rtol=RTOL, atol=atol, t_eval=theta)
    sol = solve(ALONG_THETA, (0.05, 1.0, 0.5, 0.0), NONE, (), y0, theta[-1], RTOL, atol,
                dim=2, t0=theta[0])
    assert sol.status == FINISHED
    np.testing.assert_allclose(sol.at(theta)[:2], ref.y, rtol=1e-11)
