"""The basins of a parameter point as polygons: well 0's basin from its two boundaries, each
well's basin and the running basin within a window (shapely), for the Gaussian stability
(:mod:`atlas.stability.gaussian`) and the tipping probabilities (:mod:`atlas.stability.tipping`).

Every basin boundary is a translate of Γ, the two stable branches of one saddle joined at it
(:mod:`atlas.boundaries.exact`). Without torque Γ is read off the DOP853 dense output of the
left branch L (:class:`atlas.boundaries.manifold.StableManifold`), its right branch the point
reflection of L through (π, 0), at :data:`PIECES` points per sample interval of L (≤ 0.02 of arc
length): the chord error, measured at each chord's midpoint, is about 1e-7; with torque Γ is
:meth:`atlas.boundaries.tilted.TiltedBoundaries.curves`' polyline (chord error ≤ 1e-8). Well
0's basin is the strip between Γ and Γ − 2π (no running cycle), or the tongue inside Γ
(bistable: Γ turns back to the band's lower edge, upper for τ < 0). Units: θ [rad], θ̇
[rad s⁻¹], both as one unit in the plane ("rad-ish").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from atlas.boundaries.exact import ExactBoundaries, TiltedExact, UntiltedExact
from atlas.boundaries.manifold import StableManifold

__all__ = ["BasinShape", "basin_shape", "window_basins", "PIECES"]

#: Points per sample interval of L on the polyline of an untilted boundary.
PIECES = 8
_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class BasinShape:
    """Well 0's basin of one parameter point as a closed polygon (``theta``, ``theta_dot``),
    valid for |θ̇| < ``speed`` [rad s⁻¹] (where the boundaries were integrated), with its
    polyline's chord error and the reference error [rad-ish], and the boundary's length per
    unit of θ (for error bounds). ``rest_theta``: θ of well 0's rest state [rad]."""

    theta: np.ndarray
    theta_dot: np.ndarray
    speed: float
    chord_error: float
    reference_error: float
    rest_theta: float

    def shifted(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Well k's basin: the polygon translated by 2πk."""
        return self.theta + _TWO_PI * k, self.theta_dot


def _untilted_curve(boundaries: UntiltedExact, speed: float):
    """(θ, θ̇, chord error) of Γ through (π, 0), from L integrated past ``speed``."""
    m = StableManifold(boundaries.pendulum, speed)
    t = m.tau
    fine = np.append((t[:-1, None] + np.diff(t)[:, None] * np.arange(PIECES) / PIECES).ravel(),
                     t[-1])
    theta, theta_dot = m.at(fine)
    mid_t, mid_v = m.at(0.5 * (fine[1:] + fine[:-1]))
    from atlas.boundaries.segments import segment_distance

    chord = float(segment_distance(mid_t, mid_v, theta[:-1], theta_dot[:-1], theta[1:],
                                   theta_dot[1:]).max(initial=0.0))
    # L from its far end to the saddle, then its point reflection from the saddle outward
    left_t = np.append(theta[::-1], math.pi)
    left_v = np.append(theta_dot[::-1], 0.0)
    return (np.concatenate([left_t, 2.0 * math.pi - theta]),
            np.concatenate([left_v, -theta_dot]), chord)


def _tilted_curve(boundaries: TiltedExact):
    """(θ, θ̇, j) of Γ through the saddle s_j (the branches as integrated, no clipping)."""
    curves = boundaries.tilted.curves(clip=False)
    j0 = curves[0][0]
    branch = {name: (t, v) for j, name, t, v in curves if j == j0}
    (lt, lv), (rt, rv) = branch["left"], branch["right"]
    return np.concatenate([lt[::-1], rt[1:]]), np.concatenate([lv[::-1], rv[1:]]), j0


def basin_shape(boundaries: ExactBoundaries, speed: float | None = None) -> BasinShape:
    """Well 0's basin of ``boundaries`` (which must have rest states) as a polygon valid for
    |θ̇| < ``speed`` (without torque: integrated that far, default the window's |θ̇| + 2;
    with torque: the band the boundaries were integrated over, ValueError if ``speed`` asks
    for more)."""
    p = boundaries.pendulum
    if isinstance(boundaries, UntiltedExact):
        (_, _), (v0, v1) = boundaries.window
        speed = speed if speed is not None else max(abs(v0), abs(v1)) + 2.0
        theta, theta_dot, chord = _untilted_curve(boundaries, speed + 1.0)
        well_of_curve, strip = 0, True  # Γ through (π, 0) is well 0's upper boundary
    elif isinstance(boundaries, TiltedExact):
        tilted = boundaries.tilted
        band = min(-tilted.band[0], tilted.band[1]) - 1e-9
        if speed is not None and speed > band:
            raise ValueError(f"the boundaries reach |theta_dot| < {band:g}, not {speed:g}")
        speed = band if speed is None else speed
        theta, theta_dot, j = _tilted_curve(boundaries)
        chord = tilted.curves_chord_error
        strip = not tilted.bistable
        # the boundary of saddle j bounds well j + upper_well from below when a strip, and
        # holds well j + lower_well as a tongue
        well_of_curve = j + (boundaries.upper_well - 1 if strip else boundaries.lower_well)
        theta = theta - _TWO_PI * well_of_curve
    else:
        raise ValueError("a pendulum without rest states has no well basins")
    if strip:  # between Γ (upper, from its top end down) and Γ − 2π (lower, back up)
        theta = np.concatenate([theta, theta[::-1] - _TWO_PI])
        theta_dot = np.concatenate([theta_dot, theta_dot[::-1]])
    return BasinShape(theta, theta_dot, float(speed), float(chord),
                      float(boundaries.reference_error), float(p.rest_angle))


def window_basins(shape: BasinShape | None, window, ks, running: bool) -> dict[int, object]:
    """{k: well k's basin ∩ window} as shapely geometries for each k in ``ks``, and
    {RUNNING_SIDE: the rest of the window} (the running basin: empty without a cycle,
    ``running`` false; the whole window when ``shape`` is None: no rest state)."""
    import shapely

    from atlas.boundaries.basins import RUNNING_SIDE

    (a, b), (lo, hi) = window
    box = shapely.box(a, lo, b, hi)
    out = {}
    if shape is not None:
        well = shapely.make_valid(shapely.Polygon(np.column_stack((shape.theta,
                                                                    shape.theta_dot))))
        left, _, right, _ = well.bounds
        well = well.intersection(shapely.box(left, lo, right, hi))
        for k in ks:  # well k's basin in the window: well 0's in the window shifted by −2πk
            shift = _TWO_PI * int(k)
            piece = well.intersection(shapely.box(a - shift, lo, b - shift, hi))
            out[int(k)] = shapely.transform(piece, lambda xy, s=shift: xy + (s, 0.0))
    if not running:
        rest = shapely.Polygon()
    else:
        rest = box.difference(shapely.union_all(list(out.values()))) if out else box
    out[RUNNING_SIDE] = rest
    return out
