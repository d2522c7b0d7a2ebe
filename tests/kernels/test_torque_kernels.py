"""The labelling kernels with a constant torque τ (θ̈ = −ω0² sin θ − 2αθ̇ + τ): τ = 0
bit-identical to the untilted kernels, the tilted energy trap and the running certificate in
every kernel (CPU lanes of both methods, the straightforward kernels, CUDA in the simulator),
against scipy's DOP853 classified by the same certificates."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import atlas
from atlas import defaults
from atlas.kernels import NONFINITE, RUNNING, TRAPPED, UNRESOLVED
from atlas.kernels.lanes import FULL, SCALAR, label_lanes, label_trigfree
from atlas.kernels.rk4 import label_straightforward, record_torque
from atlas.kernels.trigfree import label_trigfree_straightforward, record_trigfree_torque
from atlas.labels.trap import energy_cap, n_checks_for, trap_margin
from atlas.physics.barrier import RunningBarrier
from atlas.physics.pendulum import Pendulum
from atlas.status import ATTRACTOR_FILL
from tests.helpers import boundary_adjacent, needs_fma

TWO_PI = 2 * math.pi
#: Bistable cases: (α, ω0, τ, start of the hand-made barrier, its slope margin ε).
#: α = 0.05, τ = 0.5 is the bSTAB pendulum; α = 0.1, τ = 0.3 lies just above the homoclinic
#: threshold 8αω0/π ≈ 0.25, where the limit cycle passes close to the saddles.
CASES = {"bstab": (0.05, 1.0, 0.5, 2.0, 0.05), "near-threshold": (0.1, 1.0, 0.3, 2.0, 0.01)}
METHOD_KERNELS = [("rk4", None), ("rk4", "straightforward"), ("rk4-trigfree", None),
                  ("rk4-trigfree", "straightforward")]


# --------------------------------------------------------------------------- helpers
def make_barrier(alpha, omega0, torque, start, eps, m=4096) -> RunningBarrier:
    """A crude running certificate for the tests (atlas.physics.running builds the real ones): the
    curve θ̇ = g(θ) with dg/dθ = (|τ| − ω0² sin θ − 2αg)/g − ε from g(0) = ``start`` over one
    period. The flow's slope on it exceeds the curve's by ε, so with θ̇ > 0 the flow crosses
    it upwards; it is a barrier when g stays positive and ends at or above its start. Top:
    (|τ| + ω0²)/2α, above which θ̈ < 0. Given in the τ > 0 frame, direction sign(τ)."""
    tau, w2 = abs(torque), omega0**2
    sol = solve_ivp(lambda th, y: [(tau - w2 * math.sin(th) - 2 * alpha * y[0]) / y[0] - eps],
                    (0.0, TWO_PI), [start], method="DOP853", rtol=1e-11, atol=1e-12,
                    dense_output=True)
    g = sol.sol(np.linspace(0.0, TWO_PI, m + 1))[0]
    assert sol.status == 0 and g.min() > 0.3 and g[-1] >= g[0], "not a barrier"
    return RunningBarrier(0.0, g, (tau + w2) / (2 * alpha), 1 if torque > 0 else -1)


def barrier_value(b: RunningBarrier, theta, theta_dot) -> float:
    """> 0 inside the running region (in the frame of the barrier's direction), < 0 outside."""
    u, w = b.direction * theta, b.direction * theta_dot
    m = b.g.size - 1
    t = ((u - b.theta0) % TWO_PI) * m / TWO_PI
    i = min(max(math.floor(t), 0), m - 1)
    return min(b.top - w, w - (b.g[i] + (t - i) * (b.g[i + 1] - b.g[i])))


def dop853_label(p: Pendulum, theta0, theta_dot0, cap, barrier=None, t_end=200.0):
    """(status, k) of eq. (1) with torque by DOP853 (rtol = atol = 1e-12), stopped by the
    kernels' certificates evaluated along the dense output (events): the tilted energy trap
    E_k < cap, k = round((θ + θ*)/2π), and the running barrier. E_k jumps only where the
    strip changes, where it is above every saddle energy on both sides, so the event sees
    no false crossing."""
    w2, a2, tau, s = p.omega0**2, 2 * p.alpha, p.torque, p.rest_angle

    def well(theta):
        return math.floor((theta + s) / TWO_PI + 0.5)

    def trap(_, y):
        return float(p.energy(y[0], y[1], well(y[0]))) - cap

    def running(_, y):
        return barrier_value(barrier, y[0], y[1])

    trap.terminal = running.terminal = True
    events = [trap] + ([running] if barrier is not None else [])
    if trap(0, (theta0, theta_dot0)) < 0:
        return TRAPPED, well(theta0)
    if barrier is not None and running(0, (theta0, theta_dot0)) >= 0:
        return RUNNING, 0
    sol = solve_ivp(lambda _, y: [y[1], tau - w2 * math.sin(y[0]) - a2 * y[1]], (0.0, t_end),
                    [theta0, theta_dot0], method="DOP853", rtol=1e-12, atol=1e-12,
                    events=events)
    if sol.status != 1:
        return UNRESOLVED, 0
    if sol.t_events[0].size:
        return TRAPPED, well(sol.y_events[0][0][0])
    return RUNNING, 0


def _kernel_run(kernel, theta0, theta_dot0, alpha, omega0, torque, barrier=None, dt=0.01,
                t_max=200.0, check_every=16):
    n = theta0.size
    out = (np.full(n, 777, np.int32), np.full(n, 99, np.int8), np.full(n, -99, np.int32))
    extra = {} if barrier is None else dict(zip(("running_theta0", "running_g", "running_top"),
                                                barrier.kernel_args()))
    counts = kernel(theta0, theta_dot0, alpha, omega0, dt,
                    n_checks_for(t_max, dt, check_every), check_every,
                    energy_cap(dt, alpha, omega0, torque), *out, torque=torque, **extra)
    return out, counts


@pytest.fixture(scope="module")
def barriers():
    return {name: make_barrier(a, w, t, start, eps)
            for name, (a, w, t, start, eps) in CASES.items()}


# -------------------------------------------------------------- τ = 0: bit-identical
# Generated at commit ee9801e (before torque existed) with atlas.label on the inputs below:
# per (method, kernel, check_every) the sha256 of attractor, status and t_trap (their bytes,
# in that order), then the θ̇0 [hex] where the label flips along θ0 = 0.5 and θ0 = −2.0,
# located to one ulp by 64-point multisection of [0, 4] (a trajectory passing a saddle:
# sensitive to the last bit of every step). They pin the τ = 0 kernels as they were; the
# values are those of this machine's x86-64 with FMA (other FMA hosts agree; a host without
# FMA contraction would round differently).
TAU_ZERO_PINS = {
    ("rk4", None, 16): ("dae8811a0158180da9882cf4fdc98c14fa49140fa930479ba292c60f323f001d",
                        "0x1.219031eb577edp+1", "0x1.1ba6698775784p+1"),
    ("rk4", None, 1): ("c7e374dfa79aa1f3b9041f246a76fe7d7642c9be3d7f008b59cb27e717cc2acb",
                       "0x1.219031eb577edp+1", "0x1.1ba6698775784p+1"),
    ("rk4", "straightforward", 16): (
        "dae8811a0158180da9882cf4fdc98c14fa49140fa930479ba292c60f323f001d",
        "0x1.219031eb577edp+1", "0x1.1ba6698775784p+1"),
    ("rk4", "straightforward", 1): (
        "c7e374dfa79aa1f3b9041f246a76fe7d7642c9be3d7f008b59cb27e717cc2acb",
        "0x1.219031eb577edp+1", "0x1.1ba6698775784p+1"),
    ("rk4-trigfree", None, 16): (
        "dae8811a0158180da9882cf4fdc98c14fa49140fa930479ba292c60f323f001d",
        "0x1.219031e9cfc3cp+1", "0x1.1ba66988a2520p+1"),
    ("rk4-trigfree", None, 1): (
        "c7e374dfa79aa1f3b9041f246a76fe7d7642c9be3d7f008b59cb27e717cc2acb",
        "0x1.219031e9eee65p+1", "0x1.1ba66989a6135p+1"),
    ("rk4-trigfree", "straightforward", 16): (
        "dae8811a0158180da9882cf4fdc98c14fa49140fa930479ba292c60f323f001d",
        "0x1.219031e9cfc3cp+1", "0x1.1ba66988a2520p+1"),
    ("rk4-trigfree", "straightforward", 1): (
        "c7e374dfa79aa1f3b9041f246a76fe7d7642c9be3d7f008b59cb27e717cc2acb",
        "0x1.219031e9eee65p+1", "0x1.1ba66989a6135p+1"),
}


def _pin_inputs():
    th, v = np.meshgrid(np.linspace(*defaults.THETA0_WINDOW, 64),
                        np.linspace(*defaults.THETA_DOT0_WINDOW, 48))
    fth, fv = np.meshgrid(np.linspace(-3, 3, 8), np.linspace(-45, 45, 10))  # FULL lanes
    th = np.concatenate([th.ravel(), fth.ravel(), [np.nan, 0.0, np.pi]])
    v = np.concatenate([v.ravel(), fv.ravel(), [0.0, np.inf, 0.0]])
    return th, v


def _digest(res) -> str:
    h = hashlib.sha256()
    for a in (res.attractor, res.status, res.t_trap):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _flip(theta0, lo, hi, **kw) -> float:
    def labels(x):
        return atlas.label(np.full(x.shape, theta0), x, alpha=0.1, omega0=1.0, torque=0.0,
                           **kw).attractor

    a, b = labels(np.array([lo, hi]))
    assert a != b
    while True:
        xs = np.linspace(lo, hi, 65)
        xs = xs[(xs > lo) & (xs < hi)]
        if xs.size == 0:
            return lo
        ks = labels(xs)
        j = np.flatnonzero(ks != a)[0] if np.any(ks != a) else xs.size
        lo, hi = (xs[j - 1] if j > 0 else lo), (xs[j] if j < xs.size else hi)


@needs_fma
@pytest.mark.parametrize("method,kernel,check_every", list(TAU_ZERO_PINS))
def test_tau_zero_is_bit_identical_to_the_untilted_kernels(method, kernel, check_every):
    th, v = _pin_inputs()
    kw = dict(method=method, kernel=kernel, check_every=check_every)
    res = atlas.label(th, v, alpha=0.1, omega0=1.0, torque=0.0, dt=0.01, t_max=60.0, **kw)
    digest, *flips = TAU_ZERO_PINS[(method, kernel, check_every)]
    assert _digest(res) == digest
    assert [_flip(t0, 0.0, 4.0, **kw).hex() for t0 in (0.5, -2.0)] == flips
    assert not np.any(res.direction) and res.direction.dtype == np.int8


# ------------------------------------------------- the tilted trap and the running label
@pytest.mark.parametrize("case", list(CASES))
def test_labels_agree_with_dop853_classified_by_the_same_certificates(case, barriers):
    """Random points: RK4 labels (the lanes and the straightforward kernel, with the running
    barrier; the trig-free method is refused one) against DOP853 stopped by the same trap and
    barrier. Where both are decisive they agree on ≥ 99 %, and
    every disagreement is on a basin boundary: ±1e-6 in θ̇0 changes DOP853's own label."""
    alpha, omega0, tau, *_ = CASES[case]
    b = barriers[case]
    p = Pendulum(alpha, omega0, tau)
    cap = energy_cap(0.01, alpha, omega0, tau)
    rng = np.random.default_rng(11)
    theta0, theta_dot0 = rng.uniform(-TWO_PI, TWO_PI, 300), rng.uniform(-5.0, 5.0, 300)
    exact = [dop853_label(p, a, v, cap, b) for a, v in zip(theta0, theta_dot0)]
    ex_status = np.array([e[0] for e in exact])
    ex_k = np.array([e[1] for e in exact])
    assert np.sum(ex_status == TRAPPED) >= 50 and np.sum(ex_status == RUNNING) >= 50
    # the running certificate is established for classical RK4 only
    with pytest.raises(ValueError, match="running certificate is established for classical"):
        atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=tau,
                    method="rk4-trigfree", running=b)
    for method in (None, "straightforward"):  # (named so for the messages below)
        res = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=tau,
                          kernel=method, running=b)
        decisive = (res.status != UNRESOLVED) & (ex_status != UNRESOLVED)
        assert decisive.mean() >= 0.95
        agree = (res.status == ex_status) & ((res.status != TRAPPED) | (res.attractor == ex_k))
        assert agree[decisive].mean() >= 0.99, method
        for i in np.flatnonzero(decisive & ~agree):
            nearby = {dop853_label(p, theta0[i], theta_dot0[i] + d, cap, b) for d in (-1e-6, 1e-6)}
            assert nearby != {exact[i]}, (method, theta0[i], theta_dot0[i])
        running = res.status == RUNNING
        np.testing.assert_array_equal(res.direction, np.where(running, 1, 0))
        assert np.all(res.attractor[~(res.status == TRAPPED)] == ATTRACTOR_FILL)
        assert np.all(np.isfinite(res.t_trap[decisive]))


