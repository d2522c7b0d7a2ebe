"""The running limit cycle and its certificate (atlas.physics.running) against independent
references.

References: scipy's ``solve_ivp`` DOP853 on θ̈ = τ − ω0² sin θ − 2αθ̇ in the actual
coordinates (no mirroring, no Poincaré section); quadrature of dθ/θ̇ along the returned curve;
the small-damping limit τ_c → 8αω0/π (Melnikov / energy balance; Strogatz, *Nonlinear
Dynamics and Chaos*, §8.5) and the large-torque limit ⟨θ̇⟩ → τ/(2α); the symmetries
(θ, θ̇, τ) → (−θ, −θ̇, −τ) and θ → θ + 2π; the energy trap of the rest states.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp

from atlas.defaults import DT
from atlas.physics.barrier import RunningBarrier
from atlas.physics.running import (
    RunningCertificate,
    check_barrier,
    contains,
    homoclinic_threshold,
    limit_cycle,
    rk4_allowance,
    running_barrier,
)

TWO_PI = 2 * math.pi
#: (α, ω0, τ): bistable (the bSTAB pendulum, Stender & Hoffmann, Nonlinear Dyn. 107,
#: 1451–1468 (2022): θ̈ + 0.1θ̇ + sin θ = 0.5), bistable with other parameters, the bSTAB case
#: mirrored, and monostable running (τ = 1.2ω0²).
CASES = {
    "bstab": (0.05, 1.0, 0.5),
    "bistable": (0.1, 1.0, 0.4),
    "omega0=1.5": (0.2, 1.5, 1.0),
    "reversed": (0.05, 1.0, -0.5),
    "monostable": (0.1, 1.0, 1.2),
}
BISTABLE = ("bstab", "bistable", "omega0=1.5", "reversed")


@pytest.fixture(scope="module")
def cycles():
    return {name: limit_cycle(*params) for name, params in CASES.items()}


@pytest.fixture(scope="module")
def barriers(cycles):
    """The barriers for the kernels' default RK4 step."""
    return {name: running_barrier(*CASES[name], cycles[name], dt=DT) for name in CASES}


def dop853(alpha, omega0, torque, y0, t_end, **kwargs):
    """Orbits of the actual equation (vectorised over columns of ``y0`` = (θ, θ̇)),
    independent of atlas.physics.running."""
    y0 = np.asarray(y0, float)
    n = y0.size // 2

    def rhs(_, y):
        theta, theta_dot = y[:n], y[n:]
        return np.concatenate([theta_dot, torque - omega0**2 * np.sin(theta)
                               - 2 * alpha * theta_dot])

    return solve_ivp(rhs, (0.0, t_end), y0.ravel(), method="DOP853", **kwargs)


def rk4_step(alpha, omega0, torque, theta, theta_dot, dt):
    """One classical RK4 step of the actual equation (the kernels' method "rk4")."""

    def f(th, v):
        return v, torque - omega0**2 * np.sin(th) - 2 * alpha * v

    k1 = f(theta, theta_dot)
    k2 = f(theta + dt / 2 * k1[0], theta_dot + dt / 2 * k1[1])
    k3 = f(theta + dt / 2 * k2[0], theta_dot + dt / 2 * k2[1])
    k4 = f(theta + dt * k3[0], theta_dot + dt * k3[1])
    return (theta + dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]),
            theta_dot + dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))


def region_points(barrier, n, seed):
    """Random points of the barrier's region (actual coordinates)."""
    rng = np.random.default_rng(seed)
    theta = rng.uniform(-TWO_PI, TWO_PI, 40 * n)
    theta_dot = barrier.direction * rng.uniform(0, barrier.top, 40 * n)
    inside = contains(barrier, theta, theta_dot)
    assert inside.sum() >= n
    return theta[inside][:n], theta_dot[inside][:n]


