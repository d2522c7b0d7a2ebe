"""The model: eigenvalues solve the characteristic equations; critical points; RK4 stability."""

import math

import numpy as np
import pytest

from atlas.physics.pendulum import Pendulum, critical_points, rk4_stable


@pytest.mark.parametrize("alpha,omega0", [(0.1, 1.0), (1.0, 1.0), (3.0, 1.0), (0.0, 2.0),
                                          (50.0, 0.5)])
def test_eigenvalues_solve_the_characteristic_equations(alpha, omega0):
    p = Pendulum(alpha, omega0)
    for r in p.attractor_eigenvalues():  # r² + 2αr + ω0² = 0 (essay eq. 3)
        assert abs(r * r + 2 * alpha * r + omega0**2) < 1e-12 * max(1, abs(r) ** 2)
    u1, minus_u2 = p.saddle_eigenvalues()  # r² + 2αr − ω0² = 0 (essay eq. 24)
    assert u1 > 0 > minus_u2
    for r in (u1, minus_u2):
        assert abs(r * r + 2 * alpha * r - omega0**2) < 1e-12 * max(1, r * r)
    d_theta, d_theta_dot = p.saddle_stable_direction()
    assert d_theta_dot / d_theta == pytest.approx(minus_u2, rel=1e-14)


def test_critical_points_in_a_window():
    pts = critical_points(Pendulum(0.1, 1.0), -3 * math.pi, 3 * math.pi)
    assert [p.n for p in pts] == list(range(-3, 4))
    assert [p.kind for p in pts] == ["saddle", "attractor focus"] * 3 + ["saddle"]
    kinds = {a: critical_points(Pendulum(a, 1.0), -1, 1)[0].kind for a in (0.0, 0.5, 1.0, 2.0)}
    assert kinds == {0.0: "center", 0.5: "attractor focus", 1.0: "attractor critical node",
                     2.0: "attractor node"}


def test_energy_is_a_lyapunov_function():
    """dE/dt = −2αθ̇² along orbits: Pendulum.energy differentiated numerically along
    accurate RK4 trajectories (dt = 1e-3, central differences: error O(dt²))."""
    from atlas.kernels.rk4 import record_straightforward

    p = Pendulum(0.3, 1.5)
    dt = 1e-3
    theta, theta_dot = np.linspace(-7, 7, 9), np.linspace(3, -3, 9)
    out = np.empty((2, 2001, theta.size))
    record_straightforward(theta.copy(), theta_dot.copy(), p.alpha, p.omega0, dt, 1, out)
    energy = p.energy(out[0], out[1])
    d_energy = (energy[2:] - energy[:-2]) / (2 * dt)
    np.testing.assert_allclose(d_energy, -2 * p.alpha * out[1, 1:-1] ** 2, atol=1e-5)
    assert np.all(np.diff(energy, axis=0) <= 0)


def test_rk4_stability_limit():
    # on the real axis RK4 is stable for dt·|λ| ≤ 2.785…; overdamped α = 10: the fastest
    # decaying mode is the saddle's −u2 = −α − √(α² + ω0²) ≈ −20.05
    p = Pendulum(10.0, 1.0)
    fastest = abs(p.saddle_eigenvalues()[1])
    assert rk4_stable(p, 2.78 / fastest) and not rk4_stable(p, 2.79 / fastest)


@pytest.mark.parametrize("alpha,omega0", [(-1, 1), (0.1, 0), (float("nan"), 1), (0.1, math.inf)])
def test_bad_parameters(alpha, omega0):
    with pytest.raises(ValueError):
        Pendulum(alpha, omega0)


def test_field_and_its_derivative_along_the_flow():
    """field is (θ̇, θ̈) of eq. (1); field_jet's second part is df/dt = J·f, checked by central
    differences of f along f itself (ε = 1e-5: error O(ε²) ≈ 1e-10), for arrays and floats."""
    p = Pendulum(0.3, 1.5)
    rng = np.random.default_rng(5)
    theta, theta_dot = rng.uniform(-7, 7, 50), rng.uniform(-4, 4, 50)
    f0, f1 = p.field(theta, theta_dot)
    np.testing.assert_array_equal(f0, theta_dot)
    np.testing.assert_array_equal(f1, p.acceleration(theta, theta_dot))
    (j0, j1), (g0, g1) = p.field_jet(theta, theta_dot)
    np.testing.assert_array_equal(j0, f0)
    np.testing.assert_array_equal(j1, f1)
    eps = 1e-5
    ahead = p.field(theta + eps * f0, theta_dot + eps * f1)
    behind = p.field(theta - eps * f0, theta_dot - eps * f1)
    np.testing.assert_allclose(g0, (ahead[0] - behind[0]) / (2 * eps), rtol=0, atol=1e-8)
    np.testing.assert_allclose(g1, (ahead[1] - behind[1]) / (2 * eps), rtol=0, atol=1e-8)
    (s0, s1), (s2, s3) = p.field_jet(float(theta[0]), float(theta_dot[0]))  # floats stay
    assert all(np.ndim(x) == 0 for x in (s0, s1, s2, s3))  # scalars, the values checked above
    np.testing.assert_array_equal([s0, s1, s2, s3], [j0[0], j1[0], g0[0], g1[0]])