@pytest.mark.parametrize("method,recorder", [("rk4", record_torque),
                                             ("rk4-trigfree", record_trigfree_torque)])
@pytest.mark.parametrize("case", list(CASES))
def test_trapped_orbits_never_leave_their_tilted_well(case, method, recorder):
    """The straightforward kernel's trapped orbits, re-integrated by the same step
    (bit-identical trajectories) for 50 s past their trapping: θ stays between the well's two
    saddles, E_k stays below the trap level and never rises by more than 5 % of the margin."""
    alpha, omega0, tau, *_ = CASES[case]
    p = Pendulum(alpha, omega0, tau)
    kernel = label_straightforward if method == "rk4" else label_trigfree_straightforward
    th, v = np.meshgrid(np.linspace(-TWO_PI, TWO_PI, 24), np.linspace(-4.0, 4.0, 16))
    th, v = th.ravel().copy(), v.ravel().copy()
    (k, status, n_trap), _ = _kernel_run(kernel, th, v, alpha, omega0, tau)
    trapped = np.flatnonzero(status == TRAPPED)
    assert trapped.size > 40
    every, extra = 16, 5000  # samples at the kernel's checks; 50 s more
    n_samples = (n_trap[trapped].max() + extra) // every + 1
    out = np.empty((2, n_samples, trapped.size))
    recorder(th[trapped], v[trapped], alpha, omega0, tau, 0.01, every, out)
    cap = energy_cap(0.01, alpha, omega0, tau)
    s = p.rest_angle
    worst_rise = 0.0
    for j, i in enumerate(trapped):
        first = n_trap[i] // every
        span = slice(first, first + extra // every)
        thetas, speeds = out[0, span, j], out[1, span, j]
        phi = thetas - TWO_PI * k[i]
        assert np.all((phi > -math.pi - s) & (phi < math.pi - s)), i
        energy = p.energy(thetas, speeds, k[i])
        assert energy[0] < cap + 1e-12 and np.all(energy < p.saddle_energy)
        worst_rise = max(worst_rise, np.max(energy - np.minimum.accumulate(energy)))
        assert energy[-1] <= energy[0]
    assert worst_rise < 0.05 * trap_margin(0.01, alpha, omega0) * p.saddle_energy


@pytest.mark.parametrize("method", ["rk4", "rk4-trigfree"])
@pytest.mark.parametrize("alpha,tau", [(0.1, 0.3), (0.05, 0.5), (0.1, 0.9), (0.5, -0.6)])
def test_energy_rise_stays_far_below_the_tilted_trap_margin(alpha, tau, method):
    """As tests/labels/test_labels.py for τ = 0: orbits started just below the lower saddle's energy
    at every phase of the well gain at most 5 % of m·ΔE (ΔE the trap level) over 3000 steps,
    also close to the saddle-node (τ = 0.9: ΔE ≈ 0.06)."""
    p = Pendulum(alpha, 1.0, tau)
    rng = np.random.default_rng(1)
    s, top = p.rest_angle, p.saddle_energy
    strip = np.linspace(-math.pi - s, math.pi - s, 20001)
    low = strip[p.energy(strip, 0.0) < 0.95 * top]  # where E_k can be 0.95…1 ΔE: the well
    phi = rng.uniform(low.min(), low.max(), 400)
    target = top * rng.uniform(0.95, 1.0, 400)
    theta_dot = np.sqrt(np.maximum(2 * (target - p.energy(phi, 0.0)), 0.0))
    keep = p.energy(phi, 0.0) < target
    phi, theta_dot = phi[keep], theta_dot[keep]
    out = np.empty((2, 3001, phi.size))
    recorder = record_torque if method == "rk4" else record_trigfree_torque
    recorder(phi, theta_dot, alpha, 1.0, tau, 0.01, 1, out)
    energy = p.energy(out[0], out[1])
    inside = np.all((out[0] > -math.pi - s) & (out[0] < math.pi - s), axis=0)
    assert inside.sum() > 300
    rise = np.max((energy - np.minimum.accumulate(energy, axis=0))[:, inside])
    assert rise < 0.05 * trap_margin(0.01, alpha, 1.0) * top, rise


@pytest.mark.parametrize("torque", [1.0, 1.2, -1.5])
def test_no_orbit_is_trapped_without_rest_states(torque):
    """|τ| ≥ ω0² (1.0: the saddle-node, counted as none): no well, so nothing is trapped,
    even an orbit started at rest where the rest state would be; with a barrier every orbit
    of the window is certified running, in the direction of τ."""
    assert energy_cap(0.01, 0.1, 1.0, torque) == -math.inf
    th, v = np.meshgrid(np.linspace(-TWO_PI, TWO_PI, 16), np.linspace(-4.0, 4.0, 12))
    th = np.append(th.ravel(), math.copysign(math.pi / 2, torque))
    v = np.append(v.ravel(), 0.0)
    for method, kernel in METHOD_KERNELS:
        res = atlas.label(th, v, alpha=0.1, omega0=1.0, torque=torque, t_max=20.0,
                          method=method, kernel=kernel)
        assert np.all(res.status == UNRESOLVED)
    if abs(torque) > 1.0:
        b = make_barrier(0.1, 1.0, torque, 2.0, 0.05)
        res = atlas.label(th, v, alpha=0.1, omega0=1.0, torque=torque, running=b)
        assert np.all(res.status == RUNNING)
        assert np.all(res.direction == np.sign(torque))


def test_running_certificate_fires_and_never_in_a_trap(barriers):
    """bSTAB case (α = 0.05, τ = 0.5) with the hand-made barrier: orbits at θ̇0 = 9 are
    running at once (direction +1), orbits below the limit cycle become running later, and
    orbits started inside a well's trap are trapped at once, never running; the mirror
    image (τ = −0.5, the barrier mirrored by the kernels) gives the mirrored labels."""
    alpha, omega0, tau, *_ = CASES["bstab"]
    b = barriers["bstab"]
    p = Pendulum(alpha, omega0, tau)
    n = 64
    theta_fast = np.linspace(-3 * math.pi, 3 * math.pi, n)
    # inside the trap: E_k just below the cap, at every phase and in several wells
    cap = energy_cap(0.01, alpha, omega0, tau)
    phi = np.linspace(-math.pi - p.rest_angle + 0.05, math.pi - p.rest_angle - 0.05, n)
    phi = phi[p.energy(phi, 0.0) < 0.999 * cap]
    speed_in = np.sqrt(2 * (0.999 * cap - p.energy(phi, 0.0)))
    wells = np.arange(phi.size) % 5 - 2
    later = ([-1.0, 2.0, 1.0], [0.5, -3.0, 1.2])  # below the barrier, running within 10 s
    theta0 = np.concatenate([theta_fast, later[0], phi + TWO_PI * wells])
    theta_dot0 = np.concatenate([np.full(n, 9.0), later[1], speed_in])
    n_trap_start = n + 3
    for method, kernel in METHOD_KERNELS[:2]:  # method "rk4": the certificate's method
        res = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=tau,
                          method=method, kernel=kernel, running=b)
        assert np.all(res.status[:n + 3] == RUNNING) and np.all(res.direction[:n + 3] == 1)
        assert np.all(res.t_trap[:n] == 0.0) and np.all(res.t_trap[n:n + 3] > 0.0)
        assert np.all(res.status[n_trap_start:] == TRAPPED)
        np.testing.assert_array_equal(res.attractor[n_trap_start:], wells)
        assert np.all(res.t_trap[n_trap_start:] == 0.0)
        assert np.all(res.direction[n_trap_start:] == 0)
        mirror = atlas.label(-theta0, -theta_dot0, alpha=alpha, omega0=omega0, torque=-tau,
                             method=method, kernel=kernel,
                             running=RunningBarrier(b.theta0, b.g, b.top, -1))
        np.testing.assert_array_equal(mirror.status, res.status)
        np.testing.assert_array_equal(mirror.direction, -res.direction)
        np.testing.assert_array_equal(mirror.attractor[n_trap_start:], -wells)
    # the trap states themselves are outside the running region (the barrier is not vacuous)
    assert all(barrier_value(b, t, v) < 0 for t, v in zip(theta0[n_trap_start:],
                                                           theta_dot0[n_trap_start:]))


