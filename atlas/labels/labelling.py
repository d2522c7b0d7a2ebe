"""Which attractor does an orbit reach? Certified labels by the energy trap, and (with a
torque τ) by the running certificate.

An orbit is *trapped* in well k (the basin of the rest state (2πk, 0)) the first time

    |θ − 2πk| ≤ π   and   E_k = ½θ̇² + ω0²(1 − cos(θ − 2πk)) < 2ω0²(1 − m).

For the exact flow dE_k/dt = −2αθ̇² ≤ 0 (E is a Lyapunov function), and the set above is
bounded away from the saddles, whose energy is 2ω0²; so a trapped orbit never leaves and
converges to (2πk, 0) when α > 0. The numerical orbit differs from the exact one by RK4's
error, so the trap level is lowered by the relative safety margin m (:func:`trap_margin`),
which covers the largest energy the integrator can gain while the orbit is trapped.

With a torque (θ̈ = −ω0² sin θ − 2αθ̇ + τ, 0 < |τ| < ω0²) the wells tilt: well k is the strip
−π − θ* ≤ θ − 2πk < π − θ* between its two saddles (θ* = arcsin(τ/ω0²)), with the rest state
(θ* + 2πk, 0), and E_k = ½θ̇² + ω0²(cos θ* − cos φ) − τ(φ − θ*) (φ = θ − 2πk) is its energy
above the rest state, still with dE_k/dt = −2αθ̇². Inside the strip the potential rises
monotonically from the rest state to either saddle, so {E_k < c} is a disc around the rest
state bounded away from both saddles whenever c is below the *lower* saddle energy
(:attr:`atlas.physics.pendulum.Pendulum.saddle_energy`); the trap level is that energy lowered by the
same relative margin m, and by 1e-10·(ω0² + |τ|) for the rounding of E_k (:func:`energy_cap`).
For |τ| ≥ ω0² there is no well and nothing is trapped.

An orbit is *running* (status ``RUNNING``) once it enters a forward-invariant region around
the running limit cycle that contains no rest state, given by a :class:`RunningBarrier`
(built by :mod:`atlas.physics.running`): then it converges to the limit cycle, rotating in the
direction sign(τ). Without a barrier no orbit is labelled running (it stays unresolved:
atlas never guesses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from atlas import defaults
from atlas.kernels import ATTRACTOR_FILL, METHODS, RUNNING, TRAPPED
from atlas.limits import MAX_STEPS, MAX_TRAP_MARGIN, MAX_WELL, check_reach
from atlas.physics.pendulum import Pendulum, rk4_stable

__all__ = ["LabelResult", "RunningBarrier", "label", "trap_margin", "energy_cap",
           "ATTRACTOR_FILL", "BACKENDS", "METHODS", "DEFAULT_METHOD"]

# ATTRACTOR_FILL, the attractor where status ≠ trapped (also the HDF5 _FillValue), is defined
# in atlas.kernels with the status codes and re-exported here.

#: The CPU discretisation :func:`label` uses unless told (see :data:`atlas.kernels.METHODS`).
DEFAULT_METHOD = defaults.METHOD
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
    default dt = 0.01, α = 0.1, ω0 = 1). ``tests/labels/test_labels.py`` measures the largest energy
    rise along computed orbits near the separatrix energy, for both methods ("rk4" and
    "rk4-trigfree"), and checks it stays below 5 % of m·2ω0².
    """
    lam = alpha + math.hypot(alpha, omega0)
    return 1e-9 + (lam * dt) ** 4


#: Absolute allowance for the rounding of E_k in the tilted trap, in units of ω0² + |τ|:
#: φ = θ − 2πk carries up to ulp(2π·MAX_WELL) ≈ 3e-11 rad and |dE_k/dφ| ≤ ω0² + |τ|.
TILT_ROUNDING = 1e-10


