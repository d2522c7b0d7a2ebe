"""The driven pendulum's stroboscopic map, lane-blocked: its CPU kernels.

The equation θ̈ + 2αθ̇ + ω0² sin θ = τ + A cos(Ωt + φ) (θ [rad], θ̇ [rad s⁻¹], α [s⁻¹],
ω0 [rad s⁻¹], τ and A [rad s⁻²], Ω [rad s⁻¹], φ [rad]), every orbit starting at t = 0. The
stroboscopic map P advances a state by one drive period T = 2π/Ω: N = ``steps_per_period``
classical RK4 steps of dt = T/N (:func:`step_size`), so that every sample of P falls on a step
(Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.1; global error O(dt⁴), measured order 4 in
tests/kernels/test_driven.py against scipy's DOP853).

All orbits of a call advance in lockstep from t = 0, so the drive at each RK4 stage (t,
t + dt/2, t + dt) is the same for every lane: it is read from a table of τ + A cos(Ωt_j + φ)
at the 2N + 1 half-step times t_j = j·dt/2 of one period (:func:`forcing_table`), once per
step, not per lane. The table is used again in every period: the forcing is taken periodic
exactly (t = kT + j·dt/2 gives the same entry for every k, the equation's own symmetry), so no
rounding of a growing t enters, and P is the same map in every period.

The lane machinery is that of :mod:`atlas.kernels.lanes` (``LANES`` orbits in lockstep as a
structure of arrays, chunks of tiles in ``prange``, lanes refilled as orbits finish, a serial
twin for a single chunk), at the granularity of whole periods: an orbit is loaded, looked at
and released at a period boundary only, where every lane is at phase 0. Each orbit's path is
chosen by its initial state alone: SHARED (one Cody–Waite reduction shared by the four stage
angles, :func:`atlas.kernels.fastsin.sin_near`) when a speed bound keeps every stage offset
below ``MAX_STAGE_OFFSET``, FULL (:func:`atlas.kernels.fastsin.fast_sin` per stage) otherwise.
θ is never wrapped (the winding of an orbit is read from it); the polynomial sin's error bound
(1e-15) is stated for |θ| ≤ 2²⁰ rad. A NaN or inf state propagates in its own lane only.
Results are bit-identical for any thread count, chunking and array length.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import ATTRACTOR_FILL, NONFINITE, TRAPPED, UNRESOLVED, cached_njit
from atlas.kernels.fastsin import SIN_FASTMATH, fast_sin, reduce_pi, sin_near
from atlas.kernels.lanes import FULL, LANES, MAX_STAGE_OFFSET, SHARED, TILE, n_chunks, serial_twin

__all__ = ["step_size", "forcing_table", "advance", "sample", "trajectory", "label_driven",
           "DECIDED"]

#: ``status`` of an orbit that :func:`label_driven` labelled: it was within ``radius`` of one
#: attractor's targets at that attractor's ``confirm`` consecutive returns of P (the shared
#: code 0, "trapped").
DECIDED = TRAPPED

TWO_PI = 2.0 * math.pi
INV_TWO_PI = 1.0 / TWO_PI


def step_size(frequency: float, steps_per_period: int) -> float:
    """dt = T/N [s]: the RK4 step for the drive frequency Ω = ``frequency`` [rad s⁻¹],
    T = 2π/Ω, and N = ``steps_per_period`` steps per period. The one definition of dt."""
    if not (frequency > 0.0 and steps_per_period >= 1):
        raise ValueError("frequency must be > 0 and steps_per_period ≥ 1")
    return TWO_PI / frequency / int(steps_per_period)


def forcing_table(amplitude: float, frequency: float, phase: float,
                  steps_per_period: int) -> np.ndarray:
    """A cos(Ωt_j + φ) [rad s⁻²] at the half-step times t_j = j·dt/2 [s], j = 0 … 2N
    (dt = :func:`step_size`): float64, length 2N + 1, each entry evaluated directly (libm cos,
    no recurrence, so no error accumulates along the table)."""
    dt = step_size(frequency, steps_per_period)
    t = np.arange(2 * int(steps_per_period) + 1) * (0.5 * dt)
    return amplitude * np.cos(frequency * t + phase)


# ------------------------------------------------------------------------------ the step
@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _unreduced(theta):
    return theta


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _sin_sum(theta, delta):
    return fast_sin(theta + delta)


def make_driven_step(sin, reduce):
    """Return a jitted ``step(θ, θ̇, α, ω0, dt, f0, f1, f2) -> (θ, θ̇)``: one classical RK4
    step of θ' = θ̇, θ̇' = f(t) − ω0² sin θ − 2αθ̇ from t to t + dt, with f0, f1, f2 the forcing
    τ + A cos(Ωt + φ) at t, t + dt/2 and t + dt. The stage angles θ + δ are evaluated as
    ``sin(reduce(θ), δ)`` (as in :func:`atlas.kernels.rk4.make_rk4_step`)."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def step(theta, theta_dot, alpha, omega0, dt, f0, f1, f2):
        w2 = omega0 * omega0
        a2 = 2.0 * alpha
        h2 = 0.5 * dt
        p = reduce(theta)
        k1t = theta_dot
        k1v = f0 - w2 * sin(p, 0.0) - a2 * theta_dot
        k2t = theta_dot + h2 * k1v
        k2v = f1 - w2 * sin(p, h2 * k1t) - a2 * k2t
        k3t = theta_dot + h2 * k2v
        k3v = f1 - w2 * sin(p, h2 * k2t) - a2 * k3t
        k4t = theta_dot + dt * k3v
        k4v = f2 - w2 * sin(p, dt * k3t) - a2 * k4t
        h6 = dt / 6.0
        return (theta + h6 * (k1t + 2.0 * (k2t + k3t) + k4t),
                theta_dot + h6 * (k1v + 2.0 * (k2v + k3v) + k4v))

    return step