@pytest.mark.parametrize("method", ["rk4", "rk4-trigfree"])
def test_lane_kernels_match_their_plain_form_with_torque(method, barriers):
    """Lanes against the straightforward kernel of the same method on a grid, with the
    barrier: statuses equal, labels equal off basin-boundary cells, n_trap within one check.
    Fast orbits (|θ̇0| ≥ 35) take the full-reduction lanes ("rk4") with torque too."""
    alpha, omega0, tau, *_ = CASES["bstab"]
    b = barriers["bstab"]
    lanes = label_lanes if method == "rk4" else label_trigfree
    plain = label_straightforward if method == "rk4" else label_trigfree_straightforward
    th, v = np.meshgrid(np.linspace(-3 * math.pi, 3 * math.pi, 64), np.linspace(-6, 6, 48))
    th, v = th.ravel().copy(), v.ravel().copy()
    (a, s, n), _ = _kernel_run(lanes, th, v, alpha, omega0, tau, b)
    (a_ref, s_ref, n_ref), _ = _kernel_run(plain, th, v, alpha, omega0, tau, b)
    np.testing.assert_array_equal(s, s_ref)
    assert {TRAPPED, RUNNING} <= set(np.unique(s))
    differ = a != a_ref
    assert not (differ.reshape(48, 64) & ~boundary_adjacent(a_ref.reshape(48, 64))).any()
    assert np.all(np.abs(n[~differ] - n_ref[~differ]) <= 16)
    fast_th, fast_v = np.linspace(-3, 3, 40), np.repeat([-40.0, -35.0, 35.0, 40.0], 10)
    (a, s, n), counts = _kernel_run(lanes, fast_th, fast_v, alpha, omega0, tau, b)
    ref = _kernel_run(plain, fast_th, fast_v, alpha, omega0, tau, b)[0]
    if method == "rk4":
        assert counts[FULL] == fast_th.size and counts[SCALAR] == 0
    for x, y in zip((a, s, n), ref):
        np.testing.assert_array_equal(x, y)
    assert np.all((s == RUNNING) | (s == TRAPPED))


