"""The driven pendulum's stroboscopic-map kernels (atlas.kernels.driven): RK4's order against
scipy's DOP853, bit-identity across calls, threads and chunking, and the proximity labelling
against an independent numpy reference."""

import math

import numba as nb
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas.kernels import ATTRACTOR_FILL, NONFINITE, UNRESOLVED
from atlas.kernels.driven import (
    DECIDED,
    advance,
    forcing_table,
    label_driven,
    sample,
    step_size,
    trajectory,
)

# b = 0.2 (α = b/2), ω0 = 1, Ω = 1, A = 1.66: coexisting oscillating and running attractors
ALPHA, OMEGA0, AMP, FREQ, PHASE, N = 0.1, 1.0, 1.66, 1.0, 0.0, 400
TABLE = forcing_table(AMP, FREQ, PHASE, N)
DT = step_size(FREQ, N)


def _states(n, seed=0, speed=3.0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, n), rng.uniform(-speed, speed, n)


def test_forcing_table_against_direct_evaluation():
    table = forcing_table(AMP, FREQ, 0.7, N)
    t = np.array([j * (math.pi / FREQ / N) for j in range(2 * N + 1)])  # j·dt/2
    assert table.shape == (2 * N + 1,) and table.dtype == np.float64
    np.testing.assert_allclose(table, AMP * np.cos(FREQ * t + 0.7), rtol=0, atol=1e-14)
    assert table[0] == AMP * math.cos(0.7)
    assert step_size(2.0, 50) == pytest.approx(math.pi / 50, rel=1e-15)


@pytest.mark.parametrize("torque", [0.0, 0.5])
def test_one_period_converges_to_dop853_at_order_four(torque):
    """One period of P against DOP853 (rtol 1e-12): the error falls as N⁻⁴ (N = 100 takes
    the FULL path, N ≥ 200 the SHARED one at most states)."""
    theta0 = np.array([0.3, -2.0, 2.9, 0.0])
    theta_dot0 = np.array([0.0, 1.5, -2.5, 3.0])

    def field(t, y):
        return [y[1], torque + AMP * np.cos(FREQ * t + PHASE) - OMEGA0**2 * np.sin(y[0])
                - 2 * ALPHA * y[1]]

    exact = np.array([solve_ivp(field, (0.0, 2 * np.pi / FREQ), y0, method="DOP853",
                                rtol=1e-12, atol=1e-12).y[:, -1]
                      for y0 in zip(theta0, theta_dot0)])
    steps = np.array([100, 200, 400, 800])
    errors = []
    for n in steps:
        th, v = theta0.copy(), theta_dot0.copy()
        advance(th, v, ALPHA, OMEGA0, torque, forcing_table(AMP, FREQ, PHASE, n),
                step_size(FREQ, n), 1)
        errors.append(np.abs(np.c_[th, v] - exact).max())
    order = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(order - 4.0) <= 0.3
    assert errors[2] < 1e-8  # N = 400: RK4's error, far above DOP853's


def test_k_periods_are_k_calls_of_one_period_bit_for_bit():
    theta0, theta_dot0 = _states(300)
    th, v = theta0.copy(), theta_dot0.copy()
    advance(th, v, ALPHA, OMEGA0, 0.3, TABLE, DT, 7)
    th1, v1 = theta0.copy(), theta_dot0.copy()
    for _ in range(7):
        advance(th1, v1, ALPHA, OMEGA0, 0.3, TABLE, DT, 1)
    np.testing.assert_array_equal(th, th1)
    np.testing.assert_array_equal(v, v1)
    assert np.abs(th - theta0).max() > 1.0  # θ unwrapped: running orbits gain turns


