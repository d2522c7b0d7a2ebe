"""The predictor of a trace without torque: vertices on the exact stable manifold, and copies.

Every boundary of the untilted pendulum is a 2π copy of L, the left branch of the saddle
(π, 0), or of R = −L, the right branch of (−π, 0). :func:`predict` walks L's DOP853 dense
output (:class:`atlas.boundaries.manifold.StableManifold`, rtol = atol = 1e-13) in reversed
time from the saddle (compiled: :func:`atlas.kernels.segments.walk`) with chords
≤ max_spacing and ≤ max_spacing/√κ (κ the curvature), so the
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

__all__ = ["Predicted", "reference", "edge_speeds", "window_boxes", "fine_spacing",
           "predict", "not_a_knot_spline", "sources",
           "copies", "needed", "place"]

_SPEED_GROWTH = 0.3  # max log-growth of the speed between vertices (near the saddle)
_CHORD_AIM = 0.9  # aim at this × the allowed chord (curvature varies along it)
_MAX_VERTICES = 1_000_000  # a branch 100 rad-ish long at MIN_MAX_SPACING
#: Vertices across a window's shorter side (:func:`fine_spacing`).
_WINDOW_VERTICES = 16


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


def window_boxes(m: StableManifold, window: Window) -> list:
    """The window's copies in the frame of L (the left branch of π) that L can meet: for the
    left branch of π's copies the window shifted by −2πj, for the right branch of −π's (the
    reflection of L) the reflected window shifted by −2πj; as ((θ0, θ1), (v0, v1))."""
    turn, out = 2.0 * math.pi, []
    lo_theta, hi_theta = float(m.theta.min()) - 1.0, math.pi + 1.0
    frames = {"left": (window.theta, window.theta_dot),
              "right": ((-window.theta[1], -window.theta[0]),
                        (-window.theta_dot[1], -window.theta_dot[0]))}
    for b in sources(window):
        (t0, t1), (v0, v1) = frames[b]
        if v1 <= 0.0:
            continue
        for j in range(math.floor((t0 - hi_theta) / turn), math.ceil((t1 - lo_theta) / turn) + 1):
            out.append(((t0 - turn * j, t1 - turn * j), (v0, v1)))
    return out


def fine_spacing(window: Window) -> float:
    """The vertex spacing [rad-ish] within a window: 1/:data:`_WINDOW_VERTICES` of its
    shorter side, so that any boundary crossing it has vertices inside (the configured
    max_spacing is the spacing elsewhere, and wherever it is the finer one)."""
    return min(window.theta[1] - window.theta[0],
               window.theta_dot[1] - window.theta_dot[0]) / _WINDOW_VERTICES


def predict(m: StableManifold, edges: list[float], max_spacing: float, boxes=(),
            fine: float = math.inf) -> Predicted:
    """Vertices along L, the left branch of π, walking the dense output of ``m`` in reversed
    time from the saddle to its end: chords ≤ ``max_spacing`` and ≤ max_spacing/√κ, the step
    in τ also limited by the growth of the speed |f| near the saddle (from max_spacing/10 at
    the saddle), and an extra vertex at every crossing of a speed in ``edges`` (bisection on
    the smooth dense output). Where ``fine`` [rad-ish] is smaller than that spacing, the
    chords near the ``boxes`` (:func:`window_boxes`) shrink to it: no longer than half the
    distance to the nearest box outside them (so a zoom costs a few dozen vertices per
    decade of scale), ``fine`` inside; and the straight piece between the saddle and the
    reference's first point gets vertices ``fine`` apart where a box holds it (a zoom into
    the saddle)."""
    from atlas.kernels.segments import walk

    p = m.pendulum
    u2 = -p.saddle_eigenvalues()[1]
    refine = bool(boxes) and fine < max_spacing
    first = 0.1 * (min(max_spacing, fine) if refine else max_spacing)
    tau = min(max(0.0, math.log(first / START_DISTANCE) / u2), m.tau_end)
    straight = _straight(m, boxes, fine, u2) if refine and tau == 0.0 else []
    sol = m._sol
    rows = np.array([(t0, t1, v0, v1) for (t0, t1), (v0, v1) in boxes] if refine else
                    np.zeros((0, 4)), float).reshape(-1, 4)
    taus, ok = walk(sol.t, sol.t_old, sol.h, sol.y_old, sol.F, tau, float(m.tau_end),
                    float(max_spacing), p.alpha, p.omega0, p.torque, rows, float(fine),
                    _CHORD_AIM, _SPEED_GROWTH, _MAX_VERTICES - len(straight))
    if not ok:
        raise SeparatrixError(f"the stable manifold needs more than {_MAX_VERTICES} "
                              "vertices; raise separatrices.max_spacing or shrink the window")
    theta, theta_dot = m.at(taus)
    # an extra vertex wherever a chord crosses a θ̇ edge (bisection on the dense output)
    extra = [m.speed_crossing(v, taus[i], taus[i + 1]) for v in edges
             if (i := np.flatnonzero((theta_dot[:-1] - v) * (theta_dot[1:] - v) < 0)).size]
    if extra:
        taus = np.concatenate([taus, *extra])
        taus = taus[np.argsort(taus, kind="stable")]
        theta, theta_dot = m.at(taus)
    arr = np.column_stack([theta, theta_dot, taus])
    if straight:
        arr = np.concatenate([np.array(straight, float), arr])
    return Predicted(1, "left", arr[:, 0], arr[:, 1], arr[:, 2], np.arange(arr.shape[0]))


def _straight(m: StableManifold, boxes, fine: float, u2: float) -> list:
    """Vertices on the straight piece of L from the saddle (π, 0) to its first integrated
    point (the stable eigenvector, exact to O(START_DISTANCE²)), ``fine`` apart where it runs
    through a box: (θ, θ̇, τ) with τ = ln(s/START_DISTANCE)/u2 ≤ 0, the linear flow's
    reversed time, at distance s from the saddle."""
    if not fine < START_DISTANCE:
        return []
    ex, ev = m.start[0] - math.pi, m.start[1]
    s = np.arange(fine, START_DISTANCE, fine)[:_MAX_VERTICES]
    theta, theta_dot = math.pi + s / START_DISTANCE * ex, s / START_DISTANCE * ev
    near = np.zeros(s.size, bool)
    for (t0, t1), (v0, v1) in boxes:
        dx = np.maximum(np.maximum(t0 - theta, 0.0), theta - t1)
        dy = np.maximum(np.maximum(v0 - theta_dot, 0.0), theta_dot - v1)
        near |= np.hypot(dx, dy) <= fine
    tau = np.log(s / START_DISTANCE) / u2
    return [(float(a), float(b), float(c)) for a, b, c in zip(theta[near], theta_dot[near],
                                                              tau[near])]


def not_a_knot_spline(x: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The cubic spline through (x, y) (x increasing, at least 4 knots) with the not-a-knot
    end conditions (the third derivative continuous at the second and the second-to-last
    knot; de Boor, *A Practical Guide to Splines*, ch. IV), evaluated at ``at`` within
    [x[0], x[-1]]: scipy's ``CubicSpline(x, y)`` to rounding. The slopes m at the knots solve
    the usual tridiagonal system (banded LU with partial pivoting, as scipy's: the end rows
    are not diagonally dominant)."""
    from scipy.linalg import solve_banded

    n = x.size
    dx = np.diff(x)
    slope = np.diff(y) / dx
    bands = np.zeros((3, n))  # the super-diagonal, the diagonal, the sub-diagonal
    rhs = np.empty(n)
    bands[1, 1:-1] = 2.0 * (dx[:-1] + dx[1:])
    bands[0, 2:] = dx[:-1]
    bands[2, :-2] = dx[1:]
    rhs[1:-1] = 3.0 * (dx[1:] * slope[:-1] + dx[:-1] * slope[1:])
    d = x[2] - x[0]
    bands[1, 0], bands[0, 1] = dx[1], d
    rhs[0] = ((dx[0] + 2.0 * d) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d
    d = x[-1] - x[-3]
    bands[1, -1], bands[2, -2] = dx[-2], d
    rhs[-1] = (dx[-1] ** 2 * slope[-2] + (2.0 * d + dx[-1]) * dx[-2] * slope[-1]) / d
    m = solve_banded((1, 1), bands, rhs, overwrite_ab=True, overwrite_b=True,
                     check_finite=False)
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