# ----------------------------------------------------------------------- torque τ
def test_zero_torque_is_the_untilted_pendulum():
    """Pendulum(α, ω0) (positional, as ever) is Pendulum(α, ω0, 0.0), and every quantity is the
    untilted formula's value to the bit."""
    p = Pendulum(0.1, 1.3)
    assert p == Pendulum(0.1, 1.3, 0.0) and p.torque == 0.0
    assert p.saddle_energy == 2 * 1.3**2 and p.saddle_energies == (2 * 1.3**2,) * 2
    assert p.rest_angle == 0.0 and p.saddle_angle == math.pi and p.stiffness == 1.3**2
    s = math.hypot(0.1, 1.3)
    assert p.saddle_eigenvalues() == (1.3**2 / (0.1 + s), -(0.1 + s))
    r2 = -0.1 - np.sqrt(complex(0.1**2 - 1.3**2))
    assert p.attractor_eigenvalues() == (complex(1.3**2 / r2), complex(r2))
    theta, theta_dot = np.linspace(-7, 7, 11), np.linspace(3, -3, 11)
    np.testing.assert_array_equal(
        p.energy(theta, theta_dot, 1),
        0.5 * theta_dot**2 + 2 * 1.3**2 * np.sin(0.5 * (theta - 2 * np.pi)) ** 2)
    np.testing.assert_array_equal(p.acceleration(theta, theta_dot),
                                  -1.3**2 * np.sin(theta) - 0.2 * theta_dot)
    pts = critical_points(p, -3 * math.pi, 3 * math.pi)
    assert [c.theta for c in pts] == [n * math.pi for n in range(-3, 4)]
    assert all(c.offset == 0.0 and math.copysign(1, c.offset) == 1 for c in pts)


@pytest.mark.parametrize("alpha,omega0,tau", [(0.1, 1.0, 0.5), (0.05, 1.0, -0.3),
                                              (2.0, 1.5, 1.2), (0.0, 1.0, 0.9)])
def test_tilted_critical_points(alpha, omega0, tau):
    """Rest states at θ* + 2πk, saddles at π − θ* + 2πk (θ* = arcsin(τ/ω0²)): the field vanishes
    there, the eigenvalues are those of the Jacobian [[0, 1], [−ω0² cos θc, −2α]], and even n
    (rest) / odd n (saddle) index the points near nπ."""
    p = Pendulum(alpha, omega0, tau)
    s = math.asin(tau / omega0**2)
    assert p.rest_angle == pytest.approx(s, abs=1e-15)
    pts = critical_points(p, -3 * math.pi, 3 * math.pi)
    assert [c.n for c in pts] == sorted(c.n for c in pts)
    for c in pts:
        assert c.theta == pytest.approx(c.n * math.pi + (-s if c.is_saddle else s), abs=1e-14)
        assert abs(c.theta - c.n * math.pi) < math.pi / 2
        assert -3 * math.pi <= c.theta <= 3 * math.pi
        assert abs(p.acceleration(c.theta, 0.0)) < 1e-14
        jac = np.array([[0.0, 1.0], [-omega0**2 * math.cos(c.theta), -2 * alpha]])
        np.testing.assert_allclose(sorted(np.linalg.eigvals(jac), key=lambda z: (z.real, z.imag)),
                                   sorted(c.eigenvalues, key=lambda z: (z.real, z.imag)),
                                   atol=1e-12)
        assert (c.kind == "saddle") == c.is_saddle
    # every critical point of the window, none missed near its ends
    thetas = [c.theta for c in pts]
    expect = sorted([s + 2 * math.pi * k for k in range(-2, 3)]
                    + [math.pi - s + 2 * math.pi * k for k in range(-3, 3)])
    expect = [x for x in expect if -3 * math.pi <= x <= 3 * math.pi]
    np.testing.assert_allclose(thetas, expect, atol=1e-14)
    kappa = p.stiffness
    assert kappa == pytest.approx(omega0**2 * math.cos(s), rel=1e-14)
    for r in p.attractor_eigenvalues():
        assert abs(r * r + 2 * alpha * r + kappa) < 1e-12
    u1, minus_u2 = p.saddle_eigenvalues()
    assert u1 > 0 > minus_u2
    for r in (u1, minus_u2):
        assert abs(r * r + 2 * alpha * r - kappa) < 1e-12
    d_theta, d_theta_dot = p.saddle_stable_direction()
    assert d_theta_dot / d_theta == pytest.approx(minus_u2, rel=1e-14)


def test_tilted_regime_and_kinds():
    """The rest states' regime compares α with √κ = (ω0⁴ − τ²)^¼: a torque softens the well."""
    assert Pendulum(0.9, 1.0).regime == "underdamped"
    assert Pendulum(0.9, 1.0, 0.8).regime == "overdamped"  # √κ = 0.6^½ ≈ 0.77
    assert critical_points(Pendulum(0.9, 1.0, 0.8), -1, 1)[0].kind == "attractor node"
    assert critical_points(Pendulum(0.0, 1.0, 0.5), -1, 1)[0].kind == "center"


