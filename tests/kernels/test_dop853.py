"""The compiled DOP853 of atlas.kernels.dop853 against scipy's solve_ivp(method="DOP853")
on the stable manifold's problem: the same method, so the same first step, the same curve
to the tolerance, the event where it belongs."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.boundaries import manifold
from atlas.boundaries.manifold import StableManifold
from atlas.kernels import dop853
from atlas.kernels.dop853 import EVENT, FULL, TABLEAU, Solution, Tableau, stable_manifold
from atlas.physics.pendulum import START_DISTANCE, Pendulum

RTOL = 1e-13


def _problem(alpha, omega0, speed):
    p = Pendulum(alpha=alpha, omega0=omega0)
    e_theta, e_speed = p.saddle_stable_direction()
    start = (math.pi - START_DISTANCE * e_theta, -START_DISTANCE * e_speed)
    y0 = np.array([*start, 0.5 * start[1] * START_DISTANCE * e_theta])
    e_stop = 0.5 * speed**2 + p.saddle_energy
    return p, y0, e_stop, 1e4 * (1 / alpha + 1 / omega0)


def _scipy(p, y0, e_stop, t_cap, theta_min=math.pi):
    def rhs(_, y):
        f0, f1 = p.field(y[0], y[1])
        return [-f0, -f1, f0 * f0]

    def beyond(_, y):
        return min(p.energy(y[0], y[1]) - e_stop, theta_min - y[0])

    beyond.terminal, beyond.direction = True, 1
    return solve_ivp(rhs, (0.0, t_cap), y0, method="DOP853", rtol=RTOL, atol=RTOL,
                     dense_output=True, events=beyond)


def _compiled(p, y0, e_stop, t_cap, capacity=4096, theta_min=math.pi):
    return stable_manifold(y0, 0.0, t_cap, RTOL, RTOL, p.alpha, p.omega0, e_stop, theta_min,
                           capacity)


@pytest.mark.parametrize("alpha, omega0, speed", [(0.1, 1.0, 4.0), (0.5, 2.0, 6.0),
                                                  (0.02, 1.0, 3.0)])
def test_same_method_as_scipy_same_curve(alpha, omega0, speed):
    p, y0, e_stop, t_cap = _problem(alpha, omega0, speed)
    ref = _scipy(p, y0, e_stop, t_cap)
    status, n, t, y, t_old, h, y_old, F = _compiled(p, y0, e_stop, t_cap)
    assert status == EVENT and ref.status == 1
    # the same initial step and first step, to rounding (the same method and controller)
    assert t[1] == pytest.approx(ref.t[1], rel=1e-14)
    np.testing.assert_allclose(y[1], ref.y[:, 1], rtol=1e-13, atol=1e-20)
    # later steps drift apart by rounding in the error estimate; the curves stay together:
    # every compiled point lies within the tolerance of scipy's curve (its own samples
    # refined by Newton's method, through StableManifold's foot points)
    assert abs(n - (ref.t.size - 1)) <= max(3, n // 20)
    m = StableManifold(p, speed)
    m._pieces[0] = Solution(EVENT, ref.t, ref.y.T, *(np.array([getattr(q, a) for q in
                                                              ref.sol.interpolants])
                                                    for a in ("t_old", "h", "y_old", "F")))
    m._finish()
    inside = y[: n + 1, 1] <= speed
    _, dist = m.foot_points(y[: n + 1][inside, 0], y[: n + 1][inside, 1])
    assert dist.max() < 1e-11
    # the event: E = e_stop at the end, as at scipy's
    end = y[n]
    assert p.energy(end[0], end[1]) == pytest.approx(e_stop, rel=1e-14)
    # Q = ∫ θ̇ dθ along the curve: the same at the end, both curves ending at the same E
    assert end[2] == pytest.approx(ref.y[2, -1], rel=1e-11)


def test_dense_output_joins_the_steps():
    """Step i's polynomial at x = 1 is the next step's start (continuity of the interpolant,
    which evaluates F from lowest to highest power as StableManifold does)."""
    p, y0, e_stop, t_cap = _problem(0.1, 1.0, 4.0)
    status, n, t, y, t_old, h, y_old, F = _compiled(p, y0, e_stop, t_cap)
    dense = manifold.DenseOutput(t[: n + 1], t_old[:n], h[:n], y_old[:n], F[:n])
    ends = dense(t_old[:n] + h[:n] * (1 - 1e-15)).T
    np.testing.assert_allclose(ends[:-1], y_old[1:n], rtol=1e-12, atol=1e-14)


def test_too_few_steps_of_room_is_said_and_more_are_made():
    p, y0, e_stop, t_cap = _problem(0.1, 1.0, 4.0)
    status, n = _compiled(p, y0, e_stop, t_cap, capacity=4)[:2]
    assert (status, n) == (FULL, 4)
    full = StableManifold(p, 4.0)
    saved = manifold._STEPS
    try:
        manifold._STEPS = 3  # StableManifold asks again with more room
        small = StableManifold(p, 4.0)
    finally:
        manifold._STEPS = saved
    np.testing.assert_array_equal(small.theta, full.theta)
    np.testing.assert_array_equal(small.theta_dot, full.theta_dot)


def test_torque_is_refused():
    with pytest.raises(ValueError, match="torque"):
        StableManifold(Pendulum(alpha=0.1, omega0=1.0, torque=0.2), 4.0)


def test_compiled_dense_output_is_scipys_polynomial():
    """manifold.DenseOutput (compiled: dense_output) at times before, inside, at the ends of
    and after the steps: scipy's own dense output of the same steps (rtol 1e-13) to rounding,
    and a step's ends where the next step begins."""
    p, y0, e_stop, t_cap = _problem(0.1, 1.0, 4.0)
    sol = _scipy(p, y0, e_stop, t_cap)
    dense = manifold.DenseOutput.from_scipy([sol.sol])
    ts = sol.sol.ts
    rng = np.random.default_rng(4)
    tau = np.concatenate([rng.uniform(ts[0], ts[-1], 500), ts])
    tau = tau[: tau.size // 4 * 4]
    got = dense(tau.reshape(-1, 4))
    assert got.shape == (3, tau.size // 4, 4)
    want = sol.sol(tau)
    np.testing.assert_allclose(got.reshape(3, -1), want, rtol=1e-12, atol=1e-14)
    # the same doubles as the scalar evaluation of the same polynomial (Python floats)
    some = tau[::7]
    np.testing.assert_array_equal(dense(some), np.array([dense.point(x) for x in some]).T)
    # beyond the ends: the first and last steps' polynomials, continued
    beyond = dense(np.array([ts[0] - 1e-3, ts[-1] + 1e-3]))
    np.testing.assert_allclose(beyond[:, 0], sol.sol.interpolants[0](ts[0] - 1e-3),
                               rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(beyond[:, 1], sol.sol.interpolants[-1](ts[-1] + 1e-3),
                               rtol=1e-12, atol=1e-14)


def test_the_tableau_is_consistent_to_rounding():
    """The DOP853 tableau checks itself as diffrax's ButcherTableau does: every row sum of A
    is its node c (stage s is evaluated at t + c_s·h, the dense output's extra stages at
    0.1, 0.2, 7/9 included), the weights B sum to 1 and the error weights E3, E5 to 0 —
    to rounding; and the compiled step uses those very arrays."""
    t = TABLEAU
    eps = np.finfo(float).eps
    assert t.a.shape == (16, 16) and t.c.shape == (16,) and np.all(np.triu(t.a) == 0.0)
    for s in range(16):
        assert abs(t.a[s].sum() - t.c[s]) <= 2 * eps * max(np.abs(t.a[s]).sum(), 1.0), s
    np.testing.assert_array_equal(t.c[13:], [0.1, 0.2, 7 / 9])
    assert abs(t.b.sum() - 1.0) <= 4 * eps * np.abs(t.b).sum()
    for e in (t.e3, t.e5):
        assert abs(e.sum()) <= 4 * eps * np.abs(e).sum()
    assert max(t.defects().values()) < 1.0
    assert (dop853._A is t.a and dop853._B is t.b and dop853._E3 is t.e3
            and dop853._E5 is t.e5 and dop853._D is t.d)


@pytest.mark.parametrize("field", ["a", "c", "b", "e3", "e5"])
def test_a_mistyped_coefficient_is_refused(field):
    """One coefficient off by 1e-10 of itself (a wrong 11th significant digit) is refused
    when the tableau is built, for every nonzero coefficient of A, C, B, E3 and E5: even the
    smallest against its row (A[15, 12] ≈ −0.0014 among terms up to 9) moves the row sum by
    21 ulps of the row's magnitude, five times the tolerance."""
    import dataclasses

    values = getattr(TABLEAU, field)
    for index in zip(*np.nonzero(values)):
        typo = values.copy()
        typo[index] *= 1.0 + 1e-10
        with pytest.raises(ValueError, match="inconsistent Runge-Kutta tableau"):
            dataclasses.replace(TABLEAU, **{field: typo})
    assert isinstance(dataclasses.replace(TABLEAU), Tableau)  # the true one is accepted

