"""The bifurcations of θ̈ = −ω0² sin θ − 2αθ̇ + τ that a stability study marks, each located
to 1e-10 or better.

- The homoclinic torque τ_c(α, ω0) [rad s⁻²] (:func:`atlas.physics.running.homoclinic_threshold`,
  Brent's method on the saddle's unstable manifold by DOP853, ≈ 1e-11 relative): the running
  cycle exists for |τ| > τ_c; ≈ 8αω0/π as α → 0 (Melnikov; Strogatz, *Nonlinear Dynamics
  and Chaos*, §8.5). Along a damping axis at fixed τ the same curve read the other way is the
  homoclinic damping α_c(τ, ω0): τ_c(α_c) = |τ| (:func:`homoclinic_damping`, Brent's method on
  α; τ_c increases with α).
- The saddle-node torque |τ| = ω0², where the rest states and saddles meet and vanish.
- The focus–node damping α_fn = (ω0⁴ − τ²)^(1/4) [s⁻¹]: the rest state's eigenvalues
  −α ± √(α² − ω0² cos θ*) turn real (the essay's α = ω0 without torque), in closed form.
"""

from __future__ import annotations

import math

__all__ = ["homoclinic_torque", "homoclinic_damping", "saddle_node_torque",
           "focus_node_damping", "at_saddle_node", "SADDLE_NODE_ROUNDING"]


def homoclinic_torque(alpha: float, omega0: float) -> float:
    """τ_c [rad s⁻²] (module docstring; ω0² where the cycle is born at the saddle-node)."""
    from atlas.physics.running import homoclinic_threshold

    return float(homoclinic_threshold(alpha, omega0))


def homoclinic_damping(torque: float, omega0: float, alpha_lo: float, alpha_hi: float):
    """α_c [s⁻¹] in [alpha_lo, alpha_hi] where τ_c(α_c, ω0) = |τ|, to 1e-12 relative, or None
    where the curve does not cross that range (or τ = 0, which has no running cycle)."""
    from scipy.optimize import brentq

    if torque == 0.0 or abs(torque) >= omega0**2:
        return None

    def gap(alpha):
        return homoclinic_torque(alpha, omega0) - abs(torque)

    lo, hi = gap(alpha_lo), gap(alpha_hi)
    if lo == 0.0:
        return alpha_lo
    if hi == 0.0:
        return alpha_hi
    if (lo > 0) == (hi > 0):
        return None
    return float(brentq(gap, alpha_lo, alpha_hi, xtol=1e-13 * alpha_hi, rtol=1e-13))


def saddle_node_torque(omega0: float) -> float:
    """ω0² [rad s⁻²]: for |τ| ≥ ω0² there is no rest state."""
    return omega0 * omega0


def focus_node_damping(omega0: float, torque: float) -> float:
    """(ω0⁴ − τ²)^(1/4) [s⁻¹]: the rest state is a focus below it, a node above it; NaN where
    there is no rest state (|τ| ≥ ω0²)."""
    stiffness = omega0**4 - torque * torque
    return math.sqrt(math.sqrt(stiffness)) if stiffness > 0.0 else math.nan


#: Relative distance from ω0² within which a torque is the saddle-node: its rounding (a range
#: {start: 0, stop: 1.2, num: 7} holds 0.9999999999999999 for 1).
SADDLE_NODE_ROUNDING = 1e-13


def at_saddle_node(omega0: float, torque: float) -> bool:
    """Whether the point is the saddle-node |τ| = ω0², exactly or within its rounding
    (:data:`SADDLE_NODE_ROUNDING`): its values are NaN (no certified boundaries)."""
    return abs(abs(torque) - omega0 * omega0) <= SADDLE_NODE_ROUNDING * omega0 * omega0