@pytest.mark.parametrize("tau", [1.0, -1.0, 1.5, -7.0])
def test_no_critical_point_from_the_saddle_node_on(tau):
    p = Pendulum(0.1, 1.0, tau)
    assert not p.has_rest_states and critical_points(p, -10, 10) == []
    for method in (p.attractor_eigenvalues, p.saddle_eigenvalues):
        with pytest.raises(ValueError, match="no rest state"):
            method()
    assert Pendulum(0.1, 1.0, math.nextafter(1.0, 0.0)).has_rest_states
    assert p.regime == "no rest state"


@pytest.mark.parametrize("alpha,omega0,tau", [(0.1, 1.0, 0.5), (0.05, 2.0, -1.7), (1.0, 1.0, 0.99)])
def test_saddle_energies_are_the_same_in_every_well(alpha, omega0, tau):
    """energy(·, k) is the energy above the rest state of well k: 0 there, and at well k's
    left and right saddles the two saddle_energies, for every k; saddle_energy (the trap
    level) is the lower, the saddle on the side the torque pushes towards."""
    p = Pendulum(alpha, omega0, tau)
    s = p.rest_angle
    left, right = p.saddle_energies
    assert p.saddle_energy == min(left, right) and left - right == pytest.approx(
        2 * math.pi * tau)
    assert (p.saddle_energy == right) == (tau > 0)
    for k in (-40, -1, 0, 3, 1000):
        scale = 1e-15 * (omega0**2 + abs(tau) * (1 + abs(2 * math.pi * k)))
        assert abs(p.energy(s + 2 * math.pi * k, 0.0, k)) < 20 * scale
        assert p.energy(-math.pi - s + 2 * math.pi * k, 0.0, k) == pytest.approx(left,
                                                                                  abs=20 * scale)
        assert p.energy(math.pi - s + 2 * math.pi * k, 0.0, k) == pytest.approx(right,
                                                                                 abs=20 * scale)
        assert p.well(s + 2 * math.pi * k) == k
        lo, hi = p.well_bounds(k)
        assert lo == pytest.approx(-math.pi - s + 2 * math.pi * k, abs=1e-12) and hi - lo == (
            pytest.approx(2 * math.pi))
        assert p.well(math.pi - s + 2 * math.pi * k - 1e-9) == k
        assert p.well(math.pi - s + 2 * math.pi * k + 1e-9) == k + 1
    # the potential rises monotonically from the rest state to either saddle
    phi = np.linspace(-math.pi - s, math.pi - s, 2001)
    v = p.energy(phi, 0.0)
    i = np.argmin(v)
    assert np.all(np.diff(v[: i + 1]) < 0) and np.all(np.diff(v[i:]) > 0)
    # energy and total_energy differ by a constant in each well
    theta, theta_dot = np.linspace(-3, 3, 7), np.linspace(2, -1, 7)
    diff = p.energy(theta, theta_dot) - p.total_energy(theta, theta_dot)
    np.testing.assert_allclose(diff, diff[0], rtol=0, atol=1e-13)


def test_energy_is_a_lyapunov_function_with_torque():
    from atlas.kernels.rk4 import record_torque

    p = Pendulum(0.3, 1.5, 0.7)
    dt = 1e-3
    theta, theta_dot = np.linspace(-7, 7, 9), np.linspace(3, -3, 9)
    out = np.empty((2, 2001, theta.size))
    record_torque(theta.copy(), theta_dot.copy(), p.alpha, p.omega0, p.torque, dt, 1, out)
    for energy in (p.total_energy(out[0], out[1]), p.energy(out[0], out[1], 2)):
        d_energy = (energy[2:] - energy[:-2]) / (2 * dt)
        np.testing.assert_allclose(d_energy, -2 * p.alpha * out[1, 1:-1] ** 2, atol=1e-5)
    f0, f1 = p.field(out[0, 5], out[1, 5])
    np.testing.assert_allclose(f1, -1.5**2 * np.sin(out[0, 5]) - 0.6 * out[1, 5] + 0.7,
                               rtol=0, atol=1e-14)


@pytest.mark.parametrize("tau", [math.nan, math.inf, -math.inf])
def test_bad_torque(tau):
    with pytest.raises(ValueError, match="torque"):
        Pendulum(0.1, 1.0, tau)


def test_rk4_stability_ignores_the_torque():
    """The untilted check bounds every frozen Jacobian along any orbit (cos θ ∈ [−1, 1])."""
    p = Pendulum(10.0, 1.0)
    fastest = abs(p.saddle_eigenvalues()[1])
    for tau in (0.0, 0.5, 3.0):
        q = Pendulum(10.0, 1.0, tau)
        assert rk4_stable(q, 2.78 / fastest) and not rk4_stable(q, 2.79 / fastest)
