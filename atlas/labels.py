"""Which attractor does an orbit reach? Certified labels by the energy trap.

An orbit is *trapped* in well k (the basin of the rest state (2πk, 0)) the first time

    |θ − 2πk| ≤ π   and   E_k = ½θ̇² + ω0²(1 − cos(θ − 2πk)) < 2ω0²(1 − m).

For the exact flow dE_k/dt = −2αθ̇² ≤ 0 (E is a Lyapunov function), and the set above is
bounded away from the saddles, whose energy is 2ω0²; so a trapped orbit never leaves and
converges to (2πk, 0) when α > 0. The numerical orbit differs from the exact one by RK4's
error, so the trap level is lowered by the relative safety margin m (:func:`trap_margin`),
which covers the largest energy the integrator can gain while the orbit is trapped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import defaults
from .kernels import ATTRACTOR_FILL, METHODS, TRAPPED
from .limits import MAX_STEPS, MAX_TRAP_MARGIN, MAX_WELL, check_reach
from .model import Pendulum, rk4_stable

__all__ = ["LabelResult", "label", "trap_margin", "energy_cap", "ATTRACTOR_FILL", "BACKENDS",
           "METHODS", "DEFAULT_METHOD"]

# ATTRACTOR_FILL, the attractor where status ≠ trapped (also the HDF5 _FillValue), is defined
# in atlas.kernels with the status codes and re-exported here.

#: The CPU discretisation :func:`label` uses unless told (see :data:`atlas.kernels.METHODS`).
DEFAULT_METHOD = METHODS[0]
#: Steps between two trap tests in the fast kernels (trapping times are resolved to this).
CHECK_EVERY = 16
BACKENDS = ("cpu", "cuda")


def trap_margin(dt: float, alpha: float, omega0: float) -> float:
    """Relative safety margin m of the energy trap, dimensionless.

    RK4's local energy error per step is bounded by C(λ·dt)⁵·E with λ the fastest
    linearised rate of the system, u2 = α + √(α² + ω0²) (the saddle's stable rate, which
    bounds |r1|, |r2| of the attractors too) and C ≈ 1/120; over the 2π/(λ·dt) steps of one
    oscillation that accumulates to ≈ 0.05(λ·dt)⁴·E, while damping removes energy every
    period. m = 10⁻⁹ + (λ·dt)⁴ covers that accumulation twenty-fold (m ≈ 1.6e-8 at the
    default dt = 0.01, α = 0.1, ω0 = 1). ``tests/test_labels.py`` measures the largest energy
    rise along computed orbits near the separatrix energy, for both methods ("rk4" and
    "rk4-trigfree"), and checks it stays below 5 % of m·2ω0².
    """
    lam = alpha + math.hypot(alpha, omega0)
    return 1e-9 + (lam * dt) ** 4


def energy_cap(dt: float, alpha: float, omega0: float) -> float:
    """The trap level 2ω0²(1 − m) [rad² s⁻²] that every kernel is given (``energy_cap`` of
    the kernel contract, :mod:`atlas.kernels`), m = :func:`trap_margin`."""
    return 2.0 * omega0**2 * (1.0 - trap_margin(dt, alpha, omega0))


@dataclass(frozen=True)
class LabelResult:
    """Per-orbit labels, arrays shaped like the broadcast initial conditions.

    attractor: int16, k of the attractor (2πk, 0); ``ATTRACTOR_FILL`` where not trapped.
    status:    int8, 0 trapped (certified), 1 unresolved (t_max reached), 2 nonfinite.
    t_trap:    float32 [s], the time at which the trap was first seen (NaN if never).
    """

    attractor: np.ndarray
    status: np.ndarray
    t_trap: np.ndarray


KERNELS = (None, "straightforward")


def resolve_method(backend: str, kernel: str | None, method: str | None) -> str:
    """The discretisation :func:`label` runs: ``method`` if given, else "rk4" for the
    straightforward kernel and the CUDA backend, :data:`DEFAULT_METHOD` otherwise. Raises
    ValueError (one line) for unknown names and combinations that do not exist."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if kernel not in KERNELS:
        raise ValueError(f"kernel must be one of {KERNELS}, got {kernel!r}")
    if method is None:
        return "rk4" if backend == "cuda" or kernel == "straightforward" else DEFAULT_METHOD
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if backend == "cuda" and method != "rk4":
        raise ValueError(f"method {method!r} has no CUDA kernel; the cuda backend runs 'rk4'")
    return method


