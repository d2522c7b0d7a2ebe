"""The energy trap: the level below which an orbit of the RK4 map never leaves its well.

Well k (the strip between its two saddles, −π − θ* ≤ θ − 2πk < π − θ*, θ* = arcsin(τ/ω0²))
has the energy E_k above its rest state with dE_k/dt = −2αθ̇² ≤ 0 for the exact flow
(:meth:`atlas.physics.pendulum.Pendulum.energy`), and {E_k < c} is a disc around the rest state
bounded away from both saddles while c is below the lower saddle's energy
(:attr:`~atlas.physics.pendulum.Pendulum.saddle_energy`; 2ω0² when τ = 0). The numerical orbit
may gain what RK4's error adds, so the level is lowered by the relative margin m
(:func:`trap_margin`), measured rather than proven (``tests/labels/test_labels.py``), and, with a
torque, by the rounding of E_k (:func:`energy_cap`). Kernels test the trap every
:data:`CHECK_EVERY` steps (:func:`n_checks_for` tests per run). For |τ| ≥ ω0² there is no
well and nothing is trapped. The kernels' side of the test: :mod:`atlas.kernels`.
"""

from __future__ import annotations

import math

from atlas.physics.pendulum import Pendulum

__all__ = ["CHECK_EVERY", "TILT_ROUNDING", "trap_margin", "energy_cap", "n_checks_for"]

#: Steps between two trap tests in the fast kernels (trapping times are resolved to this).
CHECK_EVERY = 16

#: Absolute allowance for the rounding of E_k in the tilted trap, in units of ω0² + |τ|:
#: φ = θ − 2πk carries up to ulp(2π·MAX_WELL) ≈ 3e-11 rad and |dE_k/dφ| ≤ ω0² + |τ|.
TILT_ROUNDING = 1e-10


def trap_margin(dt: float, alpha: float, omega0: float) -> float:
    """Relative safety margin m of the energy trap, dimensionless.

    RK4's local energy error per step is bounded by C(λ·dt)⁵·E with λ the fastest
    linearised rate of the system, u2 = α + √(α² + ω0²) (the saddle's stable rate, which
    bounds |r1|, |r2| of the attractors too) and C ≈ 1/120; over the 2π/(λ·dt) steps of one
    oscillation that accumulates to ≈ 0.05(λ·dt)⁴·E, while damping removes energy every
    period. m = 10⁻⁹ + (λ·dt)⁴ covers that accumulation twenty-fold (m ≈ 1.6e-8 at the
    default dt = 0.01, α = 0.1, ω0 = 1). ``tests/labels/test_labels.py`` measures the largest
    energy rise along computed orbits near the separatrix energy, for both methods ("rk4" and
    "rk4-trigfree"), and checks it stays below 5 % of m·2ω0².
    """
    lam = alpha + math.hypot(alpha, omega0)
    return 1e-9 + (lam * dt) ** 4


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


def n_checks_for(t_max: float, dt: float, check_every: int) -> int:
    """Number of trap tests after the initial one: the run covers ⌈t_max/(c·dt)⌉·c steps."""
    return max(1, math.ceil(t_max / (dt * check_every) - 1e-9))