def test_edge_cases_with_torque():
    """Non-finite states, an orbit at the tilted rest state (trapped at once), one at a tilted
    saddle (unresolved: an equilibrium), and the contract's untouched attractor."""
    p = Pendulum(0.1, 1.0, 0.3)
    far = p.rest_angle + TWO_PI * 15_000  # the rest state of well 15000: |θ| ≈ 9.4e4
    th = np.array([np.nan, 0.0, p.rest_angle + TWO_PI, p.saddle_angle, far])
    v = np.array([0.0, np.inf, 0.0, 0.0, 0.0])
    for kernel in (label_lanes, label_trigfree, label_straightforward,
                   label_trigfree_straightforward):
        (a, s, n), _ = _kernel_run(kernel, th, v, 0.1, 1.0, 0.3, t_max=5.0)
        assert list(s[:4]) == [NONFINITE, NONFINITE, TRAPPED, UNRESOLVED]
        assert a[2] == 1 and n[2] == 0 and a[3] == 777 and list(n[:2]) == [-1, -1]
        assert s[4] == TRAPPED and a[4] == p.well(far) == 15_000 and n[4] == 0


def test_label_validates_torque_and_barrier(barriers):
    b = barriers["bstab"]
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(ValueError, match="torque"):
            atlas.label(0.5, 0.0, alpha=0.1, omega0=1.0, torque=bad)
    with pytest.raises(ValueError, match="sign"):
        atlas.label(0.5, 0.0, alpha=0.05, omega0=1.0, torque=-0.5, running=b)
    with pytest.raises(ValueError, match="sign"):
        atlas.label(0.5, 0.0, alpha=0.05, omega0=1.0, running=b)
    with pytest.raises(TypeError):
        atlas.label(0.5, 0.0, alpha=0.05, omega0=1.0, torque=0.5, running=(0.0, b.g, 15.0))
    for kwargs, message in [({"g": [1.0]}, "2 samples"), ({"g": [2.0, 1.0]}, "end at or above"),
                            ({"g": [1.0, np.nan]}, "finite"), ({"top": 0.5}, "above every g"),
                            ({"direction": 0}, "direction"), ({"theta0": np.inf}, "theta0")]:
        args = {"theta0": 0.0, "g": [1.0, 1.0], "top": 5.0, "direction": 1, **kwargs}
        with pytest.raises(ValueError, match=message):
            RunningBarrier(**args)
    assert not RunningBarrier(0.0, [1.0, 2.0], 5.0, 1).g.flags.writeable
    # orbits that could run past the wells an atlas file can index within t_max
    with pytest.raises(ValueError, match="32767"):
        atlas.label(0.0, 0.0, alpha=1e-3, omega0=1.0, torque=0.5, dt=0.01, t_max=2000.0)


