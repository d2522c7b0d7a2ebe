"""Basin stability under a Gaussian perturbation: the probability that a rest state kicked by
a normal (θ, θ̇) perturbation of standard deviations (σθ [rad], σθ̇ [rad s⁻¹]), independent,
lands in its own basin.

P = ∬_B φ((θ − θk)/σθ) φ(θ̇/σθ̇) / (σθ σθ̇) dθ dθ̇ over the exact basin B of rest state
(θk, 0) (:class:`atlas.stability.polygons.BasinShape`), by Green's theorem:
∬_B ∂F/∂θ dA = ∮_∂B F dθ̇ with F = Φ((θ − θk)/σθ) φ(θ̇/σθ̇)/σθ̇ (Φ, φ the standard normal
distribution and density), on the polygon of B ∩ a box of ±:data:`REACH` σ around the rest
state (the mass outside it is below 1e-30), each edge cut into pieces of at most σ/8 and
integrated by 8-point Gauss–Legendre (exact to rounding for pieces that short). The error:
the polygon's chord and reference errors times the boundary's length in the box times the
largest density 1/(2πσθσθ̇). The same for every k (the basins are 2π-translates). After
Menck et al., Nature Physics 9, 89 (2013) (uniform perturbations) and Schultz, Heitzig &
Kurths, Eur. Phys. J. Spec. Top. 223, 2593 (2014) (non-uniform ones).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["gaussian_stability", "REACH"]

#: Half-width of the integration box, in standard deviations.
REACH = 12.0
_NODES = 8


def _edges(geometry):
    """(x0, y0, x1, y1) of every edge of a shapely (multi)polygon's rings, exteriors
    counter-clockwise and holes clockwise."""
    from shapely.geometry.polygon import orient

    parts = getattr(geometry, "geoms", [geometry])
    rings = []
    for part in parts:
        if part.is_empty or part.geom_type != "Polygon":
            continue
        part = orient(part, 1.0)
        rings += [np.asarray(part.exterior.coords)]
        rings += [np.asarray(r.coords) for r in part.interiors]
    if not rings:
        return np.zeros((4, 0))
    return np.concatenate([np.vstack([r[:-1, 0], r[:-1, 1], r[1:, 0], r[1:, 1]])
                           for r in rings], axis=1)


def _green(edges, centre: float, sigma_theta: float, sigma_theta_dot: float) -> float:
    """∮ F dθ̇ over the edges (module docstring)."""
    from scipy.special import ndtr

    x0, y0, x1, y1 = edges
    longest = np.hypot((x1 - x0) / sigma_theta, (y1 - y0) / sigma_theta_dot)
    pieces = np.maximum(1, np.ceil(longest * 8.0)).astype(np.int64)
    start = np.repeat(np.cumsum(pieces) - pieces, pieces)
    s0 = (np.arange(pieces.sum()) - start) / np.repeat(pieces, pieces)
    s1 = s0 + 1.0 / np.repeat(pieces, pieces)
    x0, y0, x1, y1 = (np.repeat(c, pieces) for c in (x0, y0, x1, y1))
    node, weight = np.polynomial.legendre.leggauss(_NODES)
    total = 0.0
    for u, w in zip(0.5 * (node + 1.0), 0.5 * weight):
        s = s0 + u * (s1 - s0)
        x, y = x0 + s * (x1 - x0), y0 + s * (y1 - y0)
        f = ndtr((x - centre) / sigma_theta) * np.exp(-0.5 * (y / sigma_theta_dot) ** 2)
        total += w * float(np.sum(f * (s1 - s0) * (y1 - y0)))
    return total / (sigma_theta_dot * math.sqrt(2.0 * math.pi))


def gaussian_stability(shape, sigma_theta: float, sigma_theta_dot: float):
    """(P, error) for well 0's rest state of ``shape`` (a
    :class:`atlas.stability.polygons.BasinShape` valid past REACH σθ̇): module docstring."""
    import shapely

    if REACH * sigma_theta_dot >= shape.speed:
        raise ValueError(f"the basin is known for |theta_dot| < {shape.speed:g}, less than "
                         f"{REACH:g} sigma_theta_dot = {REACH * sigma_theta_dot:g}")
    c = shape.rest_theta
    box = shapely.box(c - REACH * sigma_theta, -REACH * sigma_theta_dot,
                      c + REACH * sigma_theta, REACH * sigma_theta_dot)
    polygon = shapely.make_valid(shapely.Polygon(np.column_stack((shape.theta,
                                                                   shape.theta_dot))))
    inside = polygon.intersection(box)
    value = _green(_edges(inside), c, sigma_theta, sigma_theta_dot)
    length = shapely.LineString(np.column_stack((shape.theta, shape.theta_dot))) \
        .intersection(box).length
    peak = 1.0 / (2.0 * math.pi * sigma_theta * sigma_theta_dot)
    error = (shape.chord_error + shape.reference_error) * length * peak + 1e-14
    return float(value), float(error)
