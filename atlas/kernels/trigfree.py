"""Trig-free RK4: eq. (1) integrated with cos θ and sin θ carried as state.

With c = cos θ, s = sin θ the pendulum is the polynomial system θ' = θ̇,
θ̇' = −ω0² s − 2αθ̇ + τ, c' = −s·θ̇, s' = c·θ̇; classical RK4 on it (:func:`make_trigfree_step`)
needs no trigonometric function in a step (≈ 45 flops instead of ≈ 90). (c, s) is
re-synchronised from θ at every trap test (:func:`~atlas.kernels.fastsin.sin_cos_vers`), which
is part of the method. :func:`label_orbit_trigfree` is its scalar form (libm), for the orbits
the lane kernel does not take.

Accuracy: a different discretisation of the same order 4 (Hairer, Nørsett & Wanner, *Solving
ODEs I*, §II.1); tests/kernels/test_trigfree_order.py fits the order against DOP853. Between
re-synchronisations c² + s² drifts by O(dt⁵) per step.
Derivation: docs/design/kernels.md#trig-free-rk4.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import NONFINITE, TRAPPED, UNRESOLVED, cached_njit, uses_torque
from atlas.kernels.fastsin import SIN_FASTMATH, sin_cos_vers
from atlas.kernels.rk4 import (
    INV_TWO_PI,
    TWO_PI,
    make_label_orbit_torque,
    specialise,
    torque_model,
)

#: Steps between two re-synchronisations of (c, s) in the fixed-steps kernels (the labelling
#: kernels re-synchronise at every trap test instead, the default ``check_every`` = 16).
SYNC_EVERY = 16


# One source for the step of both specialisations (τ = 0 as in earlier versions, τ ≠ 0 with
# θ̇' = τ − ω0² s − 2αθ̇), as :data:`atlas.kernels.rk4._RK4_STEP`. Its four stages are written
# out (they repeat one shape): the τ = 0 form must keep the earlier versions' exact code.
_TRIGFREE_STEP = """
def step(theta, theta_dot, c, s, alpha, omega0, dt{torque}):
    w2 = omega0 * omega0
    a2 = 2.0 * alpha
    h2 = 0.5 * dt
    k1v = {force}w2 * s - a2 * theta_dot
    k1c = -s * theta_dot
    k1s = c * theta_dot
    v2 = theta_dot + h2 * k1v
    c2 = c + h2 * k1c
    s2 = s + h2 * k1s
    k2v = {force}w2 * s2 - a2 * v2
    k2c = -s2 * v2
    k2s = c2 * v2
    v3 = theta_dot + h2 * k2v
    c3 = c + h2 * k2c
    s3 = s + h2 * k2s
    k3v = {force}w2 * s3 - a2 * v3
    k3c = -s3 * v3
    k3s = c3 * v3
    v4 = theta_dot + dt * k3v
    c4 = c + dt * k3c
    s4 = s + dt * k3s
    k4v = {force}w2 * s4 - a2 * v4
    k4c = -s4 * v4
    k4s = c4 * v4
    h6 = dt / 6.0
    return (
        theta + h6 * (theta_dot + 2.0 * (v2 + v3) + v4),
        theta_dot + h6 * (k1v + 2.0 * (k2v + k3v) + k4v),
        c + h6 * (k1c + 2.0 * (k2c + k3c) + k4c),
        s + h6 * (k1s + 2.0 * (k2s + k3s) + k4s),
    )
"""


def make_trigfree_step(*, torque=False):
    """Return a jitted ``step(theta, theta_dot, c, s, alpha, omega0, dt) -> (θ, θ̇, c, s)``:
    one classical RK4 step of the extended system (module docstring); with ``torque`` the
    step of θ̇' = −ω0² s − 2αθ̇ + τ, τ its last argument (:func:`make_trigfree_step_torque`)."""
    step = specialise(_TRIGFREE_STEP, "step", torque)
    return nb.njit(inline="always", fastmath=SIN_FASTMATH)(step)


