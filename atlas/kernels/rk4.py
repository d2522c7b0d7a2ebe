"""Classical RK4 for eq. (1) and the straightforward labelling kernel (one orbit per thread).

The RK4 step and the trap test are built by factories that close over a ``sin``
implementation, so the straightforward kernel (``math.sin``) and the lane-blocked kernel
(polynomial sin, :mod:`atlas.kernels.lanes`) share one definition of the method.

Reference: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.1 (classical 4th-order
Runge–Kutta, local error O(dt⁵), global error O(dt⁴)).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from . import NONFINITE, TRAPPED, UNRESOLVED, cached_njit

# Fast-math flags that keep NaN/inf semantics honest (no 'nnan'/'ninf'): the kernels must
# see a non-finite state to report status NONFINITE.
FASTMATH = {"contract", "arcp", "nsz", "afn", "reassoc"}

TWO_PI = 2.0 * math.pi
INV_TWO_PI = 1.0 / TWO_PI


@nb.njit(inline="always")
def _identity(x):
    return x


def make_rk4_step(sin, reduce=None):
    """Return a jitted ``step(theta, theta_dot, alpha, omega0, dt) -> (theta, theta_dot)``.

    One classical RK4 step of θ' = θ̇, θ̇' = −ω0² sin θ − 2αθ̇ using the given ``sin``.
    With ``reduce`` given, the four stage angles θ + δ (δ = 0, ½dt·k1θ, ½dt·k2θ, dt·k3θ) share
    one argument reduction: ``sin`` is then called as ``sin(reduce(θ), δ)`` = sin(θ + δ)
    (:mod:`atlas.kernels.lanes` uses this with a polynomial sin).
    """
    if reduce is None:
        reduce = _identity

        @nb.njit(inline="always", fastmath=FASTMATH)
        def sin_near(theta, delta):
            return sin(theta + delta)

    else:
        sin_near = sin

    @nb.njit(inline="always", fastmath=FASTMATH)
    def step(theta, theta_dot, alpha, omega0, dt):
        w2 = omega0 * omega0
        a2 = 2.0 * alpha
        h2 = 0.5 * dt
        p = reduce(theta)
        k1t = theta_dot
        k1v = -w2 * sin_near(p, 0.0) - a2 * theta_dot
        k2t = theta_dot + h2 * k1v
        k2v = -w2 * sin_near(p, h2 * k1t) - a2 * k2t
        k3t = theta_dot + h2 * k2v
        k3v = -w2 * sin_near(p, h2 * k2t) - a2 * k3t
        k4t = theta_dot + dt * k3v
        k4v = -w2 * sin_near(p, dt * k3t) - a2 * k4t
        h6 = dt / 6.0
        return (
            theta + h6 * (k1t + 2.0 * (k2t + k3t) + k4t),
            theta_dot + h6 * (k1v + 2.0 * (k2v + k3v) + k4v),
        )

    return step


def make_well_energy(sin):
    """Return a jitted ``well_energy(theta, theta_dot, omega0) -> (k, E_k)``.

    k = round(θ/2π) is the nearest well, φ = θ − 2πk ∈ [−π, π], and
    E_k = ½θ̇² + ω0²(1 − cos φ) is evaluated as ½θ̇² + 2ω0² sin²(φ/2), which has no
    cancellation near the bottom of the well.
    """

    @nb.njit(inline="always", fastmath=FASTMATH)
    def well_energy(theta, theta_dot, omega0):
        k = math.floor(theta * INV_TWO_PI + 0.5)
        s = sin(0.5 * (theta - TWO_PI * k))
        return k, 0.5 * theta_dot * theta_dot + 2.0 * omega0 * omega0 * s * s

    return well_energy


@nb.njit(inline="always")
def _libm_sin(x):
    return math.sin(x)


rk4_step = make_rk4_step(_libm_sin)
well_energy = make_well_energy(_libm_sin)


@nb.njit(nogil=True, fastmath=FASTMATH)
def label_orbit(theta, theta_dot, alpha, omega0, dt, n_checks, check_every, energy_cap):
    """Label one orbit (kernel contract in :mod:`atlas.kernels`) with ``math.sin``; returns
    (status, k, n_trap), k meaningful only when trapped."""
    for j in range(n_checks + 1):
        if not (math.isfinite(theta) and math.isfinite(theta_dot)):
            return NONFINITE, 0, -1
        k, energy = well_energy(theta, theta_dot, omega0)
        if energy < energy_cap:
            return TRAPPED, k, j * check_every
        if j == n_checks:
            break
        for _ in range(check_every):
            theta, theta_dot = rk4_step(theta, theta_dot, alpha, omega0, dt)
    return UNRESOLVED, 0, -1


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def label_straightforward(
    theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
    attractor, status, n_trap,
):
    """Label orbits one per ``prange`` iteration with ``math.sin`` (kernel contract in
    :mod:`atlas.kernels`). The plain implementation that the fast kernels are measured and
    checked against."""
    for i in nb.prange(theta0.size):
        st, k, nt = label_orbit(theta0[i], theta_dot0[i], alpha, omega0, dt, n_checks,
                                check_every, energy_cap)
        status[i] = st
        n_trap[i] = nt
        if st == TRAPPED:
            attractor[i] = np.int32(k)


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def propagate_straightforward(theta, theta_dot, alpha, omega0, dt, n_steps):
    """Advance every orbit by ``n_steps`` RK4 steps in place (no early exit): bulk throughput
    reference and the fixed-duration integrator used by tests and figures."""
    for i in nb.prange(theta.size):
        th = theta[i]
        v = theta_dot[i]
        for _ in range(n_steps):
            th, v = rk4_step(th, v, alpha, omega0, dt)
        theta[i] = th
        theta_dot[i] = v


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def record_straightforward(theta, theta_dot, alpha, omega0, dt, every, out):
    """Trajectories: ``out[:, i, j]`` = (θ, θ̇) of orbit j after i·``every`` RK4 steps, for
    i < out.shape[1] (figures and phase portraits; the same step as every kernel here)."""
    for j in nb.prange(theta.size):
        th, v = theta[j], theta_dot[j]
        out[0, 0, j], out[1, 0, j] = th, v
        for i in range(1, out.shape[1]):
            for _ in range(every):
                th, v = rk4_step(th, v, alpha, omega0, dt)
            out[0, i, j], out[1, i, j] = th, v