def energy_cap(dt: float, alpha: float, omega0: float, torque: float = 0.0) -> float:
    """The trap level [rad² s⁻²] that every kernel is given (``energy_cap`` of the kernel
    contract, :mod:`atlas.kernels`), m = :func:`trap_margin`: 2ω0²(1 − m) for τ = 0 (as
    ever); for τ ≠ 0 the lower saddle energy relative to the well, ΔE = min(2κ + τ(π + 2θ*),
    2κ − τ(π − 2θ*)) (:attr:`atlas.physics.pendulum.Pendulum.saddle_energy`), as ΔE·(1 − m) −
    ``TILT_ROUNDING``·(ω0² + |τ|); −inf when that is ≤ 0 or |τ| ≥ ω0² (no well can be
    certified: nothing is trapped)."""
    if torque == 0.0:
        return 2.0 * omega0**2 * (1.0 - trap_margin(dt, alpha, omega0))
    p = Pendulum(alpha, omega0, torque)
    if not p.has_rest_states:
        return -math.inf
    cap = (p.saddle_energy * (1.0 - trap_margin(dt, alpha, omega0))
           - TILT_ROUNDING * (omega0**2 + abs(torque)))
    return cap if cap > 0.0 else -math.inf


@dataclass(frozen=True)
class RunningBarrier:
    """The running certificate a kernel tests (contract in :mod:`atlas.kernels`), built by
    :mod:`atlas.physics.running` for θ̈ = −ω0² sin θ − 2αθ̇ + τ.

    It is given in the frame of positive rotation (the τ > 0 pendulum of torque |τ|): a
    state (θ, θ̇) is certified running when, with u = σθ, w = σθ̇ and σ = ``direction``,
    w ≤ ``top`` and w ≥ ĝ(u), ĝ the linear interpolation of ``g`` (float64, M + 1 ≥ 2
    samples on the uniform grid u ∈ [theta0, theta0 + 2π], u reduced mod 2π). The kernels
    mirror it for τ < 0 themselves (σ = sign(τ)); :func:`label` checks that ``direction`` is
    sign(τ).

    theta0:    start of the barrier's period [rad].
    g:         the lower barrier θ̇ = ĝ(θ) [rad s⁻¹], M + 1 finite samples, g[M] ≥ g[0] (the
               region does not shrink across the seam θ0 + 2π ≡ θ0).
    top:       the upper level [rad s⁻¹], finite and above every g (e.g. (|τ| + ω0²)/2α,
               above which θ̇ decreases).
    direction: +1 or −1, the direction of rotation (sign of τ).

    The builder guarantees that the region {ĝ(u) ≤ w ≤ top} is forward-invariant for the
    exact flow (with the margins the RK4 orbit needs), holds the limit cycle and no rest
    state; the kernels only test membership.
    """

    theta0: float
    g: np.ndarray
    top: float
    direction: int

    def __post_init__(self) -> None:
        g = np.array(self.g, dtype=np.float64, copy=True)
        if g.ndim != 1 or g.size < 2:
            raise ValueError(f"RunningBarrier.g must be 1-D with at least 2 samples, got "
                             f"shape {g.shape}")
        if not np.all(np.isfinite(g)):
            raise ValueError("RunningBarrier.g must be finite")
        if not g[-1] >= g[0]:
            raise ValueError(f"RunningBarrier.g must end at or above its start (g[M] = "
                             f"{g[-1]!r} < g[0] = {g[0]!r})")
        for name in ("theta0", "top"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"RunningBarrier.{name} must be finite, got "
                                 f"{getattr(self, name)!r}")
        if not self.top > g.max():
            raise ValueError(f"RunningBarrier.top = {self.top!r} must lie above every g "
                             f"(max {g.max()!r})")
        if self.direction not in (1, -1):
            raise ValueError(f"RunningBarrier.direction must be +1 or -1, got "
                             f"{self.direction!r}")
        g.flags.writeable = False
        object.__setattr__(self, "g", g)
        object.__setattr__(self, "theta0", float(self.theta0))
        object.__setattr__(self, "top", float(self.top))
        object.__setattr__(self, "direction", int(self.direction))

    def kernel_args(self) -> tuple[float, np.ndarray, float]:
        """(running_theta0, running_g, running_top) of the kernel contract."""
        return self.theta0, self.g, self.top