def make_sync(sin_cos_vers_impl):
    """Return a jitted ``sync(theta, theta_dot, omega0) -> (c, s, k, E_k)``: the
    re-synchronised c = cos θ, s = sin θ, the nearest well k = round(θ/2π) and its energy
    E_k = ½θ̇² + ω0²(1 − cos θ) (cancellation-free)."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def sync(theta, theta_dot, omega0):
        k = math.floor(theta * INV_TWO_PI + 0.5)
        s, c, vers = sin_cos_vers_impl(theta)
        return c, s, k, 0.5 * theta_dot * theta_dot + omega0 * omega0 * vers

    return sync


@nb.njit(inline="always")
def _libm_sin_cos_vers(x):
    h = math.sin(0.5 * x)
    return math.sin(x), math.cos(x), 2.0 * (h * h)


trigfree_step = make_trigfree_step()
sync_poly = make_sync(sin_cos_vers)
sync_libm = make_sync(_libm_sin_cos_vers)


# ------------------------------------------------------------------------- torque τ ≠ 0
# Separate specialisations (as in :mod:`atlas.kernels.rk4`): the τ = 0 code above is that of
# earlier versions, unchanged (the step: the same source, :data:`_TRIGFREE_STEP`).


def make_trigfree_step_torque():
    """Return a jitted ``step(theta, theta_dot, c, s, alpha, omega0, dt, torque)``: one RK4
    step of the extended system with θ̇' = −ω0² s − 2αθ̇ + τ."""
    return make_trigfree_step(torque=True)


def make_sync_torque(sin_cos_vers_impl):
    """Return a jitted ``sync(theta, theta_dot, omega0, torque, shift, vers_shift)
    -> (c, s, k, E_k)``: the re-synchronised c = cos θ, s = sin θ, the tilted well
    k = round((θ + θ*)/2π) and its energy E_k = ½θ̇² + ω0²((1 − cos θ) − (1 − cos θ*))
    − τ(φ − θ*) (contract of :mod:`atlas.kernels`; ``shift`` = θ*, ``vers_shift`` = 1 − cos θ*)."""

    @nb.njit(inline="always", fastmath=SIN_FASTMATH)
    def sync(theta, theta_dot, omega0, torque, shift, vers_shift):
        k = math.floor((theta + shift) * INV_TWO_PI + 0.5)
        s, c, vers = sin_cos_vers_impl(theta)
        phi = theta - TWO_PI * k
        return c, s, k, (0.5 * theta_dot * theta_dot + omega0 * omega0 * (vers - vers_shift)
                         - torque * (phi - shift))

    return sync


trigfree_step_torque = make_trigfree_step_torque()
sync_poly_torque = make_sync_torque(sin_cos_vers)
sync_libm_torque = make_sync_torque(_libm_sin_cos_vers)


@nb.njit(nogil=True, fastmath=SIN_FASTMATH)
def label_orbit_trigfree(theta, theta_dot, alpha, omega0, dt, n_checks, check_every,
                         energy_cap):
    """Label one orbit with the trig-free method, libm sin/cos at the re-synchronisation
    (kernel contract in :mod:`atlas.kernels`); returns (status, k, n_trap)."""
    for j in range(n_checks + 1):
        if not (math.isfinite(theta) and math.isfinite(theta_dot)):
            return NONFINITE, 0, -1
        c, s, k, energy = sync_libm(theta, theta_dot, omega0)
        if energy < energy_cap:
            return TRAPPED, k, j * check_every
        if j == n_checks:
            break
        for _ in range(check_every):
            theta, theta_dot, c, s = trigfree_step(theta, theta_dot, c, s, alpha, omega0, dt)
    return UNRESOLVED, 0, -1