@pytest.mark.parametrize("case", CASES)
def test_the_cycle_is_a_periodic_orbit(case, cycles):
    """One period from the returned start comes back to it, one turn on, and passes through
    every returned sample at the returned time."""
    alpha, omega0, torque = CASES[case]
    c = cycles[case]
    assert c.direction == np.sign(torque) and c.error < 1e-9
    sol = dop853(alpha, omega0, torque, [c.theta[0], c.theta_dot[0]], c.period, rtol=1e-12,
                 atol=1e-12, dense_output=True)
    theta, theta_dot = sol.y[:, -1]
    assert theta - c.theta[0] == pytest.approx(c.direction * TWO_PI, abs=1e-9)
    assert theta_dot == pytest.approx(c.theta_dot[0], abs=1e-9)
    theta_s, theta_dot_s = sol.sol(c.time)
    np.testing.assert_allclose(theta_s, c.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose(theta_dot_s, c.theta_dot, rtol=0, atol=1e-9)
    assert np.all(c.direction * c.theta_dot > 0)  # a rotation: θ̇ never vanishes


@pytest.mark.parametrize("case", CASES)
def test_period_is_the_integral_of_dtheta_over_theta_dot(case, cycles):
    c = cycles[case]
    # Simpson's rule on 1024 intervals (error O(h⁴)), T = ∫ dθ/θ̇ over one turn
    quadrature = simpson(1.0 / np.abs(c.theta_dot), x=np.abs(c.theta - c.theta[0]))
    assert quadrature == pytest.approx(c.period, rel=1e-10)
    assert c.time[-1] == pytest.approx(c.period, rel=1e-10)
    assert c.mean_theta_dot == pytest.approx(c.direction * TWO_PI / c.period)


def test_reversed_torque_mirrors_the_cycle(cycles):
    c, m = cycles["bstab"], cycles["reversed"]
    assert (c.direction, m.direction) == (1, -1)
    np.testing.assert_array_equal(m.theta, -c.theta)
    np.testing.assert_array_equal(m.theta_dot, -c.theta_dot)
    assert m.period == c.period and m.mean_theta_dot == -c.mean_theta_dot


def test_large_torque_limit_is_torque_over_two_alpha():
    """For τ ≫ ω0² the pendulum spins near v = τ/(2α). To second order in ω0²: θ̇ = v + u with
    u̇ ≈ −ω0² sin(vt) − 2αu, so u ≈ ω0²(v cos vt − 2α sin vt)/v², and the mean of θ̈ = 0
    gives ⟨u⟩ = −ω0²⟨sin θ⟩/(2α) = −ω0⁴/(2v³): the relative deficit ω0⁴/(2v⁴) → 0."""
    alpha, omega0 = 0.1, 1.0
    deficits = []
    for tau in (1.5, 4.0, 16.0):
        v = tau / (2 * alpha)
        deficits.append(1 - limit_cycle(alpha, omega0, tau).mean_theta_dot / v)
        if tau > 2:
            assert deficits[-1] == pytest.approx(omega0**4 / (2 * v**4), rel=1e-3)
    assert deficits[0] > deficits[1] > deficits[2] > 0


def test_threshold_tends_to_the_melnikov_estimate():
    """τ_c → 8αω0/π as α → 0: energy gained per turn 2πτ against 2α∮θ̇ dθ = 16αω0 lost along
    the undamped homoclinic orbit θ̇ = 2ω0 cos(θ/2). The relative error shrinks (like α²)."""
    errors = [abs(homoclinic_threshold(alpha, 1.0) / (8 * alpha / math.pi) - 1)
              for alpha in (0.04, 0.02, 0.01)]
    assert errors[0] > 3 * errors[1] > 9 * errors[2] and errors[2] < 1e-3


def test_threshold_of_the_bstab_pendulum_and_its_scaling():
    """For θ̈ + 0.1θ̇ + sin θ = τ the running solution first appears between τ = 0.11 and 0.16
    (bSTAB, Stender & Hoffmann 2022); t → ω0t gives τ_c(α, ω0) = ω0²·τ_c(α/ω0, 1)."""
    tau_c = homoclinic_threshold(0.05, 1.0)
    assert 0.11 < tau_c < 0.16
    assert homoclinic_threshold(0.1, 2.0) == pytest.approx(4 * tau_c, rel=1e-9)


@pytest.mark.slow
def test_threshold_agrees_with_the_existence_of_the_cycle():
    tau_c = homoclinic_threshold(0.05, 1.0)
    assert limit_cycle(0.05, 1.0, tau_c * (1 - 1e-4)) is None
    assert limit_cycle(0.05, 1.0, -tau_c * (1 - 1e-4)) is None
    assert limit_cycle(0.05, 1.0, tau_c * (1 + 1e-4)) is not None
    assert limit_cycle(0.05, 1.0, 0.0) is None
    # strong damping: the cycle is born at the saddle-node τ = ω0², not before
    assert homoclinic_threshold(1.0, 1.0) == 1.0
    assert limit_cycle(1.0, 1.0, 0.999) is None
    assert limit_cycle(1.0, 1.0, 1.05) is not None


@pytest.mark.parametrize("case", CASES)
def test_barrier_is_verified_and_holds_the_cycle(case, cycles, barriers):
    alpha, omega0, torque = CASES[case]
    b, c = barriers[case], cycles[case]
    assert isinstance(b, RunningBarrier) and isinstance(b, RunningCertificate) and b.dt == DT
    check = check_barrier(alpha, omega0, torque, b, dt=DT)
    assert check.ok and check.margin == b.verified_margin > 0
    exact = check_barrier(alpha, omega0, torque, b)  # the exact flow needs no RK4 allowance
    assert exact.ok and exact.margin > check.margin
    assert b.top > (abs(torque) + omega0**2) / (2 * alpha) and b.g.dtype == np.float64
    # on the cycle, just below it, and one turn on either side
    for k in (-1, 0, 3):
        shift = TWO_PI * k
        assert contains(b, c.theta + shift, c.theta_dot).all()
        assert contains(b, c.theta + shift, c.theta_dot * (1 - 1e-3)).all()
    # it reaches far below the cycle (the slowest point: within a few % of θ̇ = 0)
    slowest = np.argmin(np.abs(c.theta_dot))
    assert contains(b, c.theta[slowest], 0.1 * c.theta_dot[slowest])
    # Φ = d/dt(θ̇ − g(θ)) on the lower curve, sampled inside every segment, is above the margin
    m = b.g.size - 1
    h = TWO_PI / m
    x = np.linspace(0, 1, 9)[:, None]
    slope = np.diff(b.g) / h
    theta = b.theta0 + h * (np.arange(m) + x)
    g = b.g[:-1] + x * h * slope
    phi = abs(torque) - omega0**2 * np.sin(theta) - (2 * alpha + slope) * g
    assert phi.min() >= b.verified_margin


@pytest.mark.parametrize("case", BISTABLE)
def test_barrier_never_holds_a_rest_state_or_the_energy_trap(case, barriers):
    """Points of a well whose energy E = ½θ̇² − ω0² cos θ − τθ is below that of its lower
    saddle, between its saddles, never leave the well: the barrier must exclude them all."""
    alpha, omega0, torque = CASES[case]
    b = barriers[case]
    d, tau, w2 = np.sign(torque), abs(torque), omega0**2
    # canonical frame (τ > 0): well between saddles θ_sad − 2π and θ_sad (the lower one)
    rest, saddle = math.asin(tau / w2), math.pi - math.asin(tau / w2)
    rng = np.random.default_rng(1)
    theta = rng.uniform(saddle - TWO_PI, saddle, 20_000)
    lower = -w2 * math.cos(saddle) - tau * saddle
    room = 2 * (lower - (-w2 * np.cos(theta) - tau * theta))
    keep = room > 0
    theta, room = theta[keep], room[keep]
    theta_dot = rng.uniform(-1, 1, theta.size) * np.sqrt(room)
    assert theta.size > 5000
    for k in (-2, 0, 1):
        assert not contains(b, d * (theta + TWO_PI * k), d * theta_dot).any()
    for rest_state in (rest, saddle, rest + TWO_PI, saddle - 5 * TWO_PI):
        assert not contains(b, d * rest_state, 0.0)
    assert not contains(b, np.linspace(-10, 10, 1001), 0.0).any()


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_orbits_in_the_region_stay_there_and_reach_the_cycle(case, cycles, barriers):
    """Exact (DOP853) and RK4 (step DT) orbits from random points of the region never leave
    it in 200 s, and the exact ones end on the cycle."""
    alpha, omega0, torque = CASES[case]
    b, c = barriers[case], cycles[case]
    theta, theta_dot = region_points(b, 12, seed=7)
    n = theta.size
    t = np.linspace(0, 200, 20_001)
    sol = dop853(alpha, omega0, torque, np.concatenate([theta, theta_dot]), 200.0,
                 rtol=1e-10, atol=1e-10, t_eval=t)
    assert contains(b, sol.y[:n], sol.y[n:]).all()  # never leave
    # and end on the cycle: θ̇ against the cycle's θ̇ at the same angle
    phase = np.mod(c.direction * (sol.y[:n, -1] - c.theta0), TWO_PI)
    on_cycle = np.interp(phase, c.direction * (c.theta - c.theta0), c.theta_dot)
    np.testing.assert_allclose(sol.y[n:, -1], on_cycle, rtol=0, atol=1e-5)
    for _ in range(round(200 / DT)):
        theta, theta_dot = rk4_step(alpha, omega0, torque, theta, theta_dot, DT)
        assert contains(b, theta, theta_dot).all()


@pytest.mark.parametrize("case", CASES)
def test_rk4_step_maps_the_boundary_inward(case, barriers):
    """States on the lower curve (at its vertices and between them), on the seam and on the
    top line (each 1e-9 inside, against rounding) stay in the region after one RK4 step of
    DT."""
    alpha, omega0, torque = CASES[case]
    b = barriers[case]
    d, m = b.direction, b.g.size - 1
    u = b.theta0 + TWO_PI * np.arange(0, m, 0.5) / m
    g = np.interp(u, b.theta0 + TWO_PI * np.arange(m + 1) / m, b.g)
    seam = np.full(50, b.theta0 + TWO_PI * (1 - 1e-12))
    theta = np.concatenate([u, seam, u[::64]])
    theta_dot = np.concatenate([g + 1e-9, np.linspace(b.g[-1], b.top - 1e-9, 50),
                                np.full(u[::64].size, b.top - 1e-9)])
    assert contains(b, d * theta, d * theta_dot).all()
    after = rk4_step(alpha, omega0, torque, d * theta, d * theta_dot, DT)
    assert contains(b, *after).all()


@pytest.mark.parametrize(("case", "dt"), [("bstab", 0.01), ("bstab", 0.05), ("bistable", 0.1),
                                          ("omega0=1.5", 0.1), ("reversed", 0.05),
                                          ("monostable", 0.05)])
def test_rk4_allowance_covers_the_local_error(case, dt, barriers):
    """RK4's local error per unit time, against DOP853 at rtol 1e-13, at random points of the
    region: below 1/10 of the allowance in θ̇, and in θ times Λ = |θ̇| + ω0 + 2α."""
    alpha, omega0, torque = CASES[case]
    theta, theta_dot = region_points(barriers[case], 200, seed=3)
    n = theta.size
    exact = dop853(alpha, omega0, torque, np.concatenate([theta, theta_dot]), dt, rtol=1e-13,
                   atol=1e-13).y[:, -1]
    rk4 = rk4_step(alpha, omega0, torque, theta, theta_dot, dt)
    allowance = rk4_allowance(alpha, omega0, torque, dt, np.abs(theta_dot))
    lam = np.abs(theta_dot) + omega0 + 2 * alpha
    assert np.all(np.abs(rk4[1] - exact[n:]) / dt < allowance / 10)
    assert np.all(lam * np.abs(rk4[0] - exact[:n]) / dt < allowance / 10)


def test_rk4_step_too_coarse_is_refused(cycles, barriers):
    alpha, omega0, torque = CASES["bstab"]
    with pytest.raises(ValueError, match="too coarse"):
        running_barrier(alpha, omega0, torque, cycles["bstab"], dt=0.1)
    # the exact flow's barrier keeps its top too close for the RK4 step dt = 0.1
    alpha, omega0, torque = CASES["omega0=1.5"]
    exact = running_barrier(alpha, omega0, torque, cycles["omega0=1.5"])
    assert exact.dt is None and check_barrier(alpha, omega0, torque, exact).ok
    check = check_barrier(alpha, omega0, torque, exact, dt=0.1)
    assert not check.ok and "top" in check.reason and "RK4" in check.reason
    assert check_barrier(alpha, omega0, torque, running_barrier(
        alpha, omega0, torque, cycles["omega0=1.5"], dt=0.1), dt=0.1).ok


def test_verification_rejects_broken_barriers(cycles, barriers):
    """Each kind of broken barrier fails, and for its own reason."""
    alpha, omega0, torque = CASES["bstab"]
    b, c = barriers["bstab"], cycles["bstab"]

    def reason(**changes):
        fields = dict(theta0=b.theta0, g=b.g, top=b.top, direction=b.direction) | changes
        check = check_barrier(alpha, omega0, torque, SimpleNamespace(**fields))
        assert not check.ok
        return check.reason

    # a lower curve above the cycle: orbits there fall towards the cycle, through the curve
    above = b.g + (c.theta_dot.max() - b.g.min()) * 1.01
    assert "cross the lower curve upward" in reason(g=above)
    # a curve the flow crosses downward: built like the barrier with ε < 0
    epsilon = -0.05

    def lowered(theta, y):
        return [(torque - omega0**2 * np.sin(theta) - 2 * alpha * y[0] - epsilon) / y[0]]

    m = b.g.size - 1
    grid = b.theta0 + np.linspace(0, TWO_PI, m + 1)
    g = solve_ivp(lowered, (grid[0], grid[-1]), [b.g[0]], method="DOP853", rtol=1e-10,
                  t_eval=grid).y[0]
    assert g[-1] >= g[0]  # the jump condition holds: it fails on the crossing alone
    assert "cross the lower curve upward" in reason(g=g)
    # the jump at theta0 crossed leftward, out of the region: g[M] < g[0]
    assert "g[M] < g[0]" in reason(g=np.concatenate([b.g[:-1], [b.g[0] * 0.999]]))
    # a lower curve touching θ̇ = 0 would let a rest state in
    assert "rest state" in reason(g=np.where(np.arange(b.g.size) == 100, 0.0, b.g))
    # the top too low: the flow is not certainly downward across it
    assert "top" in reason(top=(torque + omega0**2) / (2 * alpha))
    assert "below top" in reason(g=b.g * 0 + b.top)
    assert "direction" in reason(direction=-1)


def test_verification_bounds_the_flow_inside_each_segment():
    """The ends of a segment are not enough: with τ = 1.2, α = 0.1, ω0 = 1 the line θ̇ = G is
    crossed upward where Φ = 1.2 − sin θ − 0.2G > 0. On four segments from θ = π/4 the
    samples see sin θ ≤ 1/√2 only; G = 1.5 passes there (Φ ≥ 0.19) but fails at θ = π/2
    (Φ = −0.1), and is rejected; G = 0.5 (Φ ≥ 0.1 everywhere) is accepted."""
    alpha, omega0, torque = 0.1, 1.0, 1.2
    top = 1.01 * (torque + omega0**2) / (2 * alpha)

    def line(level):
        return RunningBarrier(theta0=math.pi / 4, g=np.full(5, level), top=top, direction=1)

    rejected = check_barrier(alpha, omega0, torque, line(1.5))
    assert not rejected.ok and "cross the lower curve upward" in rejected.reason
    accepted = check_barrier(alpha, omega0, torque, line(0.5))
    assert accepted.ok and 0 < accepted.margin < 0.1


@pytest.mark.parametrize("torque", [0.0, 0.05, 0.1270088, 0.1270090, 0.3, -0.5, 1.5])
def test_the_cycles_existence_and_section_without_sampling_it(torque):
    """cycle_escapes (both > 0) agrees with limit_cycle's None on both sides of the
    homoclinic torque (0.127008859806 at α = 0.05); cycle_section is limit_cycle's crossing
    of its section, the same doubles, with or without the escapes given."""
    from atlas.physics.running import cycle_escapes, cycle_section

    cycle = limit_cycle(0.05, 1.0, torque)
    assert all(p > 0.0 for p in cycle_escapes(0.05, 1.0, torque)) == (cycle is not None)
    section = cycle_section(0.05, 1.0, torque)
    given = cycle_section(0.05, 1.0, torque, escapes=cycle_escapes(0.05, 1.0, torque))
    assert section == given
    if cycle is None:
        assert section is None
        return
    theta_s, v, period, error = section
    sign = 1 if torque > 0 else -1
    assert (sign * theta_s, sign * v, period, error) == (
        cycle.theta0, float(cycle.theta_dot[0]), cycle.period, cycle.error)
    # the turn the search ended on: from (θs, v) once round to θs + 2π, back at speed v
    *same, turn = cycle_section(0.05, 1.0, torque, turn=True)
    assert tuple(same) == section
    assert (turn.y[0, 0], turn.y[0, 1], turn.t[-1]) == (theta_s, v, period)
    assert turn.y[-1, 0] == pytest.approx(theta_s + 2 * math.pi, abs=1e-12)
    assert turn.y[-1, 1] == pytest.approx(v, rel=1e-11 + error)
