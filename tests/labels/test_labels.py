"""Certified labels: an independent reference, the symmetries, the energy trap's margin."""

import math

import numpy as np
import pytest

import atlas
from atlas.kernels.rk4 import propagate_straightforward
from atlas.kernels.trigfree import record_trigfree
from atlas.labels.trap import trap_margin
from atlas.physics.pendulum import Pendulum
from atlas.status import ATTRACTOR_FILL
from tests.helpers import boundary_adjacent, dop853_attractor

ALPHA, OMEGA0 = 0.1, 1.0


@pytest.fixture(scope="module")
def small_grid():
    theta0 = np.linspace(-2.95 * np.pi, 2.95 * np.pi, 40)  # misses the saddles (nπ, 0)
    theta_dot0 = np.linspace(-4.0, 4.0, 27)
    return np.meshgrid(theta0, theta_dot0)


@pytest.mark.slow
def test_labels_agree_with_dop853_away_from_boundaries(small_grid):
    theta0, theta_dot0 = small_grid
    res = atlas.label(theta0, theta_dot0, alpha=ALPHA, omega0=OMEGA0)
    assert np.all(res.status == 0)
    ref = np.array([[dop853_attractor(t, v, ALPHA, OMEGA0) for t, v in zip(rt, rv)]
                    for rt, rv in zip(theta0, theta_dot0)], dtype=object)
    settled = ref != None  # noqa: E711 (object array)
    assert settled.mean() > 0.99
    ref_k = np.where(settled, ref, 10_000).astype(int)
    interior = ~boundary_adjacent(ref_k) & settled
    assert interior.sum() > 0.25 * ref_k.size  # the comparison covers much of the grid
    np.testing.assert_array_equal(res.attractor[interior], ref_k[interior])


def test_point_reflection_maps_k_to_minus_k(small_grid):
    theta0, theta_dot0 = small_grid
    res = atlas.label(theta0, theta_dot0, alpha=ALPHA, omega0=OMEGA0)
    mirrored = atlas.label(-theta0, -theta_dot0, alpha=ALPHA, omega0=OMEGA0)
    np.testing.assert_array_equal(mirrored.attractor, -res.attractor)
    np.testing.assert_array_equal(mirrored.t_trap, res.t_trap)


def test_shift_by_two_pi_maps_k_to_k_plus_one(small_grid):
    theta0, theta_dot0 = small_grid
    res = atlas.label(theta0, theta_dot0, alpha=ALPHA, omega0=OMEGA0)
    shifted = atlas.label(theta0 + 2 * np.pi, theta_dot0, alpha=ALPHA, omega0=OMEGA0)
    # θ0 + 2π rounds differently from θ0 only for orbits that pass within ~1e-15 of a
    # separatrix; on this grid none does
    np.testing.assert_array_equal(shifted.attractor, res.attractor + 1)


def test_rest_states_and_statuses():
    res = atlas.label([0.0, 2 * np.pi, np.nan, 0.0, np.pi], [0.0, 0.0, 0.0, np.inf, 0.0],
                      alpha=ALPHA, omega0=OMEGA0, t_max=5.0)
    assert list(res.status) == [0, 0, 2, 2, 1]  # saddle (π, 0) is an equilibrium: unresolved
    assert list(res.attractor) == [0, 1, ATTRACTOR_FILL, ATTRACTOR_FILL, ATTRACTOR_FILL]
    assert res.t_trap[0] == 0.0 and np.isnan(res.t_trap[2:]).all()
    assert res.attractor.dtype == np.int16 and res.status.dtype == np.int8
    assert res.t_trap.dtype == np.float32


def test_shapes_broadcast():
    res = atlas.label(np.zeros((3, 1)), np.zeros(4), alpha=ALPHA, omega0=OMEGA0)
    assert res.attractor.shape == res.status.shape == res.t_trap.shape == (3, 4)


def test_straightforward_kernel_agrees(small_grid):
    theta0, theta_dot0 = small_grid
    a = atlas.label(theta0, theta_dot0, alpha=ALPHA, omega0=OMEGA0)
    b = atlas.label(theta0, theta_dot0, alpha=ALPHA, omega0=OMEGA0, kernel="straightforward")
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_array_equal(a.attractor, b.attractor)
    np.testing.assert_array_equal(a.t_trap, b.t_trap)


def _one_step_each(method):
    """advance(θ, θ̇, alpha, omega0, dt, n) -> every state of n steps, shape (n + 1, N)."""
    if method == "rk4":
        def advance(theta, theta_dot, alpha, omega0, dt, n):
            states = [(theta.copy(), theta_dot.copy())]
            for _ in range(n):
                propagate_straightforward(theta, theta_dot, alpha, omega0, dt, 1)
                states.append((theta.copy(), theta_dot.copy()))
            return np.array([s[0] for s in states]), np.array([s[1] for s in states])
        return advance

    def advance(theta, theta_dot, alpha, omega0, dt, n):
        # the trig-free method with its re-synchronisation every SYNC_EVERY steps (libm sin/cos
        # there; the lane kernel's polynomial differs by rounding only)
        out = np.empty((2, n + 1, theta.size))
        record_trigfree(theta, theta_dot, alpha, omega0, dt, 1, out)
        return out[0], out[1]
    return advance


@pytest.mark.slow
@pytest.mark.parametrize("method", ["rk4", "rk4-trigfree"])
@pytest.mark.parametrize("alpha,omega0,dt", [(0.1, 1.0, 0.01), (0.02, 1.0, 0.01),
                                             (1.0, 2.0, 0.02), (3.0, 1.0, 0.05),
                                             (1e-6, 1.0, 0.01)])  # damping hides nothing