def test_independent_of_threads_and_chunking():
    """3000 orbits (several chunks, parallel kernel) with 1 and 2 Numba threads, the same
    orbits reversed, and a few alone (one chunk: the serial twin): identical bits. Includes
    fast orbits (FULL path) among the SHARED ones."""
    theta0, theta_dot0 = _states(3000, seed=1, speed=30.0)
    saved = nb.get_num_threads()
    runs = []
    try:
        for threads in (1, min(2, nb.config.NUMBA_NUM_THREADS)):
            nb.set_num_threads(threads)
            th, v = theta0.copy(), theta_dot0.copy()
            advance(th, v, ALPHA, OMEGA0, 0.0, TABLE, DT, 3)
            runs.append((th, v))
    finally:
        nb.set_num_threads(saved)
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    th, v = theta0[::-1].copy(), theta_dot0[::-1].copy()
    advance(th, v, ALPHA, OMEGA0, 0.0, TABLE, DT, 3)
    np.testing.assert_array_equal(th[::-1], runs[0][0])
    np.testing.assert_array_equal(v[::-1], runs[0][1])
    few = slice(1234, 1271)
    th, v = theta0[few].copy(), theta_dot0[few].copy()
    advance(th, v, ALPHA, OMEGA0, 0.0, TABLE, DT, 3)
    np.testing.assert_array_equal(th, runs[0][0][few])
    np.testing.assert_array_equal(v, runs[0][1][few])


def test_sample_is_repeated_advance():
    theta0, theta_dot0 = _states(70, seed=3)
    out = sample(theta0, theta_dot0, ALPHA, OMEGA0, 0.2, TABLE, DT, 4, 5)
    assert out.shape == (70, 5, 2)
    th, v = theta0.copy(), theta_dot0.copy()
    advance(th, v, ALPHA, OMEGA0, 0.2, TABLE, DT, 4)
    for k in range(5):
        advance(th, v, ALPHA, OMEGA0, 0.2, TABLE, DT, 1)
        np.testing.assert_array_equal(out[:, k, 0], th)
        np.testing.assert_array_equal(out[:, k, 1], v)


@pytest.mark.parametrize("n, speed", [(N, 3.0), (32, 3.0), (16, 400.0)])
def test_trajectory_returns_are_the_lane_kernels_bit_for_bit(n, speed):
    """One orbit kept step by step (atlas orbit's) passes P at the lane kernels' bits, on
    the SHARED path and (fast orbits at a coarse step) the FULL one, with a torque; every
    s-th step kept is the same state."""
    table, dt = forcing_table(AMP, FREQ, PHASE, n), step_size(FREQ, n)
    theta0, theta_dot0 = _states(12, seed=5, speed=speed)
    returns = sample(theta0, theta_dot0, ALPHA, OMEGA0, 0.2, table, dt, 0, 6)
    for i in range(theta0.size):
        path = trajectory(theta0[i], theta_dot0[i], ALPHA, OMEGA0, 0.2, table, dt, 6)
        assert path.shape == (6 * n + 1, 2)
        np.testing.assert_array_equal(path[0], [theta0[i], theta_dot0[i]])
        np.testing.assert_array_equal(path[n::n], returns[i])
        np.testing.assert_array_equal(
            trajectory(theta0[i], theta_dot0[i], ALPHA, OMEGA0, 0.2, table, dt, 6, 4),
            path[::4])


def test_label_without_drive_finds_the_rest_states():
    """A = 0: the autonomous damped pendulum. From a small energy (below the saddles') every
    orbit settles to a rest state 2πk, which is the target (0, 0) once θ is wrapped."""
    rng = np.random.default_rng(4)
    theta0 = rng.uniform(-1.0, 1.0, 200) + 2 * np.pi * rng.integers(-2, 3, 200)
    theta_dot0 = rng.uniform(-0.5, 0.5, 200)
    attractor, periods, status = label_driven(
        theta0, theta_dot0, ALPHA, OMEGA0, 0.0, forcing_table(0.0, FREQ, PHASE, N), DT,
        np.array([[0.0, 0.0]]), np.array([0], np.int16), 0.05, 3, 100)
    assert (status == DECIDED).all() and (attractor == 0).all()
    assert (periods >= 3).all() and (periods < 100).all()


