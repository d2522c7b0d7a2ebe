"""The minimal fatal shock of each attractor: the smallest kick (Δθ, Δθ̇) that leaves its
basin (Halekotte & Feudel, "Minimal fatal shocks in multistable complex networks", Sci. Rep.
10, 11783, 2020, doi:10.1038/s41598-020-68805-6; Attractors.jl ``minimal_fatal_shock``).

It is the Euclidean (θ, θ̇) distance from the rest state (θ* + 2πk, 0) to the nearest point of
its basin boundary (the metric of ``boundary_distance``, θ and θ̇ as one unit), and that
point: :meth:`atlas.boundaries.exact.ExactBoundaries.nearest_point` of the rest state, exact
to the boundaries' own error (without torque ≈ 1e-13, Newton's method on the DOP853 dense
output; with torque exact for the dense output, its error the change from rtol 1e-12). The
shock is not limited to the window. By the 2π-periodicity of θ it is the same for every k,
its point translated by 2πk. The running limit cycle's (where there is one) is the
smallest kick from any of its points: the nearest pair of a point of the cycle and a point of
a basin boundary (:meth:`atlas.boundaries.tilted.TiltedBoundaries.running_shock`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ["FatalShock", "RunningShock", "minimal_fatal_shock", "running_fatal_shock"]


class FatalShock(NamedTuple):
    """distance [rad-ish]; theta [rad], theta_dot [rad s⁻¹]: the nearest boundary point of
    well 0's rest state; error [rad-ish]."""

    distance: float
    theta: float
    theta_dot: float
    error: float


def minimal_fatal_shock(boundaries) -> FatalShock:
    """The minimal fatal shock of well 0's rest state (θ*, 0) (module docstring); NaN where
    the pendulum has no rest state."""
    p = boundaries.pendulum
    if not p.has_rest_states:
        return FatalShock(math.nan, math.nan, math.nan, math.nan)
    distance, theta, theta_dot, error = boundaries.nearest_point(p.rest_angle, 0.0)
    return FatalShock(float(distance), float(theta), float(theta_dot), float(error))


class RunningShock(NamedTuple):
    """distance [rad-ish]; theta [rad], theta_dot [rad s⁻¹]: the point of the running limit
    cycle the smallest kick leaves from; target_theta, target_theta_dot: the boundary point
    it reaches; error [rad-ish]."""

    distance: float
    theta: float
    theta_dot: float
    target_theta: float
    target_theta_dot: float
    error: float


def running_fatal_shock(boundaries) -> RunningShock:
    """The minimal fatal shock of the running limit cycle: the smallest kick from any point
    of the cycle onto a basin boundary (the nearest pair of points of the cycle and of the
    boundaries, :meth:`atlas.boundaries.exact.ExactBoundaries.running_shock`); NaN where
    there is no running cycle, or no rest state to tip into."""
    return RunningShock(*(float(x) for x in boundaries.running_shock()))
