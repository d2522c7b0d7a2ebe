"""Lane-blocked SIMD labelling kernels: the CPU backend of :func:`atlas.label`.

Two methods share one lane machinery (:func:`make_label_chunk`): :func:`label_lanes` (method
"rk4": classical RK4 on (θ, θ̇) with the polynomial sin of :mod:`atlas.kernels.fastsin`) and
:func:`label_trigfree` (method "rk4-trigfree", :mod:`atlas.kernels.trigfree`). ``LANES`` = 32
orbits advance in lockstep as a structure of arrays, which LLVM vectorises (AVX-512/AVX2);
orbits are sent by their initial state to the SHARED, FULL or SCALAR path. Both follow the
kernel contract of :mod:`atlas.kernels` exactly and return how many orbits took each path.

Accuracy: the polynomial sin differs from libm by ≤ 1e-15, so trajectories differ from the
straightforward kernel's by ~1e-11 after 1000 steps and labels only on basin-boundary cells.
Results are bit-identical for any thread count, chunking and input order; τ = 0 runs the
specialisations of earlier versions unchanged (pinned by tests/kernels/test_torque_kernels.py).
Design, paths, measurements: docs/design/kernels.md#lanes.
"""

from __future__ import annotations

import logging
import math
import types

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import NONFINITE, RUNNING, TRAPPED, UNRESOLVED, cached_njit, uses_torque
from atlas.kernels.fastsin import (
    EXACT_RANGE,
    POLY_RANGE,
    SIN_FASTMATH,
    fast_sin,
    reduce_pi,
    sin_near,
)
from atlas.kernels.rk4 import (
    label_orbit,
    label_orbit_torque,
    make_rk4_step,
    make_rk4_step_torque,
    make_well_energy,
    make_well_energy_torque,
    rk4_step,
    running_test,
    torque_model,
)
from atlas.kernels.trigfree import (
    SYNC_EVERY,
    label_orbit_trigfree,
    label_orbit_trigfree_torque,
    sync_libm,
    sync_poly,
    sync_poly_torque,
    trigfree_step,
    trigfree_step_torque,
)

log = logging.getLogger(__name__)

#: Orbits per lane block (a compile-time constant; see the module docstring).
LANES = 32
#: Contiguous orbits a chunk takes at a time (tiles are dealt to chunks in turn).
TILE = 256
#: Chunks per Numba thread (``numba.get_num_threads()`` at the call): enough for the static
#: split of chunks between threads to stay balanced although orbits exit early.
CHUNKS_PER_THREAD = 16
#: Largest stage offset |δ| the shared-reduction path admits (sin_near is accurate to
#: POLY_RANGE − π/2).
MAX_STAGE_OFFSET = 0.3
assert MAX_STAGE_OFFSET < POLY_RANGE - math.pi / 2

#: Paths an orbit can take, indices of the per-call counts the labelling kernels return.
SHARED, FULL, SCALAR = 0, 1, 2
PATHS = ("lanes", "full-reduction lanes", "scalar")