_shared_step = make_driven_step(sin_near, reduce_pi)
_full_step = make_driven_step(_sin_sum, _unreduced)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def orbit_path(theta, theta_dot, alpha, omega0, dt, accel):
    """SHARED or FULL for an orbit from (θ, θ̇), ``accel`` = ω0² + F bounding |θ̈ + 2αθ̇|,
    F = max|τ + A cos(Ωt + φ)|. With α > 0 the speed stays bounded by two bands, each
    forward invariant: |θ̇| ≤ max(|θ̇0|, accel/2α) (above it θ̈ points back into it), and
    |θ̇| ≤ √(2 max(E0, E*)) with the energy E = ½θ̇² + ω0²(1 − cos θ) ≤ ½θ̇² + 2ω0²: E
    changes at the rate θ̇ f(t) − 2αθ̇², negative where |θ̇| > F/2α, and there
    E > E* = ½(F/2α)² + 2ω0² cannot be entered (the smaller band by far at a strong drive:
    8.5 against 13.3 rad s⁻¹ at A = 1.66, α = 0.1, ω0 = 1). A stage offset is then at most
    dt·(B(1 + 2α dt) + dt·accel) for the smaller bound B, as in :mod:`atlas.kernels.lanes`
    (whose margin absorbs RK4's error). An orbit that starts SHARED stays so. Non-finite
    input takes FULL."""
    if not (alpha > 0.0 and math.isfinite(theta) and math.isfinite(theta_dot)):
        return FULL
    w2 = omega0 * omega0
    drift = max(accel - w2, 0.0) / (2.0 * alpha)  # F/2α
    energy = max(0.5 * theta_dot * theta_dot, 0.5 * drift * drift) + 2.0 * w2
    speed = min(max(abs(theta_dot), accel / (2.0 * alpha)), math.sqrt(2.0 * energy))
    offset = dt * (speed * (1.0 + 2.0 * alpha * dt) + dt * accel)
    return SHARED if offset <= MAX_STAGE_OFFSET else FULL


