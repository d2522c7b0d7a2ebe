"""Invariants as property tests (hypothesis): symmetries, energy, ranges, fractions,
determinism across thread counts and tile sizes."""

import math

import numba
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import atlas
from atlas.kernels.rk4 import propagate_straightforward
from atlas.labels.trap import trap_margin
from atlas.physics.pendulum import Pendulum
from atlas.status import ATTRACTOR_FILL

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
angles = st.floats(-12.0, 12.0, allow_nan=False)
speeds = st.floats(-5.0, 5.0, allow_nan=False)
alphas = st.floats(0.05, 2.0)
omegas = st.floats(0.5, 2.0)


def _label(theta0, theta_dot0, alpha, omega0, **kw):
    return atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, t_max=150.0, **kw)


@SETTINGS
@given(st.lists(st.tuples(angles, speeds), min_size=1, max_size=16), alphas, omegas)
def test_point_reflection_maps_k_to_minus_k_exactly(points, alpha, omega0):
    theta0, theta_dot0 = np.array(points).T
    a = _label(theta0, theta_dot0, alpha, omega0)
    b = _label(-theta0, -theta_dot0, alpha, omega0)
    np.testing.assert_array_equal(a.status, b.status)
    trapped = a.status == 0
    np.testing.assert_array_equal(b.attractor[trapped], -a.attractor[trapped])
    np.testing.assert_array_equal(a.t_trap, b.t_trap)


@SETTINGS
@given(angles, speeds, alphas, omegas, st.integers(-3, 3))
def test_shift_by_2pi_k_maps_label_k_to_k_plus_j(theta0, theta_dot0, alpha, omega0, j):
    # compare only initial conditions whose label is robust: a 1e-6 neighbourhood agrees
    d = 1e-6
    around = _label(theta0 + np.array([0, d, -d, 0, 0]), theta_dot0 + np.array([0, 0, 0, d, -d]),
                    alpha, omega0)
    assume(np.all(around.status == 0) and np.all(around.attractor == around.attractor[0]))
    shifted = _label(theta0 + 2 * math.pi * j, theta_dot0, alpha, omega0)
    assert shifted.status[()] == 0 and shifted.attractor[()] == around.attractor[0] + j


@SETTINGS
@given(st.lists(st.tuples(angles, speeds), min_size=1, max_size=32), alphas, omegas,
       st.floats(0.5, 40.0))
def test_labels_statuses_and_times_in_range(points, alpha, omega0, t_max):
    theta0, theta_dot0 = np.array(points).T
    r = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, t_max=t_max)
    assert set(np.unique(r.status)) <= {0, 1, 2}
    trapped = r.status == 0
    assert np.all((r.attractor == ATTRACTOR_FILL) == ~trapped)
    assert np.all(np.isnan(r.t_trap) == ~trapped)
    t = r.t_trap[trapped]
    assert np.all((t >= 0) & (t <= t_max + 16 * 0.01 + 1e-6))
    k = r.attractor[trapped]
    # the attractor reached is within the energy's reach: E(0) ≥ energy needed to pass saddles
    p = Pendulum(alpha, omega0)
    e0 = p.energy(theta0[trapped], theta_dot0[trapped])
    passes = np.abs(k - np.round(theta0[trapped] / (2 * np.pi)))
    assert np.all((passes == 0) | (e0 >= p.saddle_energy * 0.999))


@pytest.mark.slow
@SETTINGS
@given(angles, speeds, alphas, omegas)
def test_energy_never_increases_along_an_orbit(theta0, theta_dot0, alpha, omega0):
    p = Pendulum(alpha, omega0)
    dt = 0.01
    theta, theta_dot = np.array([theta0]), np.array([theta_dot0])
    energy = [p.energy(theta0, theta_dot0)]
    for _ in range(400):
        propagate_straightforward(theta, theta_dot, alpha, omega0, dt, 1)
        energy.append(p.energy(theta[0], theta_dot[0]))  # E about well 0: smooth in θ
    rise = np.max(np.array(energy) - np.minimum.accumulate(energy))
    # the same 5 % of the margin as tests/labels/test_labels.py
    assert rise <= 0.05 * trap_margin(dt, alpha, omega0) * p.saddle_energy


@pytest.mark.slow
@settings(max_examples=6, deadline=None)
@given(alphas, omegas, st.integers(1, 200))
def test_basin_fractions_in_unit_interval_summing_to_one(tmp_path_factory, alpha, omega0,
                                                         tile_orbits):
    tmp = tmp_path_factory.mktemp("frac")
    cfg = atlas.Config.model_validate({
        "pendulum": {"alpha": alpha, "omega0": omega0},
        "grid": {"theta0": {"start": -7, "stop": 7, "num": 9},
                 "theta_dot0": {"start": -3, "stop": 3, "num": 7}},
        "separatrices": {"enabled": False}, "execution": {"tile_orbits": tile_orbits},
        "output": str(tmp / "f.h5")})
    ds = atlas.run(cfg, quiet=True).to_dataset(inherit=False)
    p = ds["basin_fraction"].values
    assert np.all((0 <= p) & (p <= 1))
    assert math.isclose(p.sum() + float(ds["unresolved_fraction"]), 1.0, abs_tol=1e-12)


def test_results_do_not_depend_on_thread_count_or_batch_split():
    rng = np.random.default_rng(7)
    theta0 = rng.uniform(-10, 10, 3001)
    theta_dot0 = rng.uniform(-4, 4, 3001)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = _label(theta0, theta_dot0, 0.1, 1.0)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = _label(theta0, theta_dot0, 0.1, 1.0)
    finally:
        numba.set_num_threads(threads)
    pieces = [_label(theta0[s], theta_dot0[s], 0.1, 1.0)
              for s in (slice(0, 1), slice(1, 1000), slice(1000, 3001))]
    for name in ("attractor", "status", "t_trap"):
        np.testing.assert_array_equal(getattr(one, name), getattr(many, name))
        np.testing.assert_array_equal(
            getattr(one, name), np.concatenate([getattr(p, name) for p in pieces]))