def n_chunks(n: int) -> int:
    """Chunks of a labelling call over ``n`` orbits: ``CHUNKS_PER_THREAD`` per Numba thread
    (``numba.get_num_threads()`` now), fewer on small batches so that each chunk has at least
    two tiles (the separatrix bisection labels a few hundred orbits at a time). A single chunk
    runs on the calling thread (:func:`serial_twin`). Results never depend on it. (Computed
    outside the jitted kernels: a kernel that asks Numba for its thread count cannot be
    cached.)"""
    return max(1, min(CHUNKS_PER_THREAD * nb.get_num_threads(), n // (2 * TILE)))


# --------------------------------------------------------------------- method "rk4"
_shared_step = make_rk4_step(sin_near, reduce_pi)
_full_step = make_rk4_step(fast_sin)
_well_energy = make_well_energy(fast_sin)


def _lane_step(rk4):
    """The rk4 step in the lane signature (θ, θ̇, c, s, …, model) → (θ, θ̇, c, s), c, s and
    model unused."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def step(th, v, c, s, alpha, omega0, dt, model):
        th, v = rk4(th, v, alpha, omega0, dt)
        return th, v, c, s

    return step


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _rk4_sync(th, v, omega0, model):
    k, energy = _well_energy(th, v, omega0)
    return 0.0, 0.0, k, energy


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _rk4_classify(theta, theta_dot, alpha, omega0, dt, model):
    return _rk4_path(theta, theta_dot, alpha, omega0, dt)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _rk4_scalar(theta, theta_dot, alpha, omega0, dt, n_checks, check_every, energy_cap, model):
    return label_orbit(theta, theta_dot, alpha, omega0, dt, n_checks, check_every, energy_cap)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _never_running(th, v, model):
    return False


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _rk4_path(theta, theta_dot, alpha, omega0, dt):
    """SHARED if the shared-reduction stage offsets stay below MAX_STAGE_OFFSET for the
    whole orbit, FULL (per-stage reduction, any speed) otherwise, SCALAR for non-finite
    input, α < 0 and |θ0| beyond half of fast_sin's EXACT_RANGE (its accuracy is stated up to
    there). With α ≥ 0 the energy never grows, so |θ̇| ≤ V = √(θ̇0² + 2ω0²(1 − cos θ0))
    ≤ √(θ̇0² + 4ω0²); a stage velocity exceeds |θ̇| by at most ½dt(ω0² + 2α|k|) per stage.
    The margin 0.43/MAX_STAGE_OFFSET ≈ 1.4 in speed absorbs RK4's small energy error."""
    if not (alpha >= 0.0 and abs(theta) <= 0.5 * EXACT_RANGE and math.isfinite(theta_dot)):
        return SCALAR
    speed = math.sqrt(theta_dot * theta_dot + 4.0 * omega0 * omega0)
    offset = dt * (speed * (1.0 + 2.0 * alpha * dt) + dt * omega0 * omega0)
    return SHARED if offset <= MAX_STAGE_OFFSET else FULL


# ------------------------------------------------------------ method "rk4-trigfree"
@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_path(theta, theta_dot, alpha, omega0, dt):
    """SHARED (the lane path: a trig-free step has no stage-offset limit) unless the input is
    non-finite, α < 0 or |θ0| is beyond half of fast_sin's EXACT_RANGE: SCALAR."""
    if alpha >= 0.0 and abs(theta) <= 0.5 * EXACT_RANGE and math.isfinite(theta_dot):
        return SHARED
    return SCALAR


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_step(th, v, c, s, alpha, omega0, dt, model):
    return trigfree_step(th, v, c, s, alpha, omega0, dt)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_sync(th, v, omega0, model):
    return sync_poly(th, v, omega0)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_classify(theta, theta_dot, alpha, omega0, dt, model):
    return _trigfree_path(theta, theta_dot, alpha, omega0, dt)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_scalar(theta, theta_dot, alpha, omega0, dt, n_checks, check_every, energy_cap,
                     model):
    return label_orbit_trigfree(theta, theta_dot, alpha, omega0, dt, n_checks, check_every,
                                energy_cap)


# ------------------------------------------------------------------------- torque τ ≠ 0
# The tilted kernels' callables read τ and the running barrier from ``model``
# (:func:`atlas.kernels.rk4.torque_model`: τ, θ*, 1 − cos θ*, sign, barrier θ0, g, top, span).
_shared_step_torque = make_rk4_step_torque(sin_near, reduce_pi)
_full_step_torque = make_rk4_step_torque(fast_sin)
_well_energy_torque = make_well_energy_torque(fast_sin)


def _lane_step_torque(rk4):
    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def step(th, v, c, s, alpha, omega0, dt, model):
        th, v = rk4(th, v, alpha, omega0, dt, model[0])
        return th, v, c, s

    return step


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _rk4_sync_torque(th, v, omega0, model):
    k, energy = _well_energy_torque(th, v, omega0, model[0], model[1], model[2])
    return 0.0, 0.0, k, energy


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _in_range_torque(theta, theta_dot, alpha, omega0, model):
    """Whether the lanes may take the orbit: finite input, α > 0 and |θ| within half of
    fast_sin's EXACT_RANGE for the whole run. With τ the speed stays in the band
    |θ̇| ≤ B = max(|θ̇0|, (ω0² + |τ|)/2α) (above it |θ̈| points back into the band), so
    |θ| ≤ |θ0| + B·span; returns (ok, B)."""
    band = (omega0 * omega0 + abs(model[0])) / (2.0 * alpha) if alpha > 0.0 else math.inf
    speed = max(abs(theta_dot), band)
    ok = (alpha > 0.0 and math.isfinite(theta_dot)
          and abs(theta) + speed * model[7] <= 0.5 * EXACT_RANGE)
    return ok, speed


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _rk4_classify_torque(theta, theta_dot, alpha, omega0, dt, model):
    """As :func:`_rk4_path` with the speed bound B of :func:`_in_range_torque`; a stage
    velocity exceeds it by at most ½dt(ω0² + |τ| + 2αB) per stage."""
    ok, speed = _in_range_torque(theta, theta_dot, alpha, omega0, model)
    if not ok:
        return SCALAR
    offset = dt * (speed * (1.0 + 2.0 * alpha * dt) + dt * (omega0 * omega0 + abs(model[0])))
    return SHARED if offset <= MAX_STAGE_OFFSET else FULL


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_classify_torque(theta, theta_dot, alpha, omega0, dt, model):
    ok, _ = _in_range_torque(theta, theta_dot, alpha, omega0, model)
    return SHARED if ok else SCALAR


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_step_torque(th, v, c, s, alpha, omega0, dt, model):
    return trigfree_step_torque(th, v, c, s, alpha, omega0, dt, model[0])


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _trigfree_sync_torque(th, v, omega0, model):
    return sync_poly_torque(th, v, omega0, model[0], model[1], model[2])


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _running(th, v, model):
    return running_test(th, v, model[3], model[4], model[5], model[6])


# ------------------------------------------------------------------ the lane machinery
def make_label_chunk(step, sync, path, classify, scalar_label, first_pass,
                     running=_never_running):
    """Return ``chunk(first, stride, <contract args>, model, counts)``: label, with one lane
    block of ``step`` and refill, the orbits of tiles first, first + stride, … that
    ``classify`` sends to ``path``. The ``first_pass`` also labels the SCALAR orbits by
    ``scalar_label`` and counts every orbit's path into ``counts``. Every callable takes
    ``model`` last (() for τ = 0, :func:`atlas.kernels.rk4.torque_model` otherwise);
    ``running(θ, θ̇, model)`` is the running certificate, tested after the trap (the default
    is never true, and compiles to nothing)."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def advance(th, v, c, s, alpha, omega0, dt, n_steps, model):
        # n_steps steps of every lane; the lane loop is the one LLVM vectorises
        for _ in range(n_steps):
            for lane in range(LANES):
                th[lane], v[lane], c[lane], s[lane] = step(th[lane], v[lane], c[lane],
                                                           s[lane], alpha, omega0, dt, model)

    @nb.njit(nogil=True, fastmath=SIN_FASTMATH)
    def chunk(first, stride, theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
              energy_cap, model, attractor, status, n_trap, counts):
        n = theta0.size
        th = np.zeros(LANES)
        v = np.zeros(LANES)
        c = np.ones(LANES)
        s = np.zeros(LANES)
        well = np.zeros(LANES)
        energy = np.zeros(LANES)
        orbit = np.full(LANES, -1, np.int64)  # orbit index held by each lane, −1 if idle
        check = np.zeros(LANES, np.int64)  # checks done by the lane's orbit
        nxt = first * TILE
        while True:
            for lane in range(LANES):
                c[lane], s[lane], well[lane], energy[lane] = sync(th[lane], v[lane], omega0,
                                                                  model)
            active = 0
            for lane in range(LANES):
                while True:
                    i = orbit[lane]
                    if i >= 0:
                        if not (math.isfinite(th[lane]) and math.isfinite(v[lane])):
                            status[i] = NONFINITE
                            n_trap[i] = -1
                        elif energy[lane] < energy_cap:
                            attractor[i] = np.int32(well[lane])
                            status[i] = TRAPPED
                            n_trap[i] = check[lane] * check_every
                        elif running(th[lane], v[lane], model):
                            status[i] = RUNNING
                            n_trap[i] = check[lane] * check_every
                        elif check[lane] == n_checks:
                            status[i] = UNRESOLVED
                            n_trap[i] = -1
                        else:
                            active += 1
                            break
                        orbit[lane] = -1
                    if nxt >= n:  # chunk exhausted: the lane idles at the fixed point (0, 0)
                        th[lane] = 0.0
                        v[lane] = 0.0
                        c[lane] = 1.0
                        s[lane] = 0.0
                        break
                    i = nxt
                    nxt += 1
                    if nxt % TILE == 0:  # end of a tile: jump to this chunk's next tile
                        nxt += (stride - 1) * TILE
                    kind = classify(theta0[i], theta_dot0[i], alpha, omega0, dt, model)
                    if first_pass:
                        counts[kind] += 1
                    if kind != path:
                        if first_pass and kind == SCALAR:
                            st, k, nt = scalar_label(theta0[i], theta_dot0[i], alpha, omega0,
                                                     dt, n_checks, check_every, energy_cap,
                                                     model)
                            status[i] = st
                            n_trap[i] = nt
                            if st == TRAPPED:
                                attractor[i] = np.int32(k)
                        continue
                    orbit[lane] = i
                    check[lane] = 0
                    th[lane] = theta0[i]
                    v[lane] = theta_dot0[i]
                    c[lane], s[lane], well[lane], energy[lane] = sync(th[lane], v[lane],
                                                                      omega0, model)
            if active == 0:
                return
            advance(th, v, c, s, alpha, omega0, dt, check_every, model)
            for lane in range(LANES):
                check[lane] += 1

    return chunk


_rk4_shared_chunk = make_label_chunk(_lane_step(_shared_step), _rk4_sync, SHARED,
                                     _rk4_classify, _rk4_scalar, True)
_rk4_full_chunk = make_label_chunk(_lane_step(_full_step), _rk4_sync, FULL, _rk4_classify,
                                   _rk4_scalar, False)
_trigfree_chunk = make_label_chunk(_trigfree_step, _trigfree_sync, SHARED, _trigfree_classify,
                                   _trigfree_scalar, True)
_rk4_shared_chunk_torque = make_label_chunk(_lane_step_torque(_shared_step_torque),
                                            _rk4_sync_torque, SHARED, _rk4_classify_torque,
                                            label_orbit_torque, True, _running)
_rk4_full_chunk_torque = make_label_chunk(_lane_step_torque(_full_step_torque),
                                          _rk4_sync_torque, FULL, _rk4_classify_torque,
                                          label_orbit_torque, False, _running)
_trigfree_chunk_torque = make_label_chunk(_trigfree_step_torque, _trigfree_sync_torque, SHARED,
                                          _trigfree_classify_torque,
                                          label_orbit_trigfree_torque, True, _running)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label_lanes(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
                 attractor, status, n_trap, n_chunks):
    counts = np.zeros((n_chunks, 3), np.int64)
    for b in nb.prange(n_chunks):
        # int64 chunk index: the parfor would otherwise type the call twice (int64 and uint64)
        # and compile the chunk twice
        _rk4_shared_chunk(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt,
                          n_checks, check_every, energy_cap, (), attractor, status, n_trap,
                          counts[b])
        if counts[b, FULL] > 0:
            _rk4_full_chunk(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt,
                            n_checks, check_every, energy_cap, (), attractor, status, n_trap,
                            counts[b])
    return counts


# The four parallel kernels are written out, not made by a factory: Numba's on-disk cache
# misses a closure over dispatchers in every new process (its key pickles them). Their serial
# twins (serial_twin, below) are compiled from the same code, which has no closure.
@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label_lanes_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                        energy_cap, model, attractor, status, n_trap, n_chunks):
    counts = np.zeros((n_chunks, 3), np.int64)
    for b in nb.prange(n_chunks):
        _rk4_shared_chunk_torque(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt,
                                 n_checks, check_every, energy_cap, model, attractor, status,
                                 n_trap, counts[b])
        if counts[b, FULL] > 0:
            _rk4_full_chunk_torque(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0,
                                   dt, n_checks, check_every, energy_cap, model, attractor,
                                   status, n_trap, counts[b])
    return counts


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label_trigfree(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
                    attractor, status, n_trap, n_chunks):
    counts = np.zeros((n_chunks, 3), np.int64)
    for b in nb.prange(n_chunks):
        _trigfree_chunk(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt,
                        n_checks, check_every, energy_cap, (), attractor, status, n_trap,
                        counts[b])
    return counts


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label_trigfree_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                           energy_cap, model, attractor, status, n_trap, n_chunks):
    counts = np.zeros((n_chunks, 3), np.int64)
    for b in nb.prange(n_chunks):
        _trigfree_chunk_torque(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt,
                               n_checks, check_every, energy_cap, model, attractor, status,
                               n_trap, counts[b])
    return counts


def serial_twin(kernel):
    """``kernel`` (one of the four parallel labelling kernels) compiled without ``parallel``:
    ``nb.prange`` then runs as ``range`` on the calling thread, the same chunk calls in the
    same order, so the labels are bit-identical (chunks share no state). A call of a single
    chunk (:func:`_run_chunks`) takes it and opens no parallel region: on a loaded 2-core
    machine entering one cost 10–16 ms per call, against 0.02–3.5 ms of labelling for the
    ~50 batches of 1–1,000 orbits the separatrix bisection labels per parameter point.

    The twin is a copy of the Python function under its own name ``<name>_serial``: Numba's
    on-disk cache names its files by the qualified name and keys an entry by the signature and
    the bytecode, not by the ``parallel`` option, so the same function compiled twice would
    load one variant's machine code for the other. The copy, like the original, has no
    closure, so its cache entry is found by every new process."""
    func = kernel.py_func
    twin = types.FunctionType(func.__code__, func.__globals__, func.__name__ + "_serial",
                              func.__defaults__, func.__closure__)
    twin.__qualname__ = func.__qualname__ + "_serial"
    twin.__doc__ = f"{func.__name__} on the calling thread (:func:`serial_twin`)."
    return cached_njit(nogil=True, fastmath=SIN_FASTMATH)(twin)


_label_lanes_serial = serial_twin(_label_lanes)
_label_lanes_torque_serial = serial_twin(_label_lanes_torque)
_label_trigfree_serial = serial_twin(_label_trigfree)
_label_trigfree_torque_serial = serial_twin(_label_trigfree_torque)


def _run_chunks(kernel, serial, theta0, *args):
    """Call the parallel labelling ``kernel`` on (``theta0``, ``*args``) in
    :func:`n_chunks` chunks, or its serial twin ``serial`` when that is one chunk; return the
    orbits each path took, summed over the chunks (int64 [SHARED, FULL, SCALAR])."""
    chunks = n_chunks(theta0.size)
    return (serial if chunks == 1 else kernel)(theta0, *args, chunks).sum(axis=0)


def _log_paths(kernel_name: str, counts) -> None:
    if log.isEnabledFor(logging.DEBUG):
        log.debug("%s: %s", kernel_name,
                  ", ".join(f"{int(n)} {name}" for name, n in zip(PATHS, counts)))


def label_lanes(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
                attractor, status, n_trap, torque=0.0, running_theta0=0.0, running_g=None,
                running_top=math.inf):
    """Label orbits with lane-blocked SIMD RK4 (method "rk4") and the energy trap (kernel
    contract in :mod:`atlas.kernels`; design, accuracy and differences from the
    straightforward kernel in the module docstring). Returns the orbits each path took
    (int64 [SHARED, FULL, SCALAR]), also logged at debug level. τ = 0 without a running
    barrier runs the τ = 0 specialisation (bit-identical to earlier versions)."""
    if not uses_torque(torque, running_g):
        counts = _run_chunks(_label_lanes, _label_lanes_serial, theta0, theta_dot0, alpha,
                             omega0, dt, n_checks, check_every, energy_cap, attractor, status,
                             n_trap)
    else:
        model = torque_model(omega0, torque, running_theta0, running_g, running_top,
                             n_checks * check_every * dt)
        counts = _run_chunks(_label_lanes_torque, _label_lanes_torque_serial, theta0,
                             theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
                             model, attractor, status, n_trap)
    _log_paths("label_lanes", counts)
    return counts


def label_trigfree(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
                   attractor, status, n_trap, torque=0.0, running_theta0=0.0, running_g=None,
                   running_top=math.inf):
    """Label orbits with lane-blocked trig-free RK4 (method "rk4-trigfree",
    :mod:`atlas.kernels.trigfree`) and the energy trap (kernel contract in
    :mod:`atlas.kernels`). Returns the orbits each path took (int64 [SHARED, FULL, SCALAR];
    FULL is always 0), also logged at debug level. τ = 0 without a running barrier runs the
    τ = 0 specialisation (bit-identical to earlier versions)."""
    if not uses_torque(torque, running_g):
        counts = _run_chunks(_label_trigfree, _label_trigfree_serial, theta0, theta_dot0,
                             alpha, omega0, dt, n_checks, check_every, energy_cap, attractor,
                             status, n_trap)
    else:
        model = torque_model(omega0, torque, running_theta0, running_g, running_top,
                             n_checks * check_every * dt)
        counts = _run_chunks(_label_trigfree_torque, _label_trigfree_torque_serial, theta0,
                             theta_dot0, alpha, omega0, dt, n_checks, check_every,
                             energy_cap, model, attractor, status, n_trap)
    _log_paths("label_trigfree", counts)
    return counts


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _advance_rk4(th, v, alpha, omega0, dt, n_steps):
    for _ in range(n_steps):
        for lane in range(LANES):
            th[lane], v[lane] = _shared_step(th[lane], v[lane], alpha, omega0, dt)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def propagate_lanes(theta, theta_dot, alpha, omega0, dt, n_steps):
    """Advance every orbit [θ rad, θ̇ rad s⁻¹] by ``n_steps`` RK4 steps of ``dt`` [s] in place,
    no early exit: the lane-blocked counterpart of ``propagate_straightforward`` (bulk
    throughput). Orbits outside the shared-reduction domain (:func:`_rk4_path` not SHARED)
    are advanced by the scalar ``math.sin`` step instead, their lane idling at (0, 0)."""
    n = theta.size
    for b in nb.prange((n + LANES - 1) // LANES):
        lo = b * LANES
        th = np.zeros(LANES)
        v = np.zeros(LANES)
        lanes = np.zeros(LANES, np.bool_)
        for lane in range(min(LANES, n - lo)):
            i = lo + lane
            if _rk4_path(theta[i], theta_dot[i], alpha, omega0, dt) == SHARED:
                th[lane] = theta[i]
                v[lane] = theta_dot[i]
                lanes[lane] = True
            else:
                for _ in range(n_steps):
                    theta[i], theta_dot[i] = rk4_step(theta[i], theta_dot[i], alpha, omega0, dt)
        _advance_rk4(th, v, alpha, omega0, dt, n_steps)
        for lane in range(LANES):
            if lanes[lane]:
                theta[lo + lane] = th[lane]
                theta_dot[lo + lane] = v[lane]


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def propagate_trigfree(theta, theta_dot, alpha, omega0, dt, n_steps):
    """Advance every orbit by ``n_steps`` trig-free RK4 steps in place (re-synchronised at the
    start and after every ``SYNC_EVERY`` steps), no early exit: bulk throughput of method
    "rk4-trigfree". Orbits outside its lane domain take the scalar form (libm
    re-synchronisation)."""
    n = theta.size
    for b in nb.prange((n + LANES - 1) // LANES):
        lo = b * LANES
        th = np.zeros(LANES)
        v = np.zeros(LANES)
        c = np.ones(LANES)
        s = np.zeros(LANES)
        lanes = np.zeros(LANES, np.bool_)
        for lane in range(min(LANES, n - lo)):
            i = lo + lane
            if _trigfree_path(theta[i], theta_dot[i], alpha, omega0, dt) == SHARED:
                th[lane] = theta[i]
                v[lane] = theta_dot[i]
                lanes[lane] = True
            else:
                t, w = theta[i], theta_dot[i]
                cc, ss, _, _ = sync_libm(t, w, omega0)
                for j in range(n_steps):
                    if j > 0 and j % SYNC_EVERY == 0:
                        cc, ss, _, _ = sync_libm(t, w, omega0)
                    t, w, cc, ss = trigfree_step(t, w, cc, ss, alpha, omega0, dt)
                theta[i], theta_dot[i] = t, w
        done = 0
        while done < n_steps:
            for lane in range(LANES):
                c[lane], s[lane], _, _ = sync_poly(th[lane], v[lane], omega0)
            m = min(SYNC_EVERY, n_steps - done)
            for _ in range(m):
                for lane in range(LANES):
                    th[lane], v[lane], c[lane], s[lane] = trigfree_step(
                        th[lane], v[lane], c[lane], s[lane], alpha, omega0, dt)
            done += m
        for lane in range(LANES):
            if lanes[lane]:
                theta[lo + lane] = th[lane]
                theta_dot[lo + lane] = v[lane]