@dataclass(frozen=True)
class LabelResult:
    """Per-orbit labels, arrays shaped like the broadcast initial conditions.

    attractor: int16, k of the attractor (the rest state (θ* + 2πk, 0), θ* = 0 when τ = 0);
               ``ATTRACTOR_FILL`` where not trapped.
    status:    int8, 0 trapped (certified), 1 unresolved (t_max reached), 2 nonfinite,
               4 running (certified to converge to the running limit cycle; τ ≠ 0 only).
    t_trap:    float32 [s], the time at which the trap, or the running certificate, was first
               seen (NaN if never).
    direction: int8, the direction of rotation where running (+1, −1: sign(τ)), 0 elsewhere.
               Optional when constructing (all 0).
    """

    attractor: np.ndarray
    status: np.ndarray
    t_trap: np.ndarray
    direction: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.direction is None:
            object.__setattr__(self, "direction",
                               np.zeros(np.shape(self.status), dtype=np.int8))


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
    check_method(method, backend)
    return method


def check_method(method: str, backend: str) -> None:
    """Refuse a discretisation ``method`` that ``backend`` has no kernel for (ValueError,
    one line): the CUDA kernels run "rk4" only."""
    if backend == "cuda" and method != "rk4":
        raise ValueError(f"method: {method!r} has no CUDA kernel; the cuda backend runs "
                         "'rk4' (set method: rk4, or run on the CPU)")


def _kernel(backend: str, kernel: str | None, method: str | None = None):
    method = resolve_method(backend, kernel, method)
    if backend == "cuda":
        from atlas.kernels.cuda_host import label_cuda

        return label_cuda
    if kernel == "straightforward":
        if method == "rk4":
            from atlas.kernels.rk4 import label_straightforward

            return label_straightforward
        from atlas.kernels.trigfree import label_trigfree_straightforward

        return label_trigfree_straightforward
    from atlas.kernels.lanes import label_lanes, label_trigfree

    return label_lanes if method == "rk4" else label_trigfree


def n_checks_for(t_max: float, dt: float, check_every: int) -> int:
    """Number of trap tests after the initial one: the run covers ⌈t_max/(c·dt)⌉·c steps."""
    return max(1, math.ceil(t_max / (dt * check_every) - 1e-9))


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


def check_running(running, torque: float, method: str = "rk4") -> None:
    """A running certificate must be a :class:`RunningBarrier` (or None) of direction
    sign(τ), τ ≠ 0 and method "rk4": TypeError, ValueError otherwise. The barrier's step
    allowance (:func:`atlas.physics.running.rk4_allowance`) is measured for classical RK4 only; the
    trig-free step's local error, with cos θ and sin θ drifting between re-synchronisations,
    is larger (up to several times that allowance at dt = 0.05), so nothing certifies it."""
    if running is None:
        return
    if not isinstance(running, RunningBarrier):
        raise TypeError(f"running must be a RunningBarrier or None, got "
                        f"{type(running).__name__}")
    if torque == 0.0 or running.direction != (1 if torque > 0 else -1):
        raise ValueError(f"running barrier of direction {running.direction:+d} given for "
                         f"torque = {torque:g}: it must be sign(torque)")
    if method != "rk4":
        raise ValueError(f"method {method!r}: the running certificate is established for "
                         "classical RK4 only (method 'rk4')")


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
    ``method`` picks the discretisation (:data:`atlas.kernels.METHODS`): "rk4" by default
    (RK4 with a sin per stage, also the CUDA backend's method), or "rk4-trigfree" (RK4 with
    cos θ, sin θ carried as state).
    ``kernel="straightforward"`` selects the plain one-orbit-per-thread CPU kernel of the
    method, "rk4" unless ``method`` says otherwise.
    ``torque`` τ [rad s⁻²] tilts the wells (module docstring); ``running`` (a
    :class:`RunningBarrier` for this α, ω0, τ, with ``direction`` = sign(τ)) enables the
    running certificate: such orbits get status RUNNING, ``direction`` sign(τ) and t_trap the
    time of certification. With τ = 0 and no barrier the kernels of earlier versions run and
    every array is bit-identical to theirs.
    Raises ValueError for settings that cannot give certified labels
    (:func:`check_integration`; a non-finite τ; a barrier whose direction is not sign(τ)) or
    initial conditions whose orbits may reach wells beyond |k| ≤ MAX_WELL
    (:func:`atlas.limits.check_reach`; with τ ≠ 0 the bound is the speed band times t_max);
    OverflowError if one does anyway.
    """
    torque = float(torque)
    check_integration(alpha, omega0, dt, t_max, check_every, torque)
    method = resolve_method(backend, kernel, method)
    check_running(running, torque, method)
    run = _kernel(backend, kernel, method)
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
