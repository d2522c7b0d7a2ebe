"""The basins of a parameter point as polygons: well 0's basin from its two boundaries, each
well's basin and the running basin within a window (shapely), for the Gaussian stability
(:mod:`atlas.stability.gaussian`) and the tipping probabilities (:mod:`atlas.stability.tipping`).

Every basin boundary is a translate of Γ, the two stable branches of one saddle joined at it
(:mod:`atlas.boundaries.exact`). Without torque Γ is read off the DOP853 dense output of the
left branch L (:class:`atlas.boundaries.manifold.StableManifold`), its right branch the point
reflection of L through (π, 0), at 8 points per sample interval of L (≤ 0.02 of arc
length): the chord error, measured at each chord's midpoint, is about 1e-7; with torque Γ is
:meth:`atlas.boundaries.tilted.TiltedBoundaries.curves`' polyline (chord error ≤ 1e-8); both
are the exact boundaries' :meth:`~atlas.boundaries.exact.ExactBoundaries.basin_outline`. Well
0's basin is the strip between Γ and Γ − 2π (no running cycle), or the tongue inside Γ
(bistable: Γ turns back to the band's lower edge, upper for τ < 0). Units: θ [rad], θ̇
[rad s⁻¹], both as one unit in the plane ("rad-ish").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from atlas.boundaries.exact import ExactBoundaries

__all__ = ["BasinShape", "basin_shape", "window_basins"]
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


def basin_shape(boundaries: ExactBoundaries, speed: float | None = None) -> BasinShape:
    """Well 0's basin of ``boundaries`` (which must have rest states) as a polygon valid for
    |θ̇| < ``speed`` (without torque: integrated that far, default the window's |θ̇| + 2;
    with torque: the band the boundaries were integrated over, ValueError if ``speed`` asks
    for more)."""
    p = boundaries.pendulum
    outline = boundaries.basin_outline(speed)
    theta = outline.theta - _TWO_PI * outline.well
    theta_dot, speed, chord, strip = (outline.theta_dot, outline.speed, outline.chord_error,
                                      outline.strip)
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