# ------------------------------------------------------------------ the lane machinery
def make_period_chunk(step, path, visit):
    """Return ``chunk(first, stride, theta0, theta_dot0, alpha, omega0, dt, forcing, accel,
    args)``: advance, in one lane block of ``step`` with refill, the orbits of tiles first,
    first + stride, … whose :func:`orbit_path` is ``path``, period by period (``forcing`` = τ + the
    table of :func:`forcing_table`). After loading an orbit and after each period p of it,
    ``visit(i, p, θ, θ̇, memo, lane, args) -> done`` looks at orbit i (``memo[lane]``: two
    int64 of the orbit's own, set to (ATTRACTOR_FILL, 0) at loading); the lane takes the next
    orbit once it is done."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def one_period(th, v, alpha, omega0, dt, forcing):
        # the drive is read once per step; the lane loop is the one LLVM vectorises
        for j in range(0, forcing.size - 1, 2):
            f0 = forcing[j]
            f1 = forcing[j + 1]
            f2 = forcing[j + 2]
            for lane in range(LANES):
                th[lane], v[lane] = step(th[lane], v[lane], alpha, omega0, dt, f0, f1, f2)

    @nb.njit(nogil=True, fastmath=SIN_FASTMATH)
    def chunk(first, stride, theta0, theta_dot0, alpha, omega0, dt, forcing, accel, args):
        n = theta0.size
        th = np.zeros(LANES)
        v = np.zeros(LANES)
        orbit = np.full(LANES, -1, np.int64)  # orbit index held by each lane, −1 if idle
        period = np.zeros(LANES, np.int64)  # periods done by the lane's orbit
        memo = np.zeros((LANES, 2), np.int64)
        nxt = first * TILE
        while True:
            active = 0
            for lane in range(LANES):
                while True:
                    i = orbit[lane]
                    if i >= 0:
                        if not visit(i, period[lane], th[lane], v[lane], memo, lane, args):
                            active += 1
                            break
                        orbit[lane] = -1
                    if nxt >= n:  # chunk exhausted: the lane idles from (0, 0)
                        th[lane] = 0.0
                        v[lane] = 0.0
                        break
                    i = nxt
                    nxt += 1
                    if nxt % TILE == 0:  # end of a tile: jump to this chunk's next tile
                        nxt += (stride - 1) * TILE
                    if orbit_path(theta0[i], theta_dot0[i], alpha, omega0, dt, accel) != path:
                        continue
                    orbit[lane] = i
                    period[lane] = 0
                    memo[lane, 0] = ATTRACTOR_FILL
                    memo[lane, 1] = 0
                    th[lane] = theta0[i]
                    v[lane] = theta_dot0[i]
            if active == 0:
                return
            one_period(th, v, alpha, omega0, dt, forcing)
            for lane in range(LANES):
                period[lane] += 1

    return chunk


# ------------------------------------------------------------------------- the visitors
@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def visit_advance(i, p, th, v, memo, lane, args):
    """args = (periods, θ out, θ̇ out): write the state after ``periods`` periods."""
    periods, theta, theta_dot = args
    if p < periods:
        return False
    theta[i] = th
    theta_dot[i] = v
    return True


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _visit_sample(i, p, th, v, memo, lane, args):
    """args = (transient, out): out[i, p − transient − 1] = (θ, θ̇) after period p."""
    transient, out = args
    k = p - transient - 1
    if k >= 0:
        out[i, k, 0] = th
        out[i, k, 1] = v
    return k + 1 >= out.shape[1]


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def nearest_attractor(th, v, targets, target_attractor, radius):
    """The attractor of the nearest target k within its own ``radius[k]`` of (θ wrapped,
    θ̇) (θ difference wrapped to [−π, π), Euclidean in (θ, θ̇); the first on a tie), else
    ATTRACTOR_FILL."""
    wrapped = th - TWO_PI * math.floor((th + math.pi) * INV_TWO_PI)
    best = math.inf
    hit = ATTRACTOR_FILL
    for k in range(targets.shape[0]):
        d = wrapped - targets[k, 0]
        d -= TWO_PI * math.floor((d + math.pi) * INV_TWO_PI)
        e = v - targets[k, 1]
        dist2 = d * d + e * e
        if dist2 <= radius[k] * radius[k] and dist2 < best:
            best = dist2
            hit = target_attractor[k]
    return hit


def make_visit_label(nearest):
    """Return the labelling visitor ``visit(i, p, θ, θ̇, memo, lane, args) -> done``:
    args = (targets, target_attractor, radius, confirm, max_periods, attractor, periods,
    status), ``confirm`` the returns in a row that decide each attractor (int64 per
    attractor); memo[lane] = (attractor of the current run of hits, its length); ``nearest`` is
    :func:`nearest_attractor` (a parameter so that :mod:`atlas.kernels.driven_cuda` compiles
    this one decision rule for the device around its own device function)."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def visit(i, p, th, v, memo, lane, args):
        targets, target_attractor, radius, confirm, max_periods, attractor, periods, status = args
        if not (math.isfinite(th) and math.isfinite(v)):
            status[i] = NONFINITE
            periods[i] = p
            return True
        if p > 0:
            hit = nearest(th, v, targets, target_attractor, radius)
            if hit == ATTRACTOR_FILL:
                memo[lane, 1] = 0
            elif hit == memo[lane, 0]:
                memo[lane, 1] += 1
            else:
                memo[lane, 1] = 1
            memo[lane, 0] = hit
            if hit != ATTRACTOR_FILL and memo[lane, 1] >= confirm[hit]:
                attractor[i] = hit
                status[i] = DECIDED
                periods[i] = p
                return True
        if p >= max_periods:
            status[i] = UNRESOLVED
            periods[i] = p
            return True
        return False

    return visit