def test_energy_never_increases_beyond_the_trap_margin(alpha, omega0, dt, method):
    """Along computed orbits of each method, the largest rise of E over any stretch stays far
    below the trap margin m·2ω0² (so a trapped orbit cannot climb out of its well)."""
    p = Pendulum(alpha, omega0)
    rng = np.random.default_rng(1)
    # orbits near the separatrix energy (the hardest case) and generic ones
    phi = rng.uniform(-np.pi, np.pi, 400)
    e_target = p.saddle_energy * rng.uniform(0.95, 1.0, 400)
    theta_dot = np.sqrt(np.maximum(2 * (e_target - p.energy(phi, 0.0)), 0.0))
    thetas, speeds = _one_step_each(method)(phi.copy(), theta_dot, alpha, omega0, dt, 3000)
    wells = np.round(thetas / (2 * np.pi))
    energy = p.energy(thetas, speeds, wells)
    # E_k is the energy in well k: compare only orbits that stay in one well
    one_well = np.all(wells == wells[0], axis=0)
    assert one_well.sum() > 100
    running_min = np.minimum.accumulate(energy, axis=0)
    rise = np.max((energy - running_min)[:, one_well])
    margin = trap_margin(dt, alpha, omega0) * p.saddle_energy
    assert rise < 0.05 * margin, (rise, margin)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["rk4", "rk4-trigfree"])
def test_trapped_orbits_never_leave_their_well(method):
    p = Pendulum(ALPHA, OMEGA0)
    m = trap_margin(0.01, ALPHA, OMEGA0)
    # start just inside the trap level, at every phase of the well
    phi = np.linspace(-np.pi + 1e-3, np.pi - 1e-3, 501)
    cap = p.saddle_energy * (1 - m)
    theta_dot = np.sqrt(np.maximum(2 * (cap * (1 - 1e-12) - p.energy(phi, 0.0)), 0.0))
    if method == "rk4":
        theta = phi.copy()
        states = []
        for _ in range(200):
            propagate_straightforward(theta, theta_dot, ALPHA, OMEGA0, 0.01, 50)
            states.append((theta.copy(), theta_dot.copy()))
        thetas, speeds = (np.array(x) for x in zip(*states))
    else:
        out = np.empty((2, 201, phi.size))
        record_trigfree(phi, theta_dot, ALPHA, OMEGA0, 0.01, 50, out)
        thetas, speeds = out[0, 1:], out[1, 1:]
    assert np.all(np.abs(thetas) < math.pi)
    assert np.all(p.energy(thetas, speeds) < cap)


def test_the_energy_rise_measurement_sees_an_energy_gaining_method():
    """The measurement of the test above is not vacuous: forward Euler, which gains energy
    (E grows by the factor 1 + ω²dt² per step near the bottom), fails it."""
    alpha, omega0, dt = 0.1, 1.0, 0.01
    p = Pendulum(alpha, omega0)
    theta, theta_dot = np.linspace(-3.0, 3.0, 50), np.zeros(50)
    energy = [p.energy(theta, theta_dot)]
    for _ in range(3000):
        theta, theta_dot = (theta + dt * theta_dot,
                            theta_dot + dt * (-omega0**2 * np.sin(theta) - 2 * alpha * theta_dot))
        energy.append(p.energy(theta, theta_dot))
    energy = np.array(energy)
    rise = np.max(energy - np.minimum.accumulate(energy, axis=0))
    assert rise > 0.05 * trap_margin(dt, alpha, omega0) * p.saddle_energy


@pytest.mark.parametrize("kwargs,message", [
    ({"alpha": -0.5}, "alpha"), ({"alpha": 0.0}, "no orbit ever settles"),
    ({"omega0": 0.0}, "omega0"), ({"dt": -0.01}, "dt"), ({"dt": 0.0}, "dt"),
    ({"t_max": float("nan")}, "t_max"), ({"t_max": 1e9, "dt": 1e-3}, "steps"),
    ({"dt": 3.0}, "stability limit"), ({"dt": 1.0}, "too coarse for certified labels"),
    ({"alpha": 60.0}, "too coarse for certified labels"),
])
def test_label_refuses_settings_it_cannot_certify(kwargs, message):
    args = {"alpha": ALPHA, "omega0": OMEGA0, **kwargs}
    with pytest.raises(ValueError, match=message):
        atlas.label(0.5, 0.0, **args)


@pytest.mark.parametrize("theta0,theta_dot0", [(2 * np.pi * 40_000, 0.0), (1e17, 0.0),
                                               (2 * np.pi * (2**32 + 5), 1.0), (0.0, 3e4)])
def test_orbits_that_may_pass_the_int16_wells_are_refused(theta0, theta_dot0):
    with pytest.raises(ValueError, match="32767"):
        atlas.label([0.0, theta0], [0.0, theta_dot0], alpha=ALPHA, omega0=OMEGA0)


def test_the_fast_kernel_hands_huge_angles_to_the_reference_path():
    """Beyond fast_sin's stated range the lane kernel must give the straightforward kernel's
    answer (kernels called directly: atlas.label refuses such inputs)."""
    from atlas.kernels.lanes import label_lanes
    from atlas.kernels.rk4 import label_straightforward

    theta0 = np.array([2 * np.pi * (2**31 + 5) + 0.1, 1e7 + 0.3, 0.5])
    outs = []
    for kernel in (label_lanes, label_straightforward):
        out = (np.zeros(3, np.int32), np.zeros(3, np.int8), np.zeros(3, np.int32))
        kernel(theta0, np.zeros(3), ALPHA, OMEGA0, 0.01, 100, 16, 1.9, *out)
        outs.append(out)
    for a, b in zip(*outs):
        np.testing.assert_array_equal(a, b)
