"""The predictor of a trace without torque: vertices on the exact stable manifold, and copies.

Every boundary of the untilted pendulum is a 2π copy of L, the left branch of the saddle
(π, 0), or of R = −L, the right branch of (−π, 0). :func:`predict` walks L's DOP853 dense
output (:class:`atlas.boundaries.manifold.StableManifold`, rtol = atol = 1e-13) in reversed
time from the saddle with chords ≤ max_spacing and ≤ max_spacing/√κ (κ the curvature), so the
polyline's chord error stays below max_spacing²/8; an extra vertex sits wherever the curve
crosses a θ̇ edge of the window. :func:`needed` keeps the stretch the window's copies use,
:func:`copies` and :func:`place` enumerate those copies. :func:`not_a_knot_spline` (de Boor,
*A Practical Guide to Splines*, ch. IV) interpolates bisection offsets between vertices.
Derivation: docs/design/separatrices.md.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from atlas.boundaries.manifold import StableManifold
from atlas.boundaries.window import Window
from atlas.errors import SeparatrixError
from atlas.physics.pendulum import START_DISTANCE, Pendulum
from atlas.store.separatrices import BRANCHES

__all__ = ["Predicted", "reference", "edge_speeds", "predict", "not_a_knot_spline", "sources",
           "copies", "needed", "place"]

_SPEED_GROWTH = 0.3  # max log-growth of the speed between vertices (near the saddle)
_CHORD_AIM = 0.9  # aim at this × the allowed chord (curvature varies along it)
_MAX_VERTICES = 1_000_000  # a branch 100 rad-ish long at MIN_MAX_SPACING


def reference(p: Pendulum, window: Window) -> StableManifold:
    """The exact left branch L of the saddle π, until its energy exceeds every energy in the
    window: the predictor of a trace and the reference of its check."""
    return StableManifold(p, window.speed)


@dataclass(frozen=True)
class Predicted:
    """Predicted vertices of one source branch: state (θ [rad], θ̇ [rad s⁻¹]), reversed time
    τ [s] from the first point of the reference
    (:class:`atlas.boundaries.manifold.StableManifold`) and index along the branch (0 its
    first vertex, next to the saddle)."""

    n: int
    branch: str
    theta: np.ndarray
    theta_dot: np.ndarray
    tau: np.ndarray
    vertex: np.ndarray

    def part(self, first: int, last: int) -> Predicted:
        """The vertices first..last (inclusive)."""
        cut = slice(first, last + 1)
        return Predicted(self.n, self.branch, self.theta[cut], self.theta_dot[cut],
                         self.tau[cut], self.vertex[cut])

    def reflected(self) -> Predicted:
        """The point reflection (θ, θ̇) → (−θ, −θ̇): the right branch of −π from the left
        branch of π, vertex by vertex."""
        return Predicted(-self.n, BRANCHES[1 - BRANCHES.index(self.branch)], -self.theta,
                         -self.theta_dot, self.tau, self.vertex)


def edge_speeds(window: Window) -> list[float]:
    """The speeds θ̇ > 0 at which L or its reflection R = −L crosses a θ̇ edge of the window."""
    return sorted({v for v in (*window.theta_dot, *(-x for x in window.theta_dot)) if v > 0})


def predict(m: StableManifold, edges: list[float], max_spacing: float) -> Predicted:
    """Vertices along L, the left branch of π, walking the dense output of ``m`` in reversed
    time from the saddle to its end: chords ≤ ``max_spacing`` and ≤ max_spacing/√κ, the step
    in τ also limited by the growth of the speed |f| near the saddle (from max_spacing/10 at
    the saddle), and an extra vertex at every crossing of a speed in ``edges`` (bisection on
    the smooth dense output)."""
    p = m.pendulum
    u2 = -p.saddle_eigenvalues()[1]
    tau = min(max(0.0, math.log(0.1 * max_spacing / START_DISTANCE) / u2), m.tau_end)
    y = m.at(tau)
    verts = [(*y, tau)]
    while tau < m.tau_end:
        if len(verts) > _MAX_VERTICES:
            raise SeparatrixError(f"the stable manifold needs more than {_MAX_VERTICES} "
                                  "vertices; raise separatrices.max_spacing or shrink the window")
        (f0, f1), (g0, g1) = p.field_jet(*y)
        speed = math.hypot(f0, f1)
        kappa = abs(f0 * g1 - f1 * g0) / speed**3  # curvature of the orbit [rad⁻¹]
        growth = abs(f0 * g0 + f1 * g1) / speed**2  # |d ln speed / d tau|
        h = max_spacing * min(1.0, 1.0 / math.sqrt(kappa)) if kappa > 0 else max_spacing
        span = min(_CHORD_AIM * h / speed, _SPEED_GROWTH / max(growth, 1e-300))
        while True:
            t = min(tau + span, m.tau_end)
            z = m.at(t)
            chord = math.hypot(z[0] - y[0], z[1] - y[1])
            if chord <= h:
                break
            span = (t - tau) * _CHORD_AIM * h / chord
        crossings = sorted(float(m.speed_crossing(v, tau, t))
                           for v in edges if (y[1] - v) * (z[1] - v) < 0)
        verts += [(*m.at(s), s) for s in crossings]
        verts.append((*z, t))
        tau, y = t, z
    arr = np.array(verts, float)
    return Predicted(1, "left", arr[:, 0], arr[:, 1], arr[:, 2], np.arange(arr.shape[0]))


def not_a_knot_spline(x: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The cubic spline through (x, y) (x increasing, at least 4 knots) with the not-a-knot
    end conditions (the third derivative continuous at the second and the second-to-last
    knot; de Boor, *A Practical Guide to Splines*, ch. IV), evaluated at ``at`` within
    [x[0], x[-1]]: scipy's ``CubicSpline(x, y)`` to rounding. The slopes m at the knots solve
    the usual tridiagonal system (dense here: a few hundred knots at most)."""
    n = x.size
    dx = np.diff(x)
    slope = np.diff(y) / dx
    a = np.zeros((n, n))
    rhs = np.empty(n)
    i = np.arange(1, n - 1)
    a[i, i - 1], a[i, i], a[i, i + 1] = dx[1:], 2.0 * (dx[:-1] + dx[1:]), dx[:-1]
    rhs[i] = 3.0 * (dx[1:] * slope[:-1] + dx[:-1] * slope[1:])
    d = x[2] - x[0]
    a[0, 0], a[0, 1] = dx[1], d
    rhs[0] = ((dx[0] + 2.0 * d) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d
    d = x[-1] - x[-3]
    a[-1, -1], a[-1, -2] = dx[-2], d
    rhs[-1] = (dx[-1] ** 2 * slope[-2] + (2.0 * d + dx[-1]) * dx[-2] * slope[-1]) / d
    m = np.linalg.solve(a, rhs)
    k = np.clip(np.searchsorted(x, at, side="right") - 1, 0, n - 2)
    h, u = dx[k], (at - x[k]) / dx[k]
    # cubic Hermite form on each interval
    return (y[k] * (1 - u) ** 2 * (1 + 2 * u) + y[k + 1] * u**2 * (3 - 2 * u)
            + h * (m[k] * u * (1 - u) ** 2 - m[k + 1] * u**2 * (1 - u)))


def sources(window: Window) -> list[str]:
    """The source branches whose copies can enter the window: the left branch of π (θ̇ > 0
    along it) if the window holds θ̇ > 0, the right branch of −π (θ̇ < 0) if it holds θ̇ < 0."""
    return [b for b, present in (("left", window.theta_dot[1] > 0.0),
                                 ("right", window.theta_dot[0] < 0.0)) if present]


def copies(theta: np.ndarray, theta_dot: np.ndarray, window: Window,
           reach: int) -> Iterator[tuple[int, np.ndarray]]:
    """The copies θ + 2πj of a source branch that enter the window: yields (j, mask) with
    mask = its vertices inside the window plus ``reach`` neighbours on either side of every
    inside run (the one just outside makes the polyline reach the window's edge)."""
    if theta.size == 0:
        return
    turn = 2.0 * math.pi
    for j in range(math.ceil((window.theta[0] - theta.max()) / turn),
                   math.floor((window.theta[1] - theta.min()) / turn) + 1):
        inside = window.margin(theta + turn * j, theta_dot) >= 0
        if inside.any():
            mask = inside.copy()
            for r in range(1, reach + 1):
                mask[r:] |= inside[:-r]
                mask[:-r] |= inside[r:]
            yield j, mask


def needed(g: Predicted, window: Window) -> Predicted:
    """The stretch of a grown source branch that its copies in the window use, with two
    vertices to spare at each end (the located points move by ≈ 1e-9 from the predicted)."""
    used = np.zeros(g.theta.size, bool)
    for _, mask in copies(g.theta, g.theta_dot, window, reach=2):
        used |= mask
    idx = np.flatnonzero(used)
    return g.part(int(idx[0]), int(idx[-1])) if idx.size else g.part(0, -1)  # -1: none


def place(run: np.ndarray, point: np.ndarray, window: Window):
    """The copies of the located source branches (``run`` 0, 1) that enter the window: each
    keeps its points inside the window and the one neighbour outside at either end of each
    inside run. Returns, per stored point, its index into the source arrays and the copy j
    (the shift 2πj [rad]): copy j of the left branch of π is the left branch of the saddle
    (1 + 2j)π, copy j of the right branch of −π the right branch of (−1 + 2j)π."""
    picks, copy = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for r in np.unique(run):
        src = np.flatnonzero(run == r)
        for j, keep in copies(point[src, 0], point[src, 1], window, reach=1):
            picks.append(src[keep])
            copy.append(np.full(int(keep.sum()), j))
    return np.concatenate(picks), np.concatenate(copy)