_visit_label = make_visit_label(nearest_attractor)


_advance_shared = make_period_chunk(_shared_step, SHARED, visit_advance)
_advance_full = make_period_chunk(_full_step, FULL, visit_advance)
_sample_shared = make_period_chunk(_shared_step, SHARED, _visit_sample)
_sample_full = make_period_chunk(_full_step, FULL, _visit_sample)
_label_shared = make_period_chunk(_shared_step, SHARED, _visit_label)
_label_full = make_period_chunk(_full_step, FULL, _visit_label)


# The parallel kernels are written out, not made by a factory: Numba's on-disk cache misses a
# closure over dispatchers in every new process (atlas.kernels.lanes). Each chunk takes its
# SHARED orbits, then its FULL ones.
@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _advance(theta0, theta_dot0, alpha, omega0, dt, forcing, accel, args, n_chunks):
    for b in nb.prange(n_chunks):
        _advance_shared(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt, forcing,
                        accel, args)
        _advance_full(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt, forcing,
                      accel, args)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _sample(theta0, theta_dot0, alpha, omega0, dt, forcing, accel, args, n_chunks):
    for b in nb.prange(n_chunks):
        _sample_shared(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt, forcing,
                       accel, args)
        _sample_full(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt, forcing,
                     accel, args)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label(theta0, theta_dot0, alpha, omega0, dt, forcing, accel, args, n_chunks):
    for b in nb.prange(n_chunks):
        _label_shared(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt, forcing,
                      accel, args)
        _label_full(np.int64(b), n_chunks, theta0, theta_dot0, alpha, omega0, dt, forcing,
                    accel, args)


_advance_serial = serial_twin(_advance)
_sample_serial = serial_twin(_sample)
_label_serial = serial_twin(_label)


def _states(theta, theta_dot):
    theta = np.ascontiguousarray(theta, dtype=np.float64)
    theta_dot = np.ascontiguousarray(theta_dot, dtype=np.float64)
    if theta.ndim != 1 or theta.shape != theta_dot.shape:
        raise ValueError("theta and theta_dot must be 1-D arrays of one length")
    return theta, theta_dot


def drive(omega0, torque, table, dt):
    """(forcing, accel): the drive τ + table (checked) and its bound ω0² + max|τ + table|
    (for :func:`orbit_path`), as every kernel of a call (CPU or CUDA) takes them."""
    table = np.ascontiguousarray(table, dtype=np.float64)
    if table.ndim != 1 or table.size < 3 or table.size % 2 == 0:
        raise ValueError("table must be forcing_table's 2N + 1 values")
    if not dt > 0.0:
        raise ValueError("dt must be > 0")
    forcing = float(torque) + table
    return forcing, float(omega0) ** 2 + float(np.max(np.abs(forcing)))


def _run(kernel, serial, theta0, theta_dot0, alpha, omega0, torque, table, dt, args):
    """Call ``kernel`` (or its ``serial`` twin for a single chunk) with :func:`drive`."""
    forcing, accel = drive(omega0, torque, table, dt)
    chunks = n_chunks(theta0.size)
    (serial if chunks == 1 else kernel)(theta0, theta_dot0, float(alpha), float(omega0),
                                        float(dt), forcing, accel, args, chunks)


def check_in_place(theta, theta_dot, periods) -> None:
    """Check :func:`advance`'s arguments (also those of the CUDA twin)."""
    if theta.dtype != np.float64 or theta_dot.dtype != np.float64 or not (
            theta.flags.c_contiguous and theta_dot.flags.c_contiguous):
        raise ValueError("advance works in place on contiguous float64 arrays")
    _states(theta, theta_dot)
    if periods < 0:
        raise ValueError("periods must be ≥ 0")