def _reference_trajectories(theta0, theta_dot0, periods):
    """States after each of ``periods`` periods: a straightforward numpy RK4 (np.sin, the
    drive evaluated at every stage time), all orbits at once."""
    h = 2 * np.pi / FREQ / N

    def accel(t, th, v):
        return AMP * np.cos(FREQ * t + PHASE) - OMEGA0**2 * np.sin(th) - 2 * ALPHA * v

    th, v = theta0.copy(), theta_dot0.copy()
    out = np.empty((periods, 2, th.size))
    for p in range(periods):
        for j in range(N):
            t = j * h
            a1 = accel(t, th, v)
            t2, v2 = th + h / 2 * v, v + h / 2 * a1
            a2 = accel(t + h / 2, t2, v2)
            t3, v3 = th + h / 2 * v2, v + h / 2 * a2
            a3 = accel(t + h / 2, t3, v3)
            t4, v4 = th + h * v3, v + h * a3
            a4 = accel(t + h, t4, v4)
            th = th + h / 6 * (v + 2 * v2 + 2 * v3 + v4)
            v = v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        out[p] = th, v
    return out


def _reference_label(trajectory, targets, target_attractor, radius, confirm):
    """The labelling rule, one orbit, in plain Python: (attractor, period, status);
    ``confirm`` one for all attractors or a sequence of one per attractor."""
    confirm = np.broadcast_to(confirm, (int(target_attractor.max()) + 1,))
    run_attractor, run = None, 0
    for p, (th, v) in enumerate(trajectory, start=1):
        d = np.angle(np.exp(1j * (th - targets[:, 0])))  # wrapped θ difference
        dist = np.hypot(d, v - targets[:, 1])
        hit = int(target_attractor[np.argmin(dist)]) if dist.min() <= radius else None
        run = 0 if hit is None else (run + 1 if hit == run_attractor else 1)
        run_attractor = hit
        if hit is not None and run >= confirm[hit]:
            return hit, p, DECIDED
    return ATTRACTOR_FILL, len(trajectory), UNRESOLVED


@pytest.mark.parametrize("confirm", [3, (1, 4)], ids=["one-for-all", "per-attractor"])
def test_label_agrees_with_numpy_reference(confirm):
    """Targets from two attractors found by long iteration (the period-1 oscillation; the
    period-2 running orbit, both of its points), orbits to the third attractor left
    unresolved. Chaotic transients amplify the last-bit difference of np.sin: the labels must
    agree wherever the reference trajectory stays within 1e-6 of the kernel's up to the
    decision (most orbits), and the rule applied to the kernel's own trajectory must give the
    kernel's labels for every orbit."""
    seeds = sample(np.array([-2.4, -0.6]), np.array([0.7, 1.7]), ALPHA, OMEGA0, 0.0, TABLE,
                   DT, 300, 2)
    wrapped = np.angle(np.exp(1j * seeds[..., 0]))
    targets = np.array([[wrapped[0, 0], seeds[0, 0, 1]],
                        [wrapped[1, 0], seeds[1, 0, 1]], [wrapped[1, 1], seeds[1, 1, 1]]])
    assert np.hypot(*(targets[0] - [wrapped[0, 1], seeds[0, 1, 1]])) < 1e-9  # period 1
    target_attractor = np.array([0, 1, 1], np.int16)
    radius, max_periods = 0.2, 80

    theta0, theta_dot0 = _states(50, seed=5)
    attractor, periods, status = label_driven(theta0, theta_dot0, ALPHA, OMEGA0, 0.0, TABLE,
                                              DT, targets, target_attractor, radius, confirm,
                                              max_periods)
    own = sample(theta0, theta_dot0, ALPHA, OMEGA0, 0.0, TABLE, DT, 0, max_periods)
    ref = _reference_trajectories(theta0, theta_dot0, max_periods)
    agree = 0
    for i in range(50):
        expected = _reference_label(own[i], targets, target_attractor, radius, confirm)
        assert (attractor[i], periods[i], status[i]) == expected
        ref_label = _reference_label(ref[:, :, i], targets, target_attractor, radius, confirm)
        last = ref_label[1]
        if np.abs(ref[:last, :, i] - own[i, :last]).max() < 1e-6:
            assert ref_label == expected
            agree += 1
    assert agree >= 40
    assert {0, 1} <= set(attractor[status == DECIDED].tolist())
    assert (status == UNRESOLVED).any()  # the third attractor has no target


