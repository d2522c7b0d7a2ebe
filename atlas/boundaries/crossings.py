"""Where the basin label changes along the axis θ0 = 0: each boundary's crossing of it.

Every basin boundary that meets the axis θ0 = 0 (inside the window or not, without torque;
inside it, with torque) crosses it at one initial speed θ̇0 [rad s⁻¹]. The exact boundary
predicts that speed — without torque the exact value of L at θ = −(|n| − 1)π
(:func:`axis_crossings`), with torque the exact branches' crossings of θ = 0
(:func:`tilted_crossings`) — and a shot to the saddle (:mod:`atlas.boundaries.shooting`),
or where that cannot certify it bisection along θ̇0 on certified RK4 labels
(:mod:`atlas.boundaries.bisection`), locates the label change to ``tol``: the crossing of the
RK4 map's boundary at step dt. Derivation: docs/design/separatrices.md.
"""

from __future__ import annotations

import numpy as np

from atlas.boundaries.bisection import (
    FIRST_BRACKET,
    Labeller,
    bisect_across,
    bisect_between,
    linger,
)
from atlas.boundaries.manifold import StableManifold
from atlas.boundaries.window import Window

__all__ = ["axis_crossings", "tilted_crossings", "PROBE"]

#: Half-width [rad s⁻¹] of the first bracket of a crossing with torque, and the distance at
#: which the exact sides on either side are read.
PROBE = 1e-3


def axis_crossings(m: StableManifold, saddles: np.ndarray, tol: float, dt: float,
                   backend: str, method: str):
    """θ̇0 [rad s⁻¹] where the stable manifold of each saddle nπ meets the axis θ0 = 0, the
    boundary between basins (n − 1)/2 below and (n + 1)/2 above.

    The branch arriving from the side of θ = 0 meets it: for n ≥ 1 the left branch of nπ, the
    left branch of π shifted by (n − 1)π, at θ̇ = L(−(n − 1)π); for n ≤ −1 the right branch,
    the reflection of L shifted by (n + 1)π, at θ̇ = −L((n + 1)π). The reference ``m`` gives L
    there (:meth:`~atlas.boundaries.manifold.StableManifold.extended` if it ends short of
    −(|n| − 1)π: a crossing may lie beyond the window's speeds); the crossing is shot to its
    saddle along the θ̇0 axis (:class:`atlas.boundaries.shooting.Shooter`, its Newton estimate
    stored) or, where that cannot certify it (or for a method the shots do not integrate),
    bisected along the axis on certified labels, with t_max covering the travel time to the
    saddle. Returns (θ̇0, bracket width, k above, the labeller, the orbits shot)."""
    from atlas.boundaries.shooting import Shooter, left_to_labels

    u = -(np.abs(saddles) - 1) * np.pi
    if u.size:
        m = m.extended(float(u.min()))
    travel = m.tau_at(u) if u.size else np.zeros(0)
    labels = Labeller(m.pendulum, dt, travel.max(initial=0.0) + linger(m.pendulum, tol),
                      backend, method)
    predicted = np.sign(saddles) * m.at(travel)[1]
    base = np.column_stack([np.zeros(saddles.size), predicted])
    up = np.broadcast_to([0.0, 1.0], base.shape)
    k_above = (saddles + 1) // 2
    shooter = Shooter(m.pendulum, tol, dt=dt, t_max=labels.t_max, method=method)
    lo, hi, ok, at = shooter.refine(base, np.ascontiguousarray(up), np.zeros(saddles.size),
                                    saddles * np.pi)
    for bad, centre, half_width in left_to_labels(ok, at, tol):
        b_lo, b_hi = bisect_across(labels, base[bad] + centre[:, None] * up[bad], up[bad],
                                   k_above[bad], tol=tol, half_width=half_width, strict=False)
        lo[bad], hi[bad] = centre + b_lo, centre + b_hi
    at = np.where(ok, at, 0.5 * (lo + hi))
    return predicted + at, hi - lo, k_above, labels, shooter.shots


def tilted_crossings(exact, labels, shooter, window: Window, tol: float):
    """With torque: where the label changes along the axis θ0 = 0 in the window — the exact
    polylines' crossings of θ = 0 (``exact``: :class:`atlas.boundaries.tilted.TiltedBoundaries`,
    its :meth:`~atlas.boundaries.tilted.TiltedBoundaries.axis_speeds`), each located along θ̇
    by ``shooter`` (:class:`atlas.boundaries.shooting.Shooter`: the stable manifold of
    whichever saddle the shot reaches crosses the bracket; the crossing is its Newton
    estimate, inside the bracket) or, where that cannot certify it, bisected on the certified RK4
    labels of ``labels``. Returns (θ̇0, bracket width, basin below, basin above;
    :data:`atlas.boundaries.exact.RUNNING_SIDE` for the running basin)."""
    speeds = exact.axis_speeds()
    speeds = np.sort(speeds[(window.theta_dot[0] < speeds) & (speeds < window.theta_dot[1])])
    empty = np.zeros(0)
    if (window.theta[0] > 0.0 or window.theta[1] < 0.0) or not speeds.size:
        return empty, empty, empty.astype(np.int64), empty.astype(np.int64)
    base = np.column_stack([np.zeros(speeds.size), speeds])
    up = np.column_stack([np.zeros(speeds.size), np.ones(speeds.size)])
    below = exact.side(np.zeros(speeds.size), speeds - PROBE)
    above = exact.side(np.zeros(speeds.size), speeds + PROBE)
    # shot from the exact crossing, to whichever saddle the orbit reaches (each saddle's
    # stable manifold is a basin boundary)
    lo, hi, ok, at = shooter.refine(base, up, np.zeros(speeds.size),
                                    np.full(speeds.size, np.nan))
    at = np.where(ok, at, np.nan)
    # else from the exact crossing ± FIRST_BRACKET·tol, widened as needed (the RK4 map's
    # boundary lies ≈ 1e-9 from it); a crossing that fails so is bisected again from ±PROBE
    for half_width in (FIRST_BRACKET * tol, PROBE):
        again = np.flatnonzero(~ok)
        if again.size:
            lo[again], hi[again], ok[again] = bisect_between(
                labels, base[again], up[again], below[again], above[again], tol=tol,
                half_width=half_width)
    return speeds + np.where(np.isnan(at), 0.5 * (lo + hi), at), hi - lo, below, above