def advance(theta, theta_dot, alpha, omega0, torque, table, dt, periods) -> None:
    """Apply the stroboscopic map P ``periods`` times to every state, in place: ``theta``
    [rad] (never wrapped) and ``theta_dot`` [rad s⁻¹], float64 1-D arrays, the states at
    t = 0; α [s⁻¹], ω0 [rad s⁻¹], τ = ``torque`` [rad s⁻²], ``table`` = :func:`forcing_table`
    and ``dt`` = :func:`step_size` of the same N. Classical RK4 (module docstring: method,
    accuracy, reference). k calls of one period give the same bits as one call of k, for every
    orbit that starts in the SHARED path's band (all, at the usual parameters)."""
    check_in_place(theta, theta_dot, periods)
    # the kernel reads each orbit's initial state for its path in two passes: read a copy
    _run(_advance, _advance_serial, theta.copy(), theta_dot.copy(), alpha, omega0, torque,
         table, dt, (np.int64(periods), theta, theta_dot))


def sample(theta0, theta_dot0, alpha, omega0, torque, table, dt, transient, count) -> np.ndarray:
    """The returns of P: for each initial state (θ0 [rad], θ̇0 [rad s⁻¹] at t = 0), skip
    ``transient`` periods, then record the state after each of the next ``count`` periods.
    Returns float64 (n, count, 2): [..., 0] = θ (unwrapped) [rad], [..., 1] = θ̇ [rad s⁻¹].
    Parameters as in :func:`advance`; the same bits as repeated :func:`advance`."""
    theta0, theta_dot0 = _states(theta0, theta_dot0)
    if transient < 0 or count < 0:
        raise ValueError("transient and count must be ≥ 0")
    out = np.empty((theta0.size, int(count), 2))
    if count > 0:
        _run(_sample, _sample_serial, theta0, theta_dot0, alpha, omega0, torque, table, dt,
             (np.int64(transient), out))
    return out


