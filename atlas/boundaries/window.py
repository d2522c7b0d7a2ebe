"""The window of a trace: a rectangle of the phase plane, θ [rad] × θ̇ [rad s⁻¹].

Exact (floats as given); checked on construction (finite, lo < hi). :func:`checked_window`
also checks a trace's settings against what double precision resolves in it
(:func:`atlas.limits.check_separatrix_settings`) before any work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from atlas.limits import check_separatrix_settings
from atlas.physics.pendulum import Pendulum

__all__ = ["Window", "checked_window"]


@dataclass(frozen=True)
class Window:
    """Rectangle θ ∈ [theta[0], theta[1]] [rad], θ̇ ∈ [theta_dot[0], theta_dot[1]] [rad s⁻¹]."""

    theta: tuple[float, float]
    theta_dot: tuple[float, float]

    def __post_init__(self) -> None:
        for name, (lo, hi) in (("theta", self.theta), ("theta_dot", self.theta_dot)):
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ValueError(f"{name} window must be finite with lo < hi, got {(lo, hi)!r}")

    def margin(self, theta, theta_dot):
        """Distance inside the window along the axes (≥ 0 inside, < 0 outside)."""
        return np.minimum(
            np.minimum(theta - self.theta[0], self.theta[1] - theta),
            np.minimum(theta_dot - self.theta_dot[0], self.theta_dot[1] - theta_dot),
        )

    @property
    def speed(self) -> float:
        """Largest |θ̇| [rad s⁻¹] in the window."""
        return max(abs(self.theta_dot[0]), abs(self.theta_dot[1]))

    @property
    def box(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """((θmin, θmax), (θ̇min, θ̇max)): the window as
        :func:`atlas.boundaries.exact.exact_boundaries` takes it."""
        return self.theta, self.theta_dot


def checked_window(p: Pendulum, theta_window, theta_dot_window, tol: float,
                   max_spacing: float, dt: float) -> Window:
    """The window of a trace, once its settings are checked (ValueError, one line): α > 0,
    a finite dt > 0 [s], and ``tol``, ``max_spacing`` [rad-ish] that double precision and
    the curve can honour (:func:`atlas.limits.check_separatrix_settings`)."""
    if not p.alpha > 0.0:
        raise ValueError(
            "separatrices need alpha > 0: with alpha = 0 energy is conserved and no orbit ever "
            "settles, so there are no basins of attraction to bound")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a finite number > 0, got {dt!r}")
    check_separatrix_settings(theta_window, theta_dot_window, tol, max_spacing)
    return Window(tuple(map(float, theta_window)), tuple(map(float, theta_dot_window)))