def _kernel(backend: str, kernel: str | None, method: str | None = None):
    method = resolve_method(backend, kernel, method)
    if backend == "cuda":
        from .kernels.cuda_host import label_cuda

        return label_cuda
    if kernel == "straightforward":
        if method == "rk4":
            from .kernels.rk4 import label_straightforward

            return label_straightforward
        from .kernels.trigfree import label_trigfree_straightforward

        return label_trigfree_straightforward
    from .kernels.lanes import label_lanes, label_trigfree

    return label_lanes if method == "rk4" else label_trigfree


def n_checks_for(t_max: float, dt: float, check_every: int) -> int:
    """Number of trap tests after the initial one: the run covers ⌈t_max/(c·dt)⌉·c steps."""
    return max(1, math.ceil(t_max / (dt * check_every) - 1e-9))


def check_integration(alpha: float, omega0: float, dt: float, t_max: float,
                      check_every: int = CHECK_EVERY) -> None:
    """Raise ValueError (one line, naming the setting) unless labels can be certified:
    α > 0 (with α = 0 energy is conserved and nothing settles), ω0 > 0, finite dt > 0 and
    t_max > 0, at most ``MAX_STEPS`` steps per orbit, dt within RK4's stability limit
    (:func:`atlas.model.rk4_stable`) and fine enough that the trap margin stays
    ≤ ``MAX_TRAP_MARGIN``."""
    pendulum = Pendulum(alpha, omega0)
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


def _check_inputs(theta0: np.ndarray, theta_dot0: np.ndarray, alpha: float) -> None:
    finite_theta = np.abs(theta0[np.isfinite(theta0)])
    finite_speed = np.abs(theta_dot0[np.isfinite(theta_dot0)])
    if finite_theta.size and finite_speed.size:
        check_reach(float(finite_theta.max()), float(finite_speed.max()), alpha)


def label(
    theta0,
    theta_dot0,
    *,
    alpha: float,
    omega0: float,
    dt: float = defaults.DT,
    t_max: float = defaults.T_MAX,
    backend: str = "cpu",
    kernel: str | None = None,
    check_every: int = CHECK_EVERY,
    method: str | None = None,
) -> LabelResult:
    """Label initial conditions (θ0 [rad], θ̇0 [rad s⁻¹]) by the attractor they reach.

    Integrates eq. (1) with fixed-step RK4 (step ``dt`` [s], at most ``t_max`` [s] rounded up
    to a whole number of trap tests) and stops each orbit once certified by the energy trap.
    ``method`` picks the discretisation (:data:`atlas.kernels.METHODS`): on the CPU
    "rk4-trigfree" by default (RK4 with cos θ, sin θ carried as state), or "rk4" (RK4 with a
    sin per stage, the lane kernel of earlier versions and the CUDA backend's method).
    ``kernel="straightforward"`` selects the plain one-orbit-per-thread CPU kernel of the
    method, "rk4" unless ``method`` says otherwise.
    Raises ValueError for settings that cannot give certified labels
    (:func:`check_integration`) or initial conditions whose orbits may reach wells beyond
    |k| ≤ MAX_WELL (:func:`atlas.limits.check_reach`); OverflowError if one does anyway.
    """
    check_integration(alpha, omega0, dt, t_max, check_every)
    run = _kernel(backend, kernel, method)
    theta0, theta_dot0 = np.broadcast_arrays(
        np.asarray(theta0, dtype=np.float64), np.asarray(theta_dot0, dtype=np.float64)
    )
    _check_inputs(theta0, theta_dot0, alpha)
    shape = theta0.shape
    th = np.ascontiguousarray(theta0.ravel())
    v = np.ascontiguousarray(theta_dot0.ravel())
    n = th.size
    attractor = np.zeros(n, np.int32)
    status = np.zeros(n, np.int8)
    n_trap = np.zeros(n, np.int32)
    run(th, v, float(alpha), float(omega0), float(dt), n_checks_for(t_max, dt, check_every),
        int(check_every), energy_cap(dt, alpha, omega0), attractor, status, n_trap)
    trapped = status == TRAPPED
    if np.any(np.abs(attractor[trapped]) > MAX_WELL):
        raise OverflowError(f"an orbit reached a well |k| > {MAX_WELL}, beyond the int16 "
                            "attractor index of the atlas; narrow the θ0/θ̇0 window")
    return LabelResult(
        attractor=np.where(trapped, attractor, ATTRACTOR_FILL).astype(np.int16).reshape(shape),
        status=status.reshape(shape),
        t_trap=np.where(trapped, n_trap * dt, np.nan).astype(np.float32).reshape(shape),
    )
