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

Each is also read along the other axes, so that a study over any parameter marks it: the
homoclinic frequency ω0_c (τ_c(α, ω0_c) = |τ|, Brent's method on ω0; the running cycle
exists below it), the saddle-node frequency √|τ|, the focus–node torque √(ω0⁴ − α⁴) and the
focus–node frequency (α⁴ + τ²)^(1/4).
"""

from __future__ import annotations

import math

__all__ = ["homoclinic_torque", "homoclinic_damping", "homoclinic_omega0",
           "saddle_node_torque", "saddle_node_omega0", "focus_node_damping",
           "focus_node_torque", "focus_node_omega0", "at_saddle_node",
           "SADDLE_NODE_ROUNDING"]


def homoclinic_torque(alpha: float, omega0: float) -> float:
    """τ_c [rad s⁻²] (module docstring; ω0² where the cycle is born at the saddle-node)."""
    from atlas.physics.running import homoclinic_threshold

    return float(homoclinic_threshold(alpha, omega0))


def homoclinic_damping(torque: float, omega0: float, alpha_lo: float, alpha_hi: float):
    """α_c [s⁻¹] in [alpha_lo, alpha_hi] where τ_c(α_c, ω0) = |τ|, or None where the curve
    does not cross that range (or τ = 0, which has no running cycle). Brent's method solves
    to 1e-13 relative; the result is as good as τ_c, about 1e-11 relative."""
    if torque == 0.0 or abs(torque) >= omega0**2:
        return None
    return _crossing(lambda alpha: homoclinic_torque(alpha, omega0) - abs(torque),
                     alpha_lo, alpha_hi)


def homoclinic_omega0(alpha: float, torque: float, omega0_lo: float, omega0_hi: float):
    """ω0_c [rad s⁻¹] in [omega0_lo, omega0_hi] where τ_c(α, ω0_c) = |τ| (the running cycle
    exists for ω0 below it), or None where the curve does not cross that range (or τ = 0).
    As good as τ_c, about 1e-11 relative (Brent's method solves to 1e-13). Where the damping
    is strong (α ≳ 0.59ω0_c) τ_c = ω0² and ω0_c is the saddle-node's √|τ|: the cycle is born
    there."""
    if torque == 0.0:
        return None
    return _crossing(lambda omega0: homoclinic_torque(alpha, omega0) - abs(torque),
                     omega0_lo, omega0_hi)


def _crossing(gap, lo: float, hi: float):
    """The root of ``gap`` in [lo, hi] by Brent's method, 1e-13 relative, where its ends
    differ in sign (an end where it is 0), else None."""
    from scipy.optimize import brentq

    at_lo, at_hi = gap(lo), gap(hi)
    if at_lo == 0.0:
        return lo
    if at_hi == 0.0:
        return hi
    if (at_lo > 0) == (at_hi > 0):
        return None
    return float(brentq(gap, lo, hi, xtol=1e-13 * hi, rtol=1e-13))


def saddle_node_torque(omega0: float) -> float:
    """ω0² [rad s⁻²]: for |τ| ≥ ω0² there is no rest state."""
    return omega0 * omega0


def saddle_node_omega0(torque: float) -> float:
    """√|τ| [rad s⁻¹]: for ω0 ≤ √|τ| there is no rest state; NaN for τ = 0 (rest states at
    every ω0 > 0)."""
    return math.sqrt(abs(torque)) if torque != 0.0 else math.nan


def focus_node_damping(omega0: float, torque: float) -> float:
    """(ω0⁴ − τ²)^(1/4) [s⁻¹]: the rest state is a focus below it, a node above it; NaN where
    there is no rest state (|τ| ≥ ω0²)."""
    stiffness = omega0**4 - torque * torque
    return math.sqrt(math.sqrt(stiffness)) if stiffness > 0.0 else math.nan


def focus_node_torque(alpha: float, omega0: float) -> float:
    """√(ω0⁴ − α⁴) [rad s⁻²]: the rest state is a focus for |τ| below it, a node above it
    (up to ω0²); NaN where it is a node at every torque (α ≥ ω0)."""
    room = omega0**4 - alpha**4
    return math.sqrt(room) if room > 0.0 else math.nan


def focus_node_omega0(alpha: float, torque: float) -> float:
    """(α⁴ + τ²)^(1/4) [rad s⁻¹]: the rest state is a node for ω0 below it (down to √|τ|),
    a focus above it."""
    return math.sqrt(math.sqrt(alpha**4 + torque * torque))


#: Relative distance from ω0² within which a torque is the saddle-node: its rounding (a range
#: {start: 0, stop: 1.2, num: 7} holds 0.9999999999999999 for 1).
SADDLE_NODE_ROUNDING = 1e-13


def at_saddle_node(omega0: float, torque: float) -> bool:
    """Whether the point is the saddle-node |τ| = ω0², exactly or within its rounding
    (:data:`SADDLE_NODE_ROUNDING`): its values are NaN (no certified boundaries)."""
    return abs(abs(torque) - omega0 * omega0) <= SADDLE_NODE_ROUNDING * omega0 * omega0