@cached_njit(nogil=True, fastmath=SIN_FASTMATH)
def _trajectory(theta0, theta_dot0, alpha, omega0, dt, forcing, accel, stride, out):
    """One orbit, step by step: out[i] = (θ, θ̇) after i·``stride`` steps (out[0] the start),
    on the path :func:`orbit_path` chooses for it. It is stepped in a block of LANES copies
    by the loop of :func:`make_period_chunk` (the one LLVM vectorises), so that its bits are
    those of the lane kernels' orbit, not a scalar twin's."""
    path = orbit_path(theta0, theta_dot0, alpha, omega0, dt, accel)
    th = np.full(LANES, theta0)
    v = np.full(LANES, theta_dot0)
    out[0, 0] = theta0
    out[0, 1] = theta_dot0
    n = (forcing.size - 1) // 2
    periods = (out.shape[0] - 1) * stride // n
    i = 0
    for _ in range(periods):
        for j in range(0, forcing.size - 1, 2):
            f0 = forcing[j]
            f1 = forcing[j + 1]
            f2 = forcing[j + 2]
            if path == SHARED:
                for lane in range(LANES):
                    th[lane], v[lane] = _shared_step(th[lane], v[lane], alpha, omega0, dt,
                                                     f0, f1, f2)
            else:
                for lane in range(LANES):
                    th[lane], v[lane] = _full_step(th[lane], v[lane], alpha, omega0, dt,
                                                   f0, f1, f2)
            i += 1
            if i % stride == 0:
                out[i // stride, 0] = th[0]
                out[i // stride, 1] = v[0]


def trajectory(theta0, theta_dot0, alpha, omega0, torque, table, dt, periods, stride=1
               ) -> np.ndarray:
    """One orbit from (θ0 [rad], θ̇0 [rad s⁻¹]) at t = 0 over ``periods`` drive periods, kept
    step by step: float64 (periods·N/``stride`` + 1, 2), row i the state (θ unwrapped [rad],
    θ̇ [rad s⁻¹]) at t = i·stride·dt (``stride`` must divide N, so that every return to P is
    a row: row p·N/stride). The same RK4 step, drive table and path choice as
    :func:`advance` (parameters as there), one orbit at a time: its returns are those of
    :func:`advance` and :func:`sample`, bit for bit (tests/kernels/test_driven.py)."""
    forcing, accel = drive(omega0, torque, table, dt)
    n = (forcing.size - 1) // 2
    if periods < 0 or stride < 1 or n % stride:
        raise ValueError("periods must be ≥ 0 and stride a divisor of the steps per period")
    out = np.empty((int(periods) * (n // int(stride)) + 1, 2))
    _trajectory(float(theta0), float(theta_dot0), float(alpha), float(omega0), float(dt),
                forcing, accel, np.int64(stride), out)
    return out


class LabelArrays(NamedTuple):
    """The arrays of a :func:`label_driven` call as every backend's kernel takes them."""

    theta0: np.ndarray  # float64 n [rad]
    theta_dot0: np.ndarray  # float64 n [rad s⁻¹]
    targets: np.ndarray  # float64 (K, 2)
    target_attractor: np.ndarray  # int16 K
    radius: np.ndarray  # float64 K
    confirm: np.ndarray  # int64, one per attractor (at least 0 … max(target_attractor))
    attractor: np.ndarray  # int16 n, ATTRACTOR_FILL
    periods: np.ndarray  # int32 n
    status: np.ndarray  # int8 n


def label_arrays(theta0, theta_dot0, targets, target_attractor, radius, confirm,
                 max_periods) -> LabelArrays:
    """:func:`label_driven`'s arguments checked and converted (``confirm`` one for all
    attractors, or one per attractor: int64 of length max(target_attractor) + 1), and its
    outputs allocated: for the CPU kernel and its CUDA twin
    (:mod:`atlas.kernels.driven_cuda`)."""
    theta0, theta_dot0 = _states(theta0, theta_dot0)
    targets = np.ascontiguousarray(targets, dtype=np.float64).reshape(-1, 2)
    target_attractor = np.ascontiguousarray(target_attractor, dtype=np.int16)
    if target_attractor.shape != (targets.shape[0],):
        raise ValueError("target_attractor must give one attractor per target")
    if np.any(target_attractor == ATTRACTOR_FILL):
        raise ValueError("the fill value is not an attractor")
    radius = np.ascontiguousarray(np.broadcast_to(np.asarray(radius, np.float64),
                                                  (targets.shape[0],)))
    attractors = int(target_attractor.max()) + 1 if target_attractor.size else 0
    if target_attractor.size and target_attractor.min() < 0:
        raise ValueError("target_attractor must be ≥ 0")
    confirm = np.asarray(confirm, np.int64)
    if confirm.ndim == 0:
        confirm = np.full(attractors, confirm)
    elif confirm.ndim != 1 or confirm.size < attractors:
        raise ValueError("confirm must be one count, or one per attractor (an attractor "
                         "without targets may have one too)")
    confirm = np.ascontiguousarray(confirm)
    if np.any(confirm < 1) or max_periods < 0:
        raise ValueError("confirm must be ≥ 1 and max_periods ≥ 0")
    n = theta0.size
    return LabelArrays(theta0, theta_dot0, targets, target_attractor, radius, confirm,
                       np.full(n, ATTRACTOR_FILL, np.int16), np.zeros(n, np.int32),
                       np.zeros(n, np.int8))


def label_driven(theta0, theta_dot0, alpha, omega0, torque, table, dt, targets,
                 target_attractor, radius, confirm, max_periods):
    """Label each orbit by the attractor it settles on, by proximity of P's returns.

    After each period p = 1 … ``max_periods`` the state (θ wrapped to [−π, π), θ̇) is compared
    with the ``targets`` (float64 (K, 2), θ in [−π, π) [rad], θ̇ [rad s⁻¹]): the distance is
    Euclidean in (θ, θ̇) with the θ difference wrapped to [−π, π); the nearest target within
    ``radius`` (one for all, or one per target: float64 length K) is a hit of attractor
    ``target_attractor[k]`` (int16 ≥ 0, length K). An orbit that hits one attractor a at
    ``confirm[a]`` consecutive returns (any of its targets; ``confirm`` one int for all, or
    one per attractor) is labelled with it at that period and stops. Parameters of the map
    as in :func:`advance`.

    Returns (attractor int16, periods int32, status int8): status ``DECIDED`` (0) with the
    attractor and the deciding period; ``UNRESOLVED`` (1) after ``max_periods`` undecided;
    ``NONFINITE`` (2) at the period a NaN/inf state is met (0 for non-finite input). The
    attractor is ATTRACTOR_FILL (the int16 minimum) unless decided."""
    a = label_arrays(theta0, theta_dot0, targets, target_attractor, radius, confirm,
                     max_periods)
    _run(_label, _label_serial, a.theta0, a.theta_dot0, alpha, omega0, torque, table, dt,
         (a.targets, a.target_attractor, a.radius, a.confirm, np.int64(max_periods),
          a.attractor, a.periods, a.status))
    return a.attractor, a.periods, a.status