CUDA_COMPARE = r"""
import json, math, sys
import numpy as np
from atlas.kernels.cuda import cuda_status
ok, why = cuda_status()
if not ok:
    print(json.dumps({"skip": why})); sys.exit()
from atlas.kernels.cuda_host import label_cuda
from atlas.kernels.rk4 import label_straightforward
from atlas.labels.trap import energy_cap, n_checks_for
from tests.kernels.test_torque_kernels import CASES, make_barrier

alpha, omega0, tau, start, eps = CASES["bstab"]
b = make_barrier(alpha, omega0, -tau, start, eps, m=256)
th, v = np.meshgrid(np.linspace(-3 * np.pi, 3 * np.pi, 7), np.linspace(-6.0, 6.0, 7))
theta0 = np.concatenate([th.ravel(), [np.nan, 0.0, math.asin(-tau) + 2 * np.pi]])
theta_dot0 = np.concatenate([v.ravel(), [0.0, np.inf, 0.0]])
n = theta0.size
dt, t_max = 0.01, 8.0
args = (alpha, omega0, dt, n_checks_for(t_max, dt, 16), 16, energy_cap(dt, alpha, omega0, -tau))
running = dict(running_theta0=b.theta0, running_g=b.g, running_top=b.top)

def run(kernel, **kw):
    out = (np.full(n, 12345, np.int32), np.full(n, 9, np.int8), np.full(n, 7, np.int32))
    kernel(theta0, theta_dot0, *args, *out, torque=-tau, **kw)
    return out

failures, statuses = [], {}
for variant, chunk, barrier in [("fast", 17, True), ("straightforward", None, False)]:
    extra = running if barrier else {}
    ref = run(label_straightforward, **extra)
    got = run(label_cuda, variant=variant, chunk=chunk, **extra)
    statuses[variant] = np.bincount(ref[1], minlength=5).tolist()
    for name, a, c in zip(("attractor", "status", "n_trap"), got, ref):
        bad = np.flatnonzero(a != c)
        if bad.size:
            failures.append(f"{variant}: {name} differs at {bad[:5].tolist()}")
print(json.dumps({"device": why, "failures": failures, "statuses": statuses}))
"""