def test_nonfinite_and_unresolved_statuses():
    theta0 = np.array([np.nan, 0.1, 0.2, np.inf])
    theta_dot0 = np.array([0.0, 0.0, np.nan, 0.0])
    attractor, periods, status = label_driven(
        theta0, theta_dot0, ALPHA, OMEGA0, 0.0, TABLE, DT, np.array([[3.0, 3.0]]),
        np.array([7], np.int16), 0.01, 2, 5)
    assert status.tolist() == [NONFINITE, UNRESOLVED, NONFINITE, NONFINITE]
    assert periods.tolist() == [0, 5, 0, 0]
    assert (attractor == ATTRACTOR_FILL).all() and attractor.dtype == np.int16
    # a state that turns non-finite on the way: a huge speed overflows within a period
    attractor, periods, status = label_driven(
        np.array([0.0]), np.array([1e307]), ALPHA, OMEGA0, 0.0, TABLE, DT,
        np.array([[0.0, 0.0]]), np.array([0], np.int16), 0.1, 2, 5)
    assert status[0] == NONFINITE and periods[0] == 1 and attractor[0] == ATTRACTOR_FILL


@pytest.mark.parametrize("amplitude, torque, steps", [(1.66, 0.0, 200), (1.2, 0.3, 200)])
def test_shared_orbits_keep_every_stage_offset_within_the_shared_reductions_range(
        amplitude, torque, steps):
    """The path bound (:func:`orbit_path`: the smaller of the speed band and the energy
    bound) is a promise about the whole orbit: every orbit it sends down the SHARED path,
    followed by a NumPy RK4 of the same map for 40 periods, keeps each stage offset
    (½dt·k1θ, ½dt·k2θ, dt·k3θ) within MAX_STAGE_OFFSET; orbits too fast for it take FULL.
    At the Wada case (A = 1.66, N = 200) every orbit of the window takes SHARED (the band
    alone sent them all down FULL)."""
    from atlas.kernels.driven import drive, orbit_path
    from atlas.kernels.lanes import FULL, MAX_STAGE_OFFSET, SHARED

    rng = np.random.default_rng(11)
    theta = np.concatenate([rng.uniform(-math.pi, math.pi, 2000), [0.0, 0.0]])
    theta_dot = np.concatenate([rng.uniform(-4.0, 4.0, 2000), [12.0, -12.0]])
    table, dt = forcing_table(amplitude, FREQ, PHASE, steps), step_size(FREQ, steps)
    forcing, accel = drive(OMEGA0, torque, table, dt)
    path = np.array([orbit_path.py_func(a, b, ALPHA, OMEGA0, dt, accel)
                     for a, b in zip(theta, theta_dot)])
    if amplitude == 1.66:
        assert np.all(path[:2000] == SHARED)
    assert np.all(path[2000:] == FULL)  # 12 rad/s: too fast for one shared reduction
    th, v = theta[path == SHARED].copy(), theta_dot[path == SHARED].copy()
    assert th.size > 1000
    w2, a2, largest = OMEGA0 ** 2, 2 * ALPHA, 0.0
    for _ in range(40):
        for j in range(0, forcing.size - 1, 2):
            f0, f1, f2 = forcing[j], forcing[j + 1], forcing[j + 2]
            k1t, k1v = v, f0 - w2 * np.sin(th) - a2 * v
            k2t = v + 0.5 * dt * k1v
            k2v = f1 - w2 * np.sin(th + 0.5 * dt * k1t) - a2 * k2t
            k3t = v + 0.5 * dt * k2v
            k3v = f1 - w2 * np.sin(th + 0.5 * dt * k2t) - a2 * k3t
            k4t = v + dt * k3v
            k4v = f2 - w2 * np.sin(th + dt * k3t) - a2 * k4t
            largest = max(largest, np.abs(0.5 * dt * k1t).max(), np.abs(0.5 * dt * k2t).max(),
                          np.abs(dt * k3t).max())
            th = th + dt / 6 * (k1t + 2 * (k2t + k3t) + k4t)
            v = v + dt / 6 * (k1v + 2 * (k2v + k3v) + k4v)
    assert largest <= MAX_STAGE_OFFSET
