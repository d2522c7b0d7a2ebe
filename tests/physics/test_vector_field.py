"""θ* and the vector field, each written once (:func:`atlas.physics.pendulum.tilt`,
:meth:`Pendulum.acceleration` / :meth:`Pendulum.rhs`): against their closed forms, the
kernels' use of them and scipy's DOP853 with the energy balance dE/dt = −2αθ̇²."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas import kernels
from atlas.kernels.rk4 import torque_model
from atlas.physics.pendulum import Pendulum, tilt

CASES = [(0.1, 1.0, 0.5), (0.05, 1.0, -0.3), (2.0, 1.5, 1.2), (0.3, 0.7, 0.0)]


@pytest.mark.parametrize("omega0,torque", [(1.0, 0.5), (1.5, -1.2), (0.7, 0.3), (2.0, 3.9)])
def test_tilt_is_the_arcsine(omega0, torque):
    """sin θ* = τ/ω0² with |θ* | < π/2, odd in τ: the rest state where the field vanishes."""
    s = tilt(omega0, torque)
    assert abs(s) < math.pi / 2
    assert math.sin(s) == pytest.approx(torque / omega0**2, rel=2e-16, abs=0)
    assert tilt(omega0, -torque) == -s
    assert Pendulum(0.2, omega0, torque).rest_angle == s
    assert abs(Pendulum(0.2, omega0, torque).acceleration(s, 0.0)) < 1e-15 * omega0**2


def test_tilt_at_and_beyond_the_saddle_node():
    """0 (never −0) without torque; sign(τ)·π/2 from |τ| = ω0² on, where rest state and
    saddle merge (the kernels then trap nothing)."""
    assert tilt(1.3, 0.0) == 0.0 and math.copysign(1.0, tilt(1.3, -0.0)) == 1.0
    for torque in (1.0, 2.0, 1e9):
        assert tilt(1.0, torque) == math.pi / 2 and tilt(1.0, -torque) == -math.pi / 2
    with pytest.raises(ValueError, match="no rest state"):
        _ = Pendulum(0.1, 1.0, 1.0).rest_angle


def test_the_kernels_use_the_same_tilt():
    """One definition: atlas.physics re-exports the kernels' θ*, and the kernels' model tuple
    carries exactly it and 1 − cos θ*."""
    assert tilt is kernels.tilt
    for omega0, torque in [(1.0, 0.5), (1.5, -1.2), (1.0, 7.0)]:
        _, shift, vers, *_ = torque_model(omega0, torque)
        assert shift == tilt(omega0, torque)
        assert vers == pytest.approx(1.0 - math.cos(shift), rel=1e-15)


@pytest.mark.parametrize("alpha,omega0,torque", CASES)
def test_field_is_the_equation(alpha, omega0, torque):
    """θ̈ = τ − ω0² sin θ − 2αθ̇, for arrays (numpy) and one state (scipy's rhs, libm), the
    two within an ulp of each other."""
    p = Pendulum(alpha, omega0, torque)
    rng = np.random.default_rng(3)
    theta, theta_dot = rng.uniform(-9, 9, 200), rng.uniform(-5, 5, 200)
    expected = torque - omega0**2 * np.sin(theta) - 2.0 * alpha * theta_dot
    np.testing.assert_array_equal(p.acceleration(theta, theta_dot), expected)
    f0, f1 = p.field(theta, theta_dot)
    np.testing.assert_array_equal(f0, theta_dot)
    np.testing.assert_array_equal(f1, expected)
    for th, v, acc in zip(theta[:20], theta_dot[:20], expected[:20]):
        dth, dv = p.rhs(0.0, np.array([th, v]))
        assert dth == v and dv == pytest.approx(acc, rel=0, abs=4e-16 * (omega0**2 + abs(v)))
        assert p.theta_ddot(th, v) == dv


@pytest.mark.parametrize("alpha,omega0,torque", CASES)
def test_dop853_on_the_field_keeps_the_energy_balance(alpha, omega0, torque):
    """Along DOP853 orbits of ``rhs`` the total energy E = ½θ̇² − ω0² cos θ − τθ loses exactly
    2α∫θ̇² dt (integrated alongside): the field is the damped pendulum's with torque τ."""
    p = Pendulum(alpha, omega0, torque)

    def augmented(t, y):
        return [*p.rhs(t, y[:2]), y[1] * y[1]]

    for start in ([0.4, 1.0], [-2.0, 2.5], [3.0, -1.0]):
        sol = solve_ivp(augmented, (0.0, 20.0), [*start, 0.0], method="DOP853", rtol=1e-12,
                        atol=1e-12)
        theta, theta_dot, dissipated = sol.y[:, -1]
        change = p.total_energy(theta, theta_dot) - p.total_energy(*start)
        assert change == pytest.approx(-2.0 * alpha * dissipated, rel=1e-8, abs=1e-9)