#: Label one orbit of the tilted pendulum with the trig-free method, libm sin/cos at the
#: re-synchronisation (:func:`atlas.kernels.rk4.make_label_orbit_torque`).
label_orbit_trigfree_torque = make_label_orbit_torque(sync_libm_torque, trigfree_step_torque,
                                                      SIN_FASTMATH)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label_trigfree_straightforward(
    theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
    attractor, status, n_trap,
):
    """The τ = 0 specialisation of :func:`label_trigfree_straightforward` (the kernel of
    earlier versions, unchanged)."""
    for i in nb.prange(theta0.size):
        st, k, nt = label_orbit_trigfree(theta0[i], theta_dot0[i], alpha, omega0, dt,
                                         n_checks, check_every, energy_cap)
        status[i] = st
        n_trap[i] = nt
        if st == TRAPPED:
            attractor[i] = np.int32(k)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _label_trigfree_straightforward_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks,
                                           check_every, energy_cap, model, attractor, status,
                                           n_trap):
    for i in nb.prange(theta0.size):
        st, k, nt = label_orbit_trigfree_torque(theta0[i], theta_dot0[i], alpha, omega0, dt,
                                                n_checks, check_every, energy_cap, model)
        status[i] = st
        n_trap[i] = nt
        if st == TRAPPED:
            attractor[i] = np.int32(k)


def label_trigfree_straightforward(theta0, theta_dot0, alpha, omega0, dt, n_checks,
                                   check_every, energy_cap, attractor, status, n_trap,
                                   torque=0.0, running_theta0=0.0, running_g=None,
                                   running_top=math.inf):
    """The trig-free method one orbit per ``prange`` iteration, libm at the
    re-synchronisation (kernel contract in :mod:`atlas.kernels`): the plain form of the
    method, against which its lane kernel is checked. τ = 0 without a running barrier runs
    the τ = 0 specialisation (the kernel of earlier versions), else the tilted one."""
    if not uses_torque(torque, running_g):
        _label_trigfree_straightforward(theta0, theta_dot0, alpha, omega0, dt, n_checks,
                                        check_every, energy_cap, attractor, status, n_trap)
        return
    model = torque_model(omega0, torque, running_theta0, running_g, running_top)
    _label_trigfree_straightforward_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks,
                                           check_every, energy_cap, model, attractor, status,
                                           n_trap)


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def record_trigfree(theta, theta_dot, alpha, omega0, dt, every, out):
    """Trajectories of the trig-free method (libm re-synchronisation every ``SYNC_EVERY``
    steps): ``out[:, i, j]`` = (θ, θ̇) of orbit j after i·``every`` steps."""
    for j in nb.prange(theta.size):
        th, v = theta[j], theta_dot[j]
        c, s, _, _ = sync_libm(th, v, omega0)
        out[0, 0, j], out[1, 0, j] = th, v
        n = 0
        for i in range(1, out.shape[1]):
            for _ in range(every):
                th, v, c, s = trigfree_step(th, v, c, s, alpha, omega0, dt)
                n += 1
                if n % SYNC_EVERY == 0:
                    c, s, _, _ = sync_libm(th, v, omega0)
            out[0, i, j], out[1, i, j] = th, v


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def record_trigfree_torque(theta, theta_dot, alpha, omega0, torque, dt, every, out):
    """:func:`record_trigfree` for θ̈ = −ω0² sin θ − 2αθ̇ + τ (libm re-synchronisation every
    ``SYNC_EVERY`` steps): ``out[:, i, j]`` = (θ, θ̇) of orbit j after i·``every`` steps."""
    for j in nb.prange(theta.size):
        th, v = theta[j], theta_dot[j]
        c, s = math.cos(th), math.sin(th)
        out[0, 0, j], out[1, 0, j] = th, v
        n = 0
        for i in range(1, out.shape[1]):
            for _ in range(every):
                th, v, c, s = trigfree_step_torque(th, v, c, s, alpha, omega0, dt, torque)
                n += 1
                if n % SYNC_EVERY == 0:
                    c, s = math.cos(th), math.sin(th)
            out[0, i, j], out[1, i, j] = th, v
