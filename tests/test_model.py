"""The model: eigenvalues solve the characteristic equations; critical points; RK4 stability."""

import math

import numpy as np
import pytest

from atlas.model import Pendulum, critical_points, rk4_stable


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
