"""Which attractor does an orbit reach? :func:`atlas.label`: certified labels of the RK4 map.

Each initial condition (θ0, θ̇0) of θ̈ = −ω0² sin θ − 2αθ̇ + τ is followed with fixed-step RK4
(a method of :mod:`atlas.labels.methods`, on a device of :mod:`atlas.labels.backends`) until a
certificate holds: the energy trap of a well (:mod:`atlas.labels.trap`), or, with a torque and a
:class:`~atlas.physics.barrier.RunningBarrier`, the running certificate (its builder:
:mod:`atlas.physics.running`). Trapped orbits of the *RK4 map* converge to the rest state of
their well; running ones to the running limit cycle. Nothing is guessed: an orbit no
certificate holds for within t_max is unresolved. Whether the *exact* equation agrees (the
distance to the exact basin boundaries) is the business of :mod:`atlas.boundaries`; the
status codes are :mod:`atlas.status`. Also here: the checks that settings and initial
conditions can be certified at all (:func:`check_integration`, :func:`check_torque_reach`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from atlas import defaults
from atlas.labels import backends, methods
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for, trap_margin
from atlas.limits import MAX_STEPS, MAX_TRAP_MARGIN, MAX_WELL, check_reach
from atlas.physics.barrier import RunningBarrier
from atlas.physics.pendulum import Pendulum, rk4_stable
from atlas.status import ATTRACTOR_FILL, NONFINITE, RUNNING, TRAPPED, UNRESOLVED

__all__ = ["LabelResult", "LABEL_STATUS_MEANINGS", "label", "check_integration",
           "check_torque_reach", "check_running"]


#: What each ``status`` of a :class:`LabelResult` means, by name: the labels of the *RK4 map*,
#: not checked against the exact equation. The codes are :mod:`atlas.status`'s, but in an
#: atlas file 0 (``trapped``) and 4 (``running``) mean more, certified for the exact equation
#: (:data:`atlas.status.IN_FILE`); the names here say the difference.
LABEL_STATUS_MEANINGS = {
    TRAPPED: "trapped_rk4_map",    # in the energy trap of well k of the RK4 map at step dt
    UNRESOLVED: "unresolved",      # no certificate held before t_max
    NONFINITE: "nonfinite",        # a NaN or inf state was met
    RUNNING: "running_rk4_map",    # in the running barrier of the RK4 map (τ ≠ 0)
}


@dataclass(frozen=True)
class LabelResult:
    """Per-orbit labels, arrays shaped like the broadcast initial conditions.

    attractor: int16, k of the attractor (the rest state (θ* + 2πk, 0), θ* = 0 when τ = 0);
               ``ATTRACTOR_FILL`` where not trapped.
    status:    int8 (:mod:`atlas.status`; names in :attr:`status_meanings`),
               0 ``trapped_rk4_map`` (certified for the RK4 map: not yet for the exact
               equation, see :func:`label`), 1 ``unresolved`` (t_max reached),
               2 ``nonfinite``, 4 ``running_rk4_map`` (certified, for the RK4 map, to converge
               to the running limit cycle; τ ≠ 0 only). The file's 3 and 5 (near a basin
               boundary) never occur here: :func:`label` does not measure that distance.
    t_trap:    float32 [s], the time at which the trap, or the running certificate, was first
               seen (NaN if never).
    direction: int8, the direction of rotation where running (+1, −1: sign(τ)), 0 elsewhere.
               Optional when constructing (all 0).
    """

    attractor: np.ndarray
    status: np.ndarray
    t_trap: np.ndarray
    direction: np.ndarray | None = None
    #: ``status`` code → name (:data:`LABEL_STATUS_MEANINGS`): what a code means *here*.
    status_meanings: ClassVar[dict[int, str]] = LABEL_STATUS_MEANINGS

    def __post_init__(self) -> None:
        if self.direction is None:
            object.__setattr__(self, "direction",
                               np.zeros(np.shape(self.status), dtype=np.int8))

    def status_names(self) -> np.ndarray:
        """``status`` as names (:attr:`status_meanings`), an array of str of its shape;
        ValueError for a code that :func:`label` never sets."""
        codes = np.array(sorted(self.status_meanings))
        status = np.asarray(self.status)
        index = np.minimum(np.searchsorted(codes, status), codes.size - 1)
        if not np.array_equal(codes[index], status):
            unknown = sorted(set(np.unique(status).tolist()) - set(codes.tolist()))
            raise ValueError(f"status {unknown} is not a code of atlas.label's results")
        return np.array([self.status_meanings[code] for code in codes])[index]


def check_integration(alpha: float, omega0: float, dt: float, t_max: float,
                      check_every: int = CHECK_EVERY, torque: float = 0.0) -> None:
    """Raise ValueError (one line, naming the setting) unless labels can be certified:
    α > 0 (with α = 0 energy is conserved and nothing settles), ω0 > 0, finite τ, finite
    dt > 0 and t_max > 0, at most ``MAX_STEPS`` steps per orbit, dt within RK4's stability
    limit (:func:`atlas.physics.pendulum.rk4_stable`, which covers every τ) and fine enough that the
    trap margin stays ≤ ``MAX_TRAP_MARGIN``."""
    pendulum = Pendulum(alpha, omega0, torque)
    if alpha == 0.0:
        raise ValueError("alpha = 0: without damping the energy is conserved and no orbit "
                         "ever settles, so no label can be certified")
    for name, value in (("dt", dt), ("t_max", t_max)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    if check_every < 1:
        raise ValueError(f"check_every must be >= 1, got {check_every}")
    if n_checks_for(t_max, dt, check_every) * check_every > MAX_STEPS:
        raise ValueError(f"t_max: t_max/dt = {t_max / dt:.3g} steps per orbit is more than "
                         f"the {MAX_STEPS} an orbit may take")
    where = f"for alpha = {alpha:g}, omega0 = {omega0:g}"
    if not rk4_stable(pendulum, dt):
        raise ValueError(f"dt = {dt:g} is beyond RK4's stability limit {where}; use a "
                         "smaller dt")
    margin = trap_margin(dt, alpha, omega0)
    if margin > MAX_TRAP_MARGIN:
        fine = (MAX_TRAP_MARGIN - 1e-9) ** 0.25 / (alpha + math.hypot(alpha, omega0))
        raise ValueError(f"dt = {dt:g} is too coarse for certified labels {where}: the energy "
                         f"trap's safety margin would be {margin:.2g} (at most "
                         f"{MAX_TRAP_MARGIN:g}); use dt <= {fine:.3g}")


def _check_inputs(theta0: np.ndarray, theta_dot0: np.ndarray, alpha: float,
                  omega0: float = 1.0, torque: float = 0.0, span: float = 0.0) -> None:
    finite_theta = np.abs(theta0[np.isfinite(theta0)])
    finite_speed = np.abs(theta_dot0[np.isfinite(theta_dot0)])
    if not (finite_theta.size and finite_speed.size):
        return
    theta_abs, speed_abs = float(finite_theta.max()), float(finite_speed.max())
    if torque == 0.0:
        check_reach(theta_abs, speed_abs, alpha)
        return
    check_torque_reach(theta_abs, speed_abs, alpha, omega0, torque, span)


def check_torque_reach(theta_abs: float, speed_abs: float, alpha: float, omega0: float,
                       torque: float, span: float) -> None:
    """Raise ValueError (one line) if orbits from |θ0| ≤ ``theta_abs`` [rad], |θ̇0| ≤
    ``speed_abs`` [rad s⁻¹] of the pendulum with torque may travel, within ``span`` [s], to
    wells beyond |k| ≤ MAX_WELL."""
    # with τ the speed stays within max(|θ̇0|, (ω0² + |τ|)/2α) (above it θ̈ points back), so
    # an orbit travels at most that times the run's length
    bound = theta_abs + max(speed_abs, (omega0**2 + abs(torque)) / (2.0 * alpha)) * span
    bound += 2 * math.pi
    if bound > 2 * math.pi * MAX_WELL:
        raise ValueError(f"orbits from this window may travel to |θ| ≈ {bound:.3g} rad within "
                         f"t_max, beyond the wells |k| ≤ {MAX_WELL} that an atlas file can "
                         "index")


def check_running(running, torque: float, method: str = defaults.METHOD) -> None:
    """A running certificate must be a :class:`RunningBarrier` (or None) of direction
    sign(τ), τ ≠ 0, for a method it is established for
    (:attr:`atlas.labels.methods.Method.running`: "rk4"): TypeError, ValueError otherwise.
    The barrier's step allowance (:func:`atlas.physics.running.rk4_allowance`) is measured
    for classical RK4 only; the trig-free step's local error, with cos θ and sin θ drifting
    between re-synchronisations, is larger (up to several times that allowance at
    dt = 0.05), so nothing certifies it."""
    if running is None:
        return
    if not isinstance(running, RunningBarrier):
        raise TypeError(f"running must be a RunningBarrier or None, got "
                        f"{type(running).__name__}")
    if torque == 0.0 or running.direction != (1 if torque > 0 else -1):
        raise ValueError(f"running barrier of direction {running.direction:+d} given for "
                         f"torque = {torque:g}: it must be sign(torque)")
    if not methods.lookup(method).running:
        established = ", ".join(repr(m.name) for m in methods.METHODS.values() if m.running)
        raise ValueError(f"method {method!r}: the running certificate is established for "
                         f"classical RK4 only (method {established})")


def label(
    theta0,
    theta_dot0,
    *,
    alpha: float,
    omega0: float,
    torque: float = 0.0,
    dt: float = defaults.DT,
    t_max: float = defaults.T_MAX,
    backend: str = "cpu",
    kernel: str | None = None,
    check_every: int = CHECK_EVERY,
    method: str | None = None,
    running: RunningBarrier | None = None,
) -> LabelResult:
    """Label initial conditions (θ0 [rad], θ̇0 [rad s⁻¹]) by the attractor they reach.

    Integrates eq. (1) with fixed-step RK4 (step ``dt`` [s], at most ``t_max`` [s] rounded up
    to a whole number of trap tests) and stops each orbit once certified by the energy trap.

    What ``status = 0`` (``trapped_rk4_map``) means here: the orbit of the *RK4 map* at step
    ``dt`` is trapped in well k, and so converges to its rest state; a certificate for the RK4 map,
    not for the exact equation, whose basin boundary may lie on the other side of an initial
    condition close to it. In an atlas *file* ``status = 0`` means more: certified for the
    exact equation, because the sweep turns every label closer than ``d_cert`` to an exact
    basin boundary into NEAR_BOUNDARY (3), and a running one into RUNNING_NEAR_BOUNDARY (5)
    (:mod:`atlas.boundaries.certificate`). ``atlas.label`` does no such check.

    ``method`` picks the discretisation (:mod:`atlas.labels.methods`): by default
    :data:`atlas.defaults.METHOD`, "rk4" (RK4 with a sin per stage, also the CUDA backend's
    method), or "rk4-trigfree" (RK4 with cos θ, sin θ carried as state). ``backend`` picks the
    device (:mod:`atlas.labels.backends`: "cpu" or "cuda"), ``kernel="straightforward"`` its
    plain one-orbit-per-thread kernel of the method.
    ``torque`` τ [rad s⁻²] tilts the wells (module docstring); ``running`` (a
    :class:`RunningBarrier` for this α, ω0, τ, with ``direction`` = sign(τ)) enables the
    running certificate: such orbits get status RUNNING, ``direction`` sign(τ) and t_trap the
    time of certification. With τ = 0 and no barrier the kernels of earlier versions run and
    every array is bit-identical to theirs.
    Raises ValueError for settings that cannot give certified labels
    (:func:`check_integration`; a non-finite τ; a barrier whose direction is not sign(τ);
    an unknown backend, kernel or method, or a method the backend has no kernel for) or
    initial conditions whose orbits may reach wells beyond |k| ≤ MAX_WELL
    (:func:`atlas.limits.check_reach`; with τ ≠ 0 the bound is the speed band times t_max);
    OverflowError if one does anyway.
    """
    torque = float(torque)
    check_integration(alpha, omega0, dt, t_max, check_every, torque)
    method = backends.resolve_method(backend, kernel, method)
    check_running(running, torque, method)
    run = backends.lookup(backend).kernel(method, kernel)
    theta0, theta_dot0 = np.broadcast_arrays(
        np.asarray(theta0, dtype=np.float64), np.asarray(theta_dot0, dtype=np.float64)
    )
    n_checks = n_checks_for(t_max, dt, check_every)
    _check_inputs(theta0, theta_dot0, alpha, omega0, torque, n_checks * check_every * dt)
    shape = theta0.shape
    th = np.ascontiguousarray(theta0.ravel())
    v = np.ascontiguousarray(theta_dot0.ravel())
    n = th.size
    attractor = np.zeros(n, np.int32)
    status = np.zeros(n, np.int8)
    n_trap = np.zeros(n, np.int32)
    args = (th, v, float(alpha), float(omega0), float(dt), n_checks, int(check_every),
            energy_cap(dt, alpha, omega0, torque), attractor, status, n_trap)
    if torque == 0.0 and running is None:
        run(*args)  # the τ = 0 kernels of earlier versions
    else:
        r_theta0, r_g, r_top = (running.kernel_args() if running is not None
                                else (0.0, None, math.inf))
        run(*args, torque=torque, running_theta0=r_theta0, running_g=r_g, running_top=r_top)
    trapped = status == TRAPPED
    if np.any(np.abs(attractor[trapped]) > MAX_WELL):
        raise OverflowError(f"an orbit reached a well |k| > {MAX_WELL}, beyond the int16 "
                            "attractor index of the atlas; narrow the θ0/θ̇0 window")
    certified = trapped | (status == RUNNING)
    direction = np.zeros(n, np.int8)
    if running is not None:
        direction[status == RUNNING] = running.direction
    return LabelResult(
        attractor=np.where(trapped, attractor, ATTRACTOR_FILL).astype(np.int16).reshape(shape),
        status=status.reshape(shape),
        t_trap=np.where(certified, n_trap * dt, np.nan).astype(np.float32).reshape(shape),
        direction=direction.reshape(shape),
    )