@pytest.mark.slow
def test_cuda_torque_kernel_matches_cpu_kernel():
    """The CUDA tilted kernel (both variants; "fast" with the mirrored running barrier of
    τ < 0) against the CPU straightforward kernel, in numba's CUDA simulator (or on a GPU
    when one is present, as tests/kernels/test_cuda.py runs its comparison): identical labels,
    statuses and n_trap on a small grid and hand-picked orbits."""
    from tests.kernels.test_cuda import _child

    out = _child(CUDA_COMPARE, simulator=True)
    if "skip" in out:
        pytest.skip(f"CUDA simulator unavailable: {out['skip']}")
    assert out["failures"] == []
    fast, plain = out["statuses"]["fast"], out["statuses"]["straightforward"]
    assert fast[RUNNING] > 5 and fast[TRAPPED] > 0 and fast[NONFINITE] == 2
    assert plain[RUNNING] == 0 and plain[UNRESOLVED] > 5


@pytest.mark.parametrize("kernel", [label_lanes, label_trigfree])
def test_tilted_lanes_are_independent_of_threads_and_order(kernel, barriers):
    import numba as nb

    alpha, omega0, tau, *_ = CASES["bstab"]
    b = barriers["bstab"]
    th, v = np.meshgrid(np.linspace(-3 * math.pi, 3 * math.pi, 80), np.linspace(-6, 6, 64))
    th, v = th.ravel().copy(), v.ravel().copy()
    full, _ = _kernel_run(kernel, th, v, alpha, omega0, tau, b)
    n_threads = nb.get_num_threads()
    try:
        nb.set_num_threads(1)
        one, _ = _kernel_run(kernel, th, v, alpha, omega0, tau, b)
    finally:
        nb.set_num_threads(n_threads)
    perm = np.random.default_rng(0).permutation(th.size)
    shuffled, _ = _kernel_run(kernel, th[perm], v[perm], alpha, omega0, tau, b)
    for x, y, z in zip(full, one, shuffled):
        np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(x[perm], z)
