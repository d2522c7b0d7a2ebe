"""Separatrices, certified: the basin boundaries of the RK4 map, located by bisection.

The basin of the rest state (2πk, 0) is bounded by the stable manifolds of the saddles on either
side (essay §3, Figure 9). Each saddle nπ (n odd) has two branches:

* ``left``:  arriving with θ̇ > 0 from θ < nπ;
* ``right``: arriving with θ̇ < 0 from θ > nπ.

Along either branch E > 2ω0² and θ̇ ≠ 0, so every branch is a graph θ̇(θ), and the initial
conditions just above it (larger θ̇) reach well k = (n+1)/2 while those just below reach
k − 1 = (n−1)/2. That is the property the method uses.

Eq. (1) is invariant under θ → θ + 2π and under the point reflection (θ, θ̇) → (−θ, −θ̇). So
every left branch is a copy of L, the left branch of π: that of nπ is L shifted by (n − 1)π;
every right branch is a copy of R, the right branch of −π: that of nπ is R shifted by
(n + 1)π; and R = −L. Only L and R are located; every boundary in the window, from saddles
inside it or outside, is one of their copies.

This module locates the boundaries of the *RK4 map* at step dt — those that colour the basin
map — by bisection on its labels. The exact boundaries, the stable manifolds of eq. (1)
itself, are :mod:`atlas.boundaries.manifold`'s: they serve here as the predictor and as the check.

Method (:func:`trace`)
----------------------
1. *Predictor* (vertices on the exact manifold): L is integrated once by DOP853
   (:class:`atlas.boundaries.manifold.StableManifold`: from 10⁻⁷ along the stable eigenvector, essay
   eqs. 22, 24, rtol = atol = 10⁻¹³, dense output) until its energy exceeds every energy in
   the window. Vertices are taken along it, walking its dense output in reversed time from
   the saddle, with chords ≤ ``max_spacing`` and ≤ max_spacing/√κ (κ the curvature in
   rad⁻¹, from the vector field and its derivative along the flow,
   :meth:`atlas.physics.pendulum.Pendulum.field_jet`), so the chord error of the polyline stays below
   max_spacing²/8 everywhere; near the saddle the spacing grows geometrically from
   max_spacing/10. An extra vertex is placed wherever the curve crosses a θ̇ edge of the
   window (or of its reflection), found by Brent's method on the dense output. The
   predicted vertices of R are the point reflections of those of L. Only the stretch of each
   that its copies in the window use is kept.
2. *Corrector* (bisection on initial conditions): each predicted vertex is only a guess.
   Across the curve, along the normal of the vector field, certified labels of
   :func:`atlas.labels.labelling.label` at step ``dt`` bracket the boundary between basins k − 1 and k;
   the bracket is widened ×8 until its ends carry those labels, then shrunk by bisection (or
   multisection — several labels across each bracket in one kernel call — when few brackets
   are left), all vertices of both branches in one batch per call, until narrower than
   ``tol`` (:func:`bisect_across`, usable on its own with any labeller). The stored point is
   the bracket's midpoint, so the labels at ±tol across the curve differ. Two passes share
   the work (:func:`_locate`): every 8th vertex is bisected from ±32·tol to tol/8; a spline of
   those offsets predicts the others so well that their first bracket, ±0.45·tol, is usually
   final — two orbits per vertex (≈ 4.5 orbits per point in all at the default settings
   instead of ≈ 17).
   Orbits near the manifold linger ≈ ln(1/δ)/u1 at the saddle: t_max is the predictor's
   travel time plus 2(ln(1/tol) + 5)/u1, enough down to δ ≈ tol². An ``unresolved`` orbit is
   never taken as either side: bisection treats it as no information (such orbits are stuck
   at a floating-point fixed point next to the saddle, see :class:`_Labeller`; the attribute
   ``n_unresolved`` counts them); a bracket that cannot get below tol because of them (only
   for α ≳ 3ω0 at tol = 1e-12) is kept with its true ``bracket_width`` and reported in the
   ``warnings`` attribute.
   The located curve is the basin boundary of the RK4 scheme at step ``dt``, the same one that
   colours the basin map; it differs from the exact manifold by O(dt⁴).
3. *Symmetry check*: R is located on its own labels, not reflected from L. Its predicted
   vertices are the exact reflections of those of L, and the normal of the vector field is
   the same vector at both; the largest distance between a located point of R and the
   reflected located point of L is the attribute ``symmetry_error``, below tol when the
   labels respect the symmetry (at rounding level in practice: the bisection is symmetric
   too); above ``SYMMETRY_BOUND``·tol the summary carries a warning.
4. *Copies*: copy j of L is the left branch of the saddle (1 + 2j)π, copy j of R the right
   branch of (−1 + 2j)π, both shifted by 2πj. Each copy that enters the window is stored with
   its points inside it and the one neighbour outside at either end of each inside run, so the
   polylines reach the window's edges; ``vertex`` keeps the index along the source branch.
5. *Check against the exact manifold* (:func:`check_against_stable_manifold`): the distance
   from every stored point to the exact boundary it belongs to — the same DOP853 reference,
   its foot points by Newton's method on the dense output
   (:meth:`atlas.boundaries.manifold.StableManifold.foot_points`). Its maximum is the attribute
   ``discrepancy``: ≈ 6e-10 at α = 0.1, ω0 = 1, dt = 0.01 (≈ 7e-10 at α = 1 and α = 2),
   falling as dt⁴ — RK4's offset, not bisection error (tests/boundaries/test_separatrices.py checks it
   against Richardson's estimate). The predictor lies on that reference, but the located
   points do not: they come from the RK4 labels alone, so the check measures the RK4 map's
   boundary against the exact one. Above ``DISCREPANCY_BOUND`` = 10⁻⁸ the summary carries a
   warning. The same curve measures ``polyline_error``, the largest distance from the
   manifold to the polyline.

:func:`atlas.limits.check_separatrix_settings` rejects, before any work, a ``tol`` below what
double precision resolves in the window and a ``max_spacing`` finer than the curve is
accurate; what can still fail during a run raises :class:`SeparatrixError`, one line for the
user.

The crossing of every boundary in the window with the axis θ0 = 0 (the initial speed at which
the label changes there, inside the window or not) is located by the same bisection along the
θ̇0 axis, from the exact value of L at θ = −(|n| − 1)π (:func:`_axis_crossings`).

With a torque τ (0 < |τ| < ω0²) the point reflection is gone and the branches fold, so
:func:`trace_tilted` takes its vertices from the exact tilted boundaries of
:mod:`atlas.boundaries.tilted` and bisects every copy in the window on its own labels (the 2π shift is
checked on relocated copies); the schema is the same.

References: Nusse & Yorke, "A procedure for finding numerical trajectories on chaotic saddles",
Physica D 36 (1989) 137 (straddle orbits: bisection between initial conditions of different
fate); Krauskopf et al., "A survey of methods for computing (un)stable manifolds of vector
fields", Int. J. Bifurcation Chaos 15 (2005) 763 (growing a manifold from its linearisation);
Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5–6 (DOP853 and its dense output).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import xarray as xr

from atlas import defaults, lazy_dask  # noqa: F401 (lazy_dask installs itself)
from atlas.boundaries.manifold import START_DISTANCE, StableManifold, to_left_branch
from atlas.errors import SeparatrixError
from atlas.kernels import TRAPPED, UNRESOLVED
from atlas.labels.labelling import label
from atlas.limits import MAX_STEPS, check_separatrix_settings
from atlas.physics.pendulum import Pendulum

__all__ = [
    "trace",
    "SeparatrixError",
    "branches",
    "summary",
    "warnings",
    "bisect_across",
    "check_against_stable_manifold",
    "max_discrepancy",
    "ManifoldCheck",
    "NO_LABEL",
    "BRANCHES",
    "DISCREPANCY_BOUND",
    "SYMMETRY_BOUND",
]

#: Branch names, in the order of the ``branch`` flag values 0, 1.
BRANCHES = ("left", "right")
#: Largest accepted distance [rad-ish] between bisected points and the DOP853 manifold.
DISCREPANCY_BOUND = 1e-8
#: ``attractor`` of an orbit without a certified label, as seen by the bisection.
NO_LABEL = np.iinfo(np.int64).min
#: Largest accepted distance between the bisected right branch of −π and the point reflection of
#: the bisected left branch of π, in units of tol (expected: below 1, see :func:`_symmetry_error`).
SYMMETRY_BOUND = 4.0
_FIRST_BRACKET = 32.0  # initial half-width of a bracket, in units of tol
_GROW = 8.0  # widening factor while a bracket has equal labels at both ends
_MAX_BRACKET = 0.1  # no wider than this [rad-ish]: the predictor is far better than that
_BATCH = 64  # below this many orbits per kernel call, add multisection points
_MAX_SECTIONS = 7
_COARSE_STRIDE = 8  # every 8th vertex is bisected first, to tol/_COARSE_TOL
_COARSE_TOL = 8.0
_FINE_BRACKET = 0.45  # half-width of the other vertices' first bracket, in units of tol
_MAX_STALLS = 20  # rounds in a row without a certified label inside a bracket
_SPEED_GROWTH = 0.3  # predictor: max log-growth of the speed between vertices (near the saddle)
_CHORD_AIM = 0.9  # predictor: aim at this × the allowed chord (curvature varies along it)
_MAX_VERTICES = 1_000_000  # a branch 100 rad-ish long at MIN_MAX_SPACING
_SHIFT_STRIDE = 8  # with torque: every 8th vertex is located again on its 2π-shifted copy


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


def _normal(p: Pendulum, theta, theta_dot):
    """Unit normal (nθ, nθ̇) to the orbit through each point, oriented so that nθ̇ > 0.

    Along a branch θ̇ ≠ 0, so nθ̇ = |θ̇|/|f| > 0 is well defined; on the positive side lie the
    initial conditions of well k = (n+1)/2."""
    f0, f1 = p.field(theta, theta_dot)
    s = np.sign(f0) / np.hypot(f0, f1)
    return -f1 * s, f0 * s

# --------------------------------------------------------------------------- labels


class _Labeller:
    """Certified labels (:func:`atlas.labels.labelling.label`) with ``NO_LABEL`` where an orbit is not
    trapped — never taken as either side.

    Why orbits stay unresolved although t_max covers the lingering time ln(1/δ)/u1 down to
    δ ≈ 1e-24: an orbit that arrives at the saddle θs within |φ| < ulp(θs)/(2·dt·u1) of it
    (≈ 4e-13 for α = 2, ω0 = 1, θs = 3π, dt = 0.01) has RK4 increments dt·θ̇ below half an ulp
    of θ, so θ never changes again: a fixed point of the floating-point map. Bisection treats
    such samples as unknown and brackets around them (``unresolved`` counts them)."""

    def __init__(self, p: Pendulum, dt: float, t_max: float, backend: str = "cpu",
                 method: str = defaults.METHOD):
        # never more steps than an orbit may take (atlas.limits.MAX_STEPS)
        self.p, self.dt, self.backend, self.method = p, dt, backend, method
        self.t_max = min(t_max, 0.99 * MAX_STEPS * dt)
        self.orbits = self.unresolved = self.nonfinite = 0

    def __call__(self, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
        res = label(theta, theta_dot, alpha=self.p.alpha, omega0=self.p.omega0, dt=self.dt,
                    t_max=self.t_max, backend=self.backend, method=self.method)
        k, status = res.attractor.astype(np.int64), res.status
        self.orbits += theta.size
        self.unresolved += int(np.sum(status == UNRESOLVED))
        self.nonfinite += int(np.sum((status != TRAPPED) & (status != UNRESOLVED)))
        return np.where(status == TRAPPED, k, NO_LABEL)


# --------------------------------------------------------------------------- bisection


def bisect_across(
    labels,
    base: np.ndarray,
    direction: np.ndarray,
    k: np.ndarray,
    *,
    tol: float,
    half_width,
    target: float | None = None,
    strict: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Locate the boundary between basins k − 1 and k on the lines base + s·direction: a
    vectorised bracket multisection, usable on its own with any labeller.

    ``labels(theta, theta_dot) -> k`` maps arrays of points to integer labels, ``NO_LABEL``
    where a point has none (for :func:`trace`, certified RK4 labels, :class:`_Labeller`; any
    function that is k − 1 on one side of a curve and k on the other will do);
    ``base``, ``direction``: (N, 2) arrays [rad, rad s⁻¹]
    (s is in units of |direction|); ``k``: (N,) the basin on the +s side; ``half_width``: the
    first bracket is [−half_width, +half_width] (scalar or (N,)); ``target`` ≤ tol (default
    tol): the width aimed at, a bracket that stalls between target and tol is accepted.

    The bracket is widened ×8 while both ends lie on one side (label ≥ k or < k), then shrunk
    by multisection — M points across every bracket in one kernel call, M chosen to fill
    ``_BATCH`` orbits (plain bisection for many brackets: the least work), so the width falls
    by M + 1 per call — until narrower than ``target``.
    Samples without a certified label carry no information: the bracket keeps them inside,
    and a bracket that made no progress is sampled at fresh random positions next time (or,
    if already narrower than tol, accepted: the uncertified band is as narrow as it gets).
    Returns (s_lo, s_hi): certified label k − 1 at s_lo, k at s_hi, 0 < s_hi − s_lo < tol.
    Raises if the final ends do not carry exactly k − 1 and k (the bracket met a third basin)
    or, with ``strict``, if a bracket stalls ``_MAX_STALLS`` times while wider than tol (the
    band of uncertified orbits is wider than tol); without ``strict`` such a bracket is
    returned as it is, for the caller to report.
    """
    base = np.asarray(base, float).reshape(-1, 2)
    direction = np.asarray(direction, float).reshape(-1, 2)
    k = np.broadcast_to(np.asarray(k, np.int64), base.shape[:1])
    n = base.shape[0]
    lo, hi = np.full(n, np.nan), np.full(n, np.nan)
    lab_lo, lab_hi = np.zeros(n, np.int64), np.zeros(n, np.int64)
    if n == 0:
        return lo, hi

    def evaluate(idx, s):
        lab = labels(base[idx, 0] + s * direction[idx, 0], base[idx, 1] + s * direction[idx, 1])
        return lab, lab != NO_LABEL, lab >= k[idx]

    def fail(i, why):
        return SeparatrixError(f"separatrix point near ({base[i, 0]!r}, {base[i, 1]!r}) between "
                            f"basins {k[i] - 1} and {k[i]}: {why}")

    # Phase 1: a bracket, widened geometrically around s = 0. Each part holds distinct points.
    step = np.broadcast_to(np.asarray(half_width, float), (n,)).copy()
    everyone = np.arange(n)
    parts = [(everyone, -step), (everyone, step.copy())]
    while parts:
        lab, known, above = evaluate(np.concatenate([i for i, _ in parts]),
                                     np.concatenate([s for _, s in parts]))
        at = 0
        for i, s in parts:
            li, ki, ai = lab[at:at + i.size], known[at:at + i.size], above[at:at + i.size]
            at += i.size
            up = ki & ai & ~(hi[i] <= s)  # nearer to the curve than the known end on that side
            down = ki & ~ai & ~(lo[i] >= s)
            hi[i[up]], lab_hi[i[up]] = s[up], li[up]
            lo[i[down]], lab_lo[i[down]] = s[down], li[down]
        missing_lo, missing_hi = np.isnan(lo), np.isnan(hi)
        grown = missing_lo | missing_hi
        step[grown] *= _GROW
        if np.any(grown & (step > _MAX_BRACKET)):
            raise fail(int(np.argmax(grown & (step > _MAX_BRACKET))),
                       f"no certified bracket within {_MAX_BRACKET}")
        i_lo, i_hi = np.flatnonzero(missing_lo), np.flatnonzero(missing_hi)
        parts = [(i, s) for i, s in ((i_lo, np.nan_to_num(hi[i_lo]) - step[i_lo]),
                                     (i_hi, np.nan_to_num(lo[i_hi]) + step[i_hi])) if i.size]

    # Phase 2: multisection until narrower than tol.
    target = tol if target is None else target
    rng = np.random.default_rng(0)
    stalls = np.zeros(n, np.int64)
    while True:
        width = hi - lo
        # a bracket already narrower than tol is final at its first stall
        active = np.flatnonzero((width >= target) & (stalls <= _MAX_STALLS)
                                & ~((stalls > 0) & (width < tol)))
        if not active.size:
            break
        m = int(np.clip(_BATCH // active.size, 1, _MAX_SECTIONS))
        frac = np.broadcast_to(np.arange(1, m + 1) / (m + 1), (active.size, m)).copy()
        stalled = stalls[active] > 0
        frac[stalled] = np.sort(rng.uniform(0.05, 0.95, (int(stalled.sum()), m)), axis=1)
        s = lo[active, None] + (hi - lo)[active, None] * frac  # (A, m)
        lab, known, above = (x.reshape(-1, m) for x in evaluate(np.repeat(active, m), s.ravel()))
        up, down = known & above, known & ~above
        # the bracket becomes [last certified point below, first certified point above]
        first = np.where(up.any(axis=1), np.argmax(up, axis=1), m)
        below = down & (np.arange(m) < first[:, None])
        last = np.where(below.any(axis=1), m - 1 - np.argmax(below[:, ::-1], axis=1), -1)
        rows = np.arange(active.size)
        has_hi, has_lo = first < m, last >= 0
        hi[active[has_hi]] = s[rows[has_hi], first[has_hi]]
        lab_hi[active[has_hi]] = lab[rows[has_hi], first[has_hi]]
        lo[active[has_lo]] = s[rows[has_lo], last[has_lo]]
        lab_lo[active[has_lo]] = lab[rows[has_lo], last[has_lo]]
        stalls[active] = np.where(has_hi | has_lo, 0, stalls[active] + 1)
        stuck = (stalls > _MAX_STALLS) & (hi - lo >= tol)
        if strict and stuck.any():
            raise fail(int(np.argmax(stuck)), "no certified label inside a bracket of width "
                       f"{float(np.max((hi - lo)[stuck])):.1e}; the band of uncertified orbits "
                       "is wider than tol: raise tol")

    bad = (lab_lo != k - 1) | (lab_hi != k)
    if bad.any():
        i = int(np.argmax(bad))
        raise fail(i, f"the final bracket ends in basins {lab_lo[i]} and {lab_hi[i]}")
    return lo, hi


# --------------------------------------------------------------------------- predictor


def _reference(p: Pendulum, window: Window) -> StableManifold:
    """The exact left branch L of the saddle π, until its energy exceeds every energy in the
    window: the predictor of :func:`trace` and the reference of its check."""
    return StableManifold(p, window.speed)


@dataclass(frozen=True)
class _Predicted:
    """Predicted vertices of one source branch: state, reversed time τ from the first point
    of the reference (:class:`atlas.boundaries.manifold.StableManifold`) and index along the branch (0
    its first vertex, next to the saddle)."""

    n: int
    branch: str
    theta: np.ndarray
    theta_dot: np.ndarray
    tau: np.ndarray
    vertex: np.ndarray

    def part(self, first: int, last: int) -> _Predicted:
        """The vertices first..last (inclusive)."""
        cut = slice(first, last + 1)
        return _Predicted(self.n, self.branch, self.theta[cut], self.theta_dot[cut],
                          self.tau[cut], self.vertex[cut])

    def reflected(self) -> _Predicted:
        """The point reflection (θ, θ̇) → (−θ, −θ̇): the right branch of −π from the left
        branch of π, vertex by vertex."""
        return _Predicted(-self.n, BRANCHES[1 - BRANCHES.index(self.branch)], -self.theta,
                          -self.theta_dot, self.tau, self.vertex)


def _edge_speeds(window: Window) -> list[float]:
    """The speeds θ̇ > 0 at which L or its reflection R = −L crosses a θ̇ edge of the window."""
    return sorted({v for v in (*window.theta_dot, *(-x for x in window.theta_dot)) if v > 0})


def _predict(m: StableManifold, edges: list[float], max_spacing: float) -> _Predicted:
    """Vertices along L, the left branch of π, walking the dense output of ``m`` in reversed
    time from the saddle to its end: chords ≤ ``max_spacing`` and ≤ max_spacing/√κ, the step
    in τ also limited by the growth of the speed |f| near the saddle, and an extra vertex at
    every crossing of a speed in ``edges`` (bisection on the smooth dense output)."""
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
    return _Predicted(1, "left", arr[:, 0], arr[:, 1], arr[:, 2], np.arange(arr.shape[0]))


def _not_a_knot_spline(x: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
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


# --------------------------------------------------------------------------- check


@dataclass(frozen=True)
class ManifoldCheck:
    """Result of :func:`check_against_stable_manifold`.

    distance:       per point, the distance [rad-ish] to the DOP853 stable manifold.
    polyline_error: largest distance from the DOP853 manifold to the polyline through the
                    points, between consecutive vertices of each branch.
    """

    distance: np.ndarray
    polyline_error: float

    @property
    def discrepancy(self) -> float:
        return float(self.distance.max(initial=0.0))


def check_against_stable_manifold(ds: xr.Dataset) -> ManifoldCheck:
    """Recompute the check of a traced ``/separatrices`` group (see :func:`_check`) against
    the same reference: per-point distances to the DOP853 stable manifold, polyline error."""
    if float(ds.attrs.get("torque", 0.0)) != 0.0:
        raise ValueError("a /separatrices node with torque: its check is trace_tilted's "
                         "discrepancy, against atlas.boundaries.tilted (this one is the untilted manifold's)")
    p = Pendulum(float(ds.attrs["alpha"]), float(ds.attrs["omega0"]))
    window = Window(tuple(ds.attrs["theta_window"]), tuple(ds.attrs["theta_dot_window"]))
    return _check(_reference(p, window), ds["saddle_n"].values, ds["branch"].values,
                  ds["vertex"].values, ds["theta"].values, ds["theta_dot"].values)


def _check(m: StableManifold, saddle_n, branch, vertex, theta, theta_dot) -> ManifoldCheck:
    """Traced separatrix points against the exact stable manifolds of :mod:`atlas.boundaries.manifold`.

    Each point of the branch (n, left|right) is mapped into the frame of L, the left branch of
    π (:func:`atlas.boundaries.manifold.to_left_branch`, an isometry), and its distance to L is that of
    its foot point on ``m``'s dense output (:meth:`~atlas.boundaries.manifold.StableManifold.foot_points`,
    accurate to ≈ 1e-13). ``branch`` holds flag values (0 left, 1 right); ``vertex`` orders the
    points of a branch, and the polyline joins consecutive vertices only (a branch may leave the
    window and come back: the points in between are not stored); the manifold is sampled at 15
    points between the foot points of each pair, and their largest distance to the chord is
    ``polyline_error``.
    """
    saddle_n, branch, vertex = (np.asarray(a, np.int64) for a in (saddle_n, branch, vertex))
    theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
    if theta.size == 0:
        return ManifoldCheck(np.zeros(0), 0.0)
    x, v = to_left_branch(saddle_n, branch == 1, theta, theta_dot)
    t, distance = m.foot_points(x, v)

    # polyline: sample the manifold between consecutive vertices, distance to the chord
    order = np.lexsort((vertex, branch, saddle_n))
    same = ((np.diff(saddle_n[order]) == 0) & (np.diff(branch[order]) == 0)
            & (np.diff(vertex[order]) == 1))
    i0, i1 = order[:-1][same], order[1:][same]
    frac = np.linspace(0.0, 1.0, 17)[1:-1]
    ts = t[i0, None] + (t[i1] - t[i0])[:, None] * frac
    cx, cv = m.at(ts)
    ax, av, bx, bv = x[i0, None], v[i0, None], x[i1, None], v[i1, None]
    ex, ev = bx - ax, bv - av
    s = np.clip(((cx - ax) * ex + (cv - av) * ev) / (ex * ex + ev * ev), 0.0, 1.0)
    chord = np.hypot(ax + s * ex - cx, av + s * ev - cv)
    return ManifoldCheck(distance, float(chord.max(initial=0.0)))


# --------------------------------------------------------------------------- public API


def _require_damping(p: Pendulum) -> None:
    if not p.alpha > 0.0:
        raise ValueError(
            "separatrices need alpha > 0: with alpha = 0 energy is conserved and no orbit ever "
            "settles, so there are no basins of attraction to bound")


def _checked(p: Pendulum, theta_window, theta_dot_window, tol: float, max_spacing: float,
             dt: float) -> Window:
    """The window of a trace, once its settings are checked (ValueError, one line)."""
    _require_damping(p)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a finite number > 0, got {dt!r}")
    check_separatrix_settings(theta_window, theta_dot_window, tol, max_spacing)
    return Window(tuple(map(float, theta_window)), tuple(map(float, theta_dot_window)))


def _linger(p: Pendulum, tol: float) -> float:
    """Time [s] an orbit within δ of a stable manifold lingers at its saddle, ≈ ln(1/δ)/u1,
    with room for δ down to ≈ tol² and the fall into the well after it."""
    return 2.0 * (math.log(1.0 / tol) + 5.0) / p.saddle_eigenvalues()[0]


def _sources(window: Window) -> list[str]:
    """The source branches whose copies can enter the window: the left branch of π (θ̇ > 0
    along it) if the window holds θ̇ > 0, the right branch of −π (θ̇ < 0) if it holds θ̇ < 0."""
    return [b for b, present in (("left", window.theta_dot[1] > 0.0),
                                 ("right", window.theta_dot[0] < 0.0)) if present]


def _copies(theta: np.ndarray, theta_dot: np.ndarray, window: Window,
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


def _needed(g: _Predicted, window: Window) -> _Predicted:
    """The stretch of a grown source branch that its copies in the window use, with two
    vertices to spare at each end (the located points move by ≈ 1e-9 from the predicted)."""
    used = np.zeros(g.theta.size, bool)
    for _, mask in _copies(g.theta, g.theta_dot, window, reach=2):
        used |= mask
    idx = np.flatnonzero(used)
    return g.part(int(idx[0]), int(idx[-1])) if idx.size else g.part(0, -1)  # -1: none


def _axis_crossings(m: StableManifold, saddles: np.ndarray, tol: float, dt: float,
                    backend: str, method: str):
    """θ̇0 [rad s⁻¹] where the stable manifold of each saddle nπ meets the axis θ0 = 0, the
    boundary between basins (n − 1)/2 below and (n + 1)/2 above.

    The branch arriving from the side of θ = 0 meets it: for n ≥ 1 the left branch of nπ, the
    left branch of π shifted by (n − 1)π, at θ̇ = L(−(n − 1)π); for n ≤ −1 the right branch,
    the reflection of L shifted by (n + 1)π, at θ̇ = −L((n + 1)π). The reference ``m`` gives L
    there (:meth:`~atlas.boundaries.manifold.StableManifold.extended` if it ends short of −(|n| − 1)π: a
    crossing may lie beyond the window's speeds); the crossing is bisected along the θ̇0 axis
    on certified labels, with t_max covering the travel time to the saddle. Returns (θ̇0,
    bracket width, k above, the labeller)."""
    u = -(np.abs(saddles) - 1) * np.pi
    if u.size:
        m = m.extended(float(u.min()))
    travel = m.tau_at(u) if u.size else np.zeros(0)
    labels = _Labeller(m.pendulum, dt, travel.max(initial=0.0) + _linger(m.pendulum, tol),
                       backend, method)
    predicted = np.sign(saddles) * m.at(travel)[1]
    base = np.column_stack([np.zeros(saddles.size), predicted])
    k_above = (saddles + 1) // 2
    lo, hi = bisect_across(labels, base, np.broadcast_to([0.0, 1.0], base.shape), k_above,
                           tol=tol, half_width=_FIRST_BRACKET * tol, strict=False)
    return predicted + 0.5 * (lo + hi), hi - lo, k_above, labels


def _locate(labels, base, normal, k, run, tau, tol):
    """Bisect across every predicted vertex, in two passes that share the work.

    The offset s* of the label boundary from the predictor along the normal is a smooth
    function of the predictor's time τ (both curves are smooth; at dt = 0.01 s* ≲ 1e-9). Every
    ``_COARSE_STRIDE``-th vertex of each run (consecutive vertices with one ``run`` value; and
    its last) is bisected from a small first bracket, widened as needed, to tol/``_COARSE_TOL``;
    a cubic spline of those offsets over τ then predicts the others to ≈ tol/16, so their first
    bracket, ±0.45·tol around the prediction, is usually final: two labels per vertex. Returns
    (s_lo, s_hi) along ``normal``.
    """
    start = np.flatnonzero(np.diff(run, prepend=np.nan) != 0)
    stop = np.append(start[1:], run.size)[:start.size]
    coarse = np.zeros(run.size, bool)
    for a, b in zip(start, stop, strict=True):
        stride = _COARSE_STRIDE if b - a >= 4 * _COARSE_STRIDE else 1
        coarse[a:b:stride] = coarse[b - 1] = True
    lo, hi = np.empty(run.size), np.empty(run.size)
    lo[coarse], hi[coarse] = bisect_across(labels, base[coarse], normal[coarse], k[coarse],
                                           tol=tol, target=tol / _COARSE_TOL,
                                           half_width=_FIRST_BRACKET * tol, strict=False)
    offset = 0.5 * (lo + hi)
    for a, b in zip(start, stop, strict=True):
        c = np.flatnonzero(coarse[a:b]) + a
        f = np.flatnonzero(~coarse[a:b]) + a
        if f.size:
            offset[f] = _not_a_knot_spline(tau[c], offset[c], tau[f])
    fine = ~coarse
    lo_f, hi_f = bisect_across(labels, base[fine] + offset[fine, None] * normal[fine],
                               normal[fine], k[fine], tol=tol, half_width=_FINE_BRACKET * tol,
                               strict=False)
    lo[fine], hi[fine] = offset[fine] + lo_f, offset[fine] + hi_f
    return lo, hi


def _symmetry_error(branch: np.ndarray, vertex: np.ndarray, point: np.ndarray) -> float:
    """Largest distance [rad-ish] between a located point of the right branch of −π (branch 1)
    and the point reflection of the located point of the left branch of π (branch 0) with the
    same vertex index; NaN if they share none (one source only).

    The predicted vertices of the right branch are the reflections of those of the left one,
    and the normal of a pair is one vector (the vector field is odd), so both brackets lie on
    one line; if the label boundary is symmetric, as eq. (1) is, both brackets — each
    narrower than tol — hold its crossing with that line and the midpoints differ by less than
    tol. The bisection's sample points are symmetric about the vertex too, so labels that are
    odd in floating point give an error at rounding level; labels that break the symmetry
    show as an error of order tol or more."""
    left, right = branch == 0, branch == 1
    _, i, j = np.intersect1d(vertex[left], vertex[right], return_indices=True)
    if i.size == 0:
        return math.nan
    gap = point[left][i] + point[right][j]
    return float(np.hypot(gap[:, 0], gap[:, 1]).max())


def _place(run: np.ndarray, point: np.ndarray, window: Window):
    """The copies of the located source branches (``run`` 0, 1) that enter the window: each
    keeps its points inside the window and the one neighbour outside at either end of each
    inside run. Returns, per stored point, its index into the source arrays and the copy j
    (the shift 2πj [rad]): copy j of the left branch of π is the left branch of the saddle
    (1 + 2j)π, copy j of the right branch of −π the right branch of (−1 + 2j)π."""
    picks, copy = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for r in np.unique(run):
        src = np.flatnonzero(run == r)
        for j, keep in _copies(point[src, 0], point[src, 1], window, reach=1):
            picks.append(src[keep])
            copy.append(np.full(int(keep.sum()), j))
    return np.concatenate(picks), np.concatenate(copy)


def _group(*, theta, theta_dot, width, crossing, crossing_width, k_below, k_above, in_window,
           saddle_theta, saddle_n, branch, vertex, saddle_name: str, branch_comment: str,
           attrs: dict, k_comment: str | None = None) -> xr.Dataset:
    """The ``/separatrices`` node of one parameter point: per ``point`` the located boundary
    points with their saddle, branch and vertex; per ``crossing`` of the axis θ0 = 0 the
    speed, its bracket and the basins on either side (module docstring, :func:`trace`)."""
    flags = np.array([0, 1], np.int8)
    k_attrs = {"units": "1", **({"comment": k_comment} if k_comment else {})}
    return xr.Dataset(
        data_vars={
            "theta": ("point", theta, {"units": "rad", "long_name": "angle theta"}),
            "theta_dot": ("point", theta_dot,
                          {"units": "rad s-1", "long_name": "angular velocity theta_dot"}),
            "bracket_width": ("point", width, {
                "units": "1", "long_name": "final bisection bracket width across the curve "
                "(phase-plane distance, rad and rad s-1 mixed)"}),
            "crossing_theta_dot": ("crossing", crossing, {
                "units": "rad s-1", "long_name": "theta_dot0 where the label changes on the "
                "axis theta0 = 0"}),
            "k_below": ("crossing", np.asarray(k_below).astype(np.int16),
                        {**k_attrs, "long_name": "attractor k just below the crossing"}),
            "k_above": ("crossing", np.asarray(k_above).astype(np.int16),
                        {**k_attrs, "long_name": "attractor k just above the crossing"}),
            "crossing_bracket_width": ("crossing", crossing_width, {
                "units": "rad s-1", "long_name": "final bisection bracket width"}),
            "crossing_in_window": ("crossing", in_window, {
                "long_name": "whether the crossing (0, theta_dot0) lies in the window",
                "flag_values": flags, "flag_meanings": "outside inside"}),
        },
        coords={
            "saddle_theta": ("point", saddle_theta, {"units": "rad", "long_name": saddle_name}),
            "saddle_n": ("point", saddle_n, {"units": "1", "long_name": "saddle at n*pi"}),
            "branch": ("point", branch, {
                "long_name": "branch of the stable manifold", "flag_values": flags,
                "flag_meanings": "left right", "comment": branch_comment}),
            "vertex": ("point", vertex, {
                "units": "1", "long_name": "index along the branch, 0 nearest the saddle",
                "comment": "gaps where the branch leaves the window and comes back"}),
        },
        attrs=attrs,
    )


def trace(
    pendulum: Pendulum,
    theta_window,
    theta_dot_window,
    *,
    tol: float = defaults.SEPARATRIX_TOL,
    max_spacing: float = defaults.MAX_SPACING,
    dt: float = defaults.DT,
    backend: str = "cpu",
    method: str = defaults.METHOD,
) -> xr.Dataset:
    """Trace every basin boundary in the window: the branches of the stable manifolds of the
    saddles (nπ, 0), inside the window or not, that enter it.

    ``theta_window`` = (θmin, θmax) [rad], ``theta_dot_window`` = (θ̇min, θ̇max) [rad s⁻¹];
    ``tol``: bisection tolerance, the width [rad-ish] across the curve below which a point is
    accepted; ``max_spacing``: largest distance between vertices (the chord error stays below
    max_spacing²/8); ``dt`` [s]: RK4 step of the labels, the same as the basin map's;
    ``method``: their discretisation (:data:`atlas.kernels.METHODS`), the basin map's.

    Method, accuracy and references: see the module docstring. Returns the ``/separatrices``
    group: per ``point`` the coordinates ``saddle_theta``, ``saddle_n``, ``branch`` (0 left,
    1 right), ``vertex`` and the variables ``theta``, ``theta_dot``, ``bracket_width``; per
    ``crossing`` of the axis θ0 = 0 (one per boundary, inside the window or not) the variables
    ``crossing_theta_dot``, ``k_below``, ``k_above``, ``crossing_bracket_width``,
    ``crossing_in_window``; attributes: ``alpha``, ``omega0``, the windows, ``tol``,
    ``max_spacing``, ``dt``, ``t_max``, ``n_boundaries``, ``symmetry_error``,
    ``symmetry_bound``, ``discrepancy``, ``discrepancy_bound``, ``polyline_error``,
    ``n_orbits``, ``n_unresolved``, ``warnings`` (lines joined by "\\n", read with
    :func:`warnings`) and ``method``.
    Raises ValueError for α = 0, a bad window, dt or settings
    (:func:`atlas.limits.check_separatrix_settings`);
    :class:`SeparatrixError` (an :class:`~atlas.errors.AtlasError`) if a point or branch
    cannot be certified during the run.
    """
    p = pendulum
    window = _checked(p, theta_window, theta_dot_window, tol, max_spacing, dt)

    # the two source branches, over the stretch their copies in the window use: vertices on
    # the exact left branch of π, and their reflections for the right branch of −π
    reference = _reference(p, window)
    left = _predict(reference, _edge_speeds(window), max_spacing)
    grown = [g for b in _sources(window)
             if (g := _needed(left if b == "left" else left.reflected(), window)).theta.size]

    def cat(f):
        return np.concatenate([f(r, g) for r, g in enumerate(grown)]) if grown else np.zeros(0)

    run = cat(lambda r, g: np.full(g.theta.size, r)).astype(np.int32)
    saddle_n = cat(lambda r, g: np.full(g.theta.size, g.n)).astype(np.int32)
    branch = cat(lambda r, g: np.full(g.theta.size, BRANCHES.index(g.branch))).astype(np.int8)
    vertex = cat(lambda r, g: g.vertex).astype(np.int32)
    base = np.column_stack([cat(lambda r, g: g.theta), cat(lambda r, g: g.theta_dot)])
    tau = cat(lambda r, g: g.tau)

    # vertices: t_max covers their travel τ and lingering down to δ ≈ tol²; unresolved ones
    # are stuck in floating point (see _Labeller), so a longer t_max would not help them
    labels = _Labeller(p, dt, tau.max(initial=0.0) + _linger(p, tol), backend, method)
    normal = np.column_stack(_normal(p, base[:, 0], base[:, 1]))
    lo, hi = _locate(labels, base, normal, (saddle_n + 1) // 2, run, tau, tol)
    point = base + 0.5 * (lo + hi)[:, None] * normal
    symmetry_error = _symmetry_error(branch, vertex, point)
    source, copy = _place(run, point, window)
    stored_n = (saddle_n[source] + 2 * copy).astype(np.int32)
    order = np.lexsort((vertex[source], branch[source], stored_n))
    source, copy, stored_n = source[order], copy[order], stored_n[order]
    stored_theta = point[source, 0] + 2.0 * math.pi * copy
    check = _check(reference, stored_n, branch[source], vertex[source], stored_theta,
                   point[source, 1])
    saddles = np.unique(stored_n).astype(np.int64)
    crossing, crossing_width, k_above, axis_labels = _axis_crossings(reference, saddles, tol,
                                                                     dt, backend, method)
    crossing_in_window = (window.margin(0.0, crossing) >= 0).astype(np.int8)

    problems = []
    nonfinite = labels.nonfinite + axis_labels.nonfinite
    if nonfinite:
        problems.append(f"{nonfinite} orbits met NaN/inf (dt = {dt:g} s unstable?); they "
                        "were left out of the bisection")
    widths = np.concatenate([hi - lo, crossing_width])
    if np.any(widths >= tol):
        problems.append(
            f"{int(np.sum(widths >= tol))} points could not be bracketed below tol = {tol:g} "
            f"(widest {widths.max():.1e}): certified labels stop short of the curve where "
            "orbits stall at a saddle in floating point (large alpha/omega0 or |theta|); "
            "their bracket_width is stored; raise tol")
    if symmetry_error > SYMMETRY_BOUND * tol:
        problems.append(f"the right branch of -pi is up to {symmetry_error:.1e} from the point "
                        f"reflection of the left branch of pi (bound {SYMMETRY_BOUND:g} tol): "
                        "the labels are not symmetric under (theta, theta_dot) -> (-theta, "
                        "-theta_dot)")
    if check.discrepancy > DISCREPANCY_BOUND:
        problems.append(f"separatrix points are up to {check.discrepancy:.2e} from the "
                        f"DOP853 stable manifold (bound {DISCREPANCY_BOUND:.0e}): lower "
                        + ("tol" if tol > DISCREPANCY_BOUND else "dt"))

    return _group(
        theta=stored_theta, theta_dot=point[source, 1], width=(hi - lo)[source],
        crossing=crossing, crossing_width=crossing_width, k_below=k_above - 1,
        k_above=k_above, in_window=crossing_in_window, saddle_theta=stored_n * np.pi,
        saddle_n=stored_n, branch=branch[source], vertex=vertex[source],
        saddle_name="theta of the saddle (n*pi, 0)",
        branch_comment="left: arrives with theta_dot > 0 from theta < n*pi; right: arrives "
                       "with theta_dot < 0 from theta > n*pi",
        attrs={
            "alpha": p.alpha,
            "omega0": p.omega0,
            "theta_window": np.array(window.theta),
            "theta_dot_window": np.array(window.theta_dot),
            "tol": float(tol),
            "max_spacing": float(max_spacing),
            "dt": float(dt),
            "t_max": max(labels.t_max, axis_labels.t_max),
            "n_boundaries": int(saddles.size),
            "symmetry_error": symmetry_error,
            "symmetry_bound": SYMMETRY_BOUND * tol,
            "discrepancy": check.discrepancy,
            "discrepancy_bound": DISCREPANCY_BOUND,
            "polyline_error": check.polyline_error,
            "n_orbits": labels.orbits + axis_labels.orbits,
            "n_unresolved": labels.unresolved + axis_labels.unresolved,
            "warnings": "\n".join(problems),
            "method": (
                f"basin boundaries of the RK4 map (step dt, method {method}): the left "
                "branch of pi and the right branch of -pi, vertices predicted on the exact "
                "stable manifold (DOP853 in reversed time, rtol = atol = 1e-13, from 1e-7 "
                "along the stable "
                "eigenvector, essay eqs. 22, 24; the right branch its point reflection), "
                "spacing <= max_spacing and <= max_spacing/sqrt(curvature); each vertex "
                "located by bisection/multisection across the curve on certified RK4 labels "
                "until the bracket is narrower than tol; every other branch is a copy shifted "
                "by a multiple of 2 pi (symmetry_error: the right branch of -pi vs the point "
                "reflection of the left branch of pi); checked against the same DOP853 "
                "manifold: discrepancy = max distance of the points to it, polyline_error = "
                "max distance of it to the polyline"),
        },
    )


def branches(ds: xr.Dataset) -> Iterator[tuple[int, str, np.ndarray, np.ndarray]]:
    """Yield (saddle_n, "left"|"right", theta [rad], theta_dot [rad s⁻¹]) per polyline, the
    arrays ordered from the saddle outward; for plotting. A branch that leaves the window and
    comes back (its ``vertex`` skips the points outside) yields one polyline per visit."""
    n, b, vtx = (ds[name].values for name in ("saddle_n", "branch", "vertex"))
    theta, theta_dot = ds["theta"].values, ds["theta_dot"].values
    for key in sorted(set(zip(n.tolist(), b.tolist(), strict=True))):
        sel = np.flatnonzero((n == key[0]) & (b == key[1]))
        sel = sel[np.argsort(vtx[sel], kind="stable")]
        for piece in np.split(sel, np.flatnonzero(np.diff(vtx[sel]) != 1) + 1):
            yield key[0], BRANCHES[key[1]], theta[piece], theta_dot[piece]


def warnings(ds: xr.Dataset) -> list[str]:
    """The problems recorded by :func:`trace` (discrepancy above its bound), one per line."""
    text = str(ds.attrs.get("warnings", ""))
    return [line for line in text.split("\n") if line]


def max_discrepancy(ds: xr.Dataset) -> float:
    """The largest distance [rad-ish] of the traced points to the DOP853 stable manifold."""
    return float(ds.attrs["discrepancy"])


def _basin_name(k) -> str:
    """A crossing's basin: its well k, or "run" for the running basin."""
    from atlas.kernels import ATTRACTOR_FILL

    return "run" if int(k) == ATTRACTOR_FILL else str(int(k))


def summary(ds: xr.Dataset) -> list[str]:
    """Short human-readable lines for ``atlas info``."""
    found = {(n, b) for n, b, *_ in branches(ds)}
    saddles = sorted({n for n, _ in found})
    bound = float(ds.attrs["discrepancy_bound"])
    disc = max_discrepancy(ds)
    symmetry = float(ds.attrs.get("symmetry_error", math.nan))
    symmetry_bound = float(ds.attrs.get("symmetry_bound", math.nan))
    lines = [
        f"separatrices: {len(saddles)} basin boundaries (saddles n = "
        f"{', '.join(map(str, saddles)) or '-'}), {len(found)} branches, "
        f"{ds.sizes.get('point', 0)} points; bisection tol {float(ds.attrs['tol']):.0e}, "
        f"max spacing {float(ds.attrs['max_spacing']):g}",
        (f"symmetry: torque breaks the point reflection; the 2 pi shift between copies, "
         f"located independently: max distance {float(ds.attrs['shift_error']):.1e} over "
         f"{int(ds.attrs.get('shift_pairs', 0))} pairs"
         if "shift_error" in ds.attrs else
         "symmetry: right branch of -pi vs reflected left branch of pi: "
         + (f"max distance {symmetry:.1e} "
            f"({'within' if symmetry <= symmetry_bound else 'EXCEEDS'} bound "
            f"{symmetry_bound:.0e})" if symmetry == symmetry else
            "not checked (the window needs one of them only)")),
        f"check vs DOP853 stable manifold: max distance {disc:.1e} "
        f"({'within' if disc <= bound else 'EXCEEDS'} bound {bound:.0e}); "
        f"polyline error {float(ds.attrs['polyline_error']):.1e}; "
        f"{int(ds.attrs['n_orbits'])} orbits labelled, {int(ds.attrs['n_unresolved'])} "
        "uncertified (left out, never counted as either side)",
    ]
    inside = ds["crossing_in_window"].values if "crossing_in_window" in ds else None
    cross = [f"{v:+.10f} ({_basin_name(lo)}|{_basin_name(hi)})"
             f"{'' if inside is None or inside[i] else '*'}"
             for i, (v, lo, hi) in enumerate(zip(ds["crossing_theta_dot"].values,
                                                 ds["k_below"].values, ds["k_above"].values,
                                                 strict=True))]
    lines.append("basin boundaries on theta0 = 0: theta_dot0 = "
                 + (", ".join(cross) if cross else "none") + " rad/s (k below|above; "
                 "* outside the window)")
    lines += [f"warning: {w}" for w in warnings(ds)]
    return lines


# --------------------------------------------------------------------------- torque


class _RunningLabeller(_Labeller):
    """Certified labels with torque: well k, :data:`atlas.boundaries.tilted.RUNNING_SIDE` for an orbit in
    the running barrier, ``NO_LABEL`` for neither."""

    def __init__(self, p: Pendulum, dt: float, t_max: float, barrier, backend: str = "cpu",
                 method: str = defaults.METHOD):
        super().__init__(p, dt, t_max, backend, method)
        self.barrier = barrier

    def __call__(self, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
        from atlas.boundaries.tilted import RUNNING_SIDE
        from atlas.kernels import RUNNING

        res = label(theta, theta_dot, alpha=self.p.alpha, omega0=self.p.omega0,
                    torque=self.p.torque, dt=self.dt, t_max=self.t_max, backend=self.backend,
                    method=self.method, running=self.barrier)
        k, status = res.attractor.astype(np.int64), res.status
        self.orbits += theta.size
        self.unresolved += int(np.sum(status == UNRESOLVED))
        self.nonfinite += int(np.sum((status != TRAPPED) & (status != UNRESOLVED)
                                     & (status != RUNNING)))
        return np.where(status == TRAPPED, k, np.where(status == RUNNING, RUNNING_SIDE,
                                                       NO_LABEL))


def _bisect_between(labels, base, normal, below, above, *, tol: float, half_width: float):
    """Vectorised bisection of labels along base + s·normal between basin ``below`` (s < 0
    side) and ``above`` (s > 0), from the bracket ±half_width, each end pushed out ×8 (up to
    ``_MAX_BRACKET``) while it carries the other end's basin: returns (s_lo, s_hi, ok), ``ok``
    False where an end carries neither basin or the bracket outgrew the limit, or a midpoint
    carries neither (the bracket is then left as it was: its width says how far it got)."""
    n = base.shape[0]
    lo, hi = np.full(n, -half_width), np.full(n, half_width)
    ok = np.ones(n, bool)
    pending = np.arange(n)
    while pending.size:
        s_ends = np.concatenate([lo[pending], hi[pending]])
        at = np.concatenate([pending, pending])
        lab = labels(base[at, 0] + s_ends * normal[at, 0], base[at, 1] + s_ends * normal[at, 1])
        lab_lo, lab_hi = lab[:pending.size], lab[pending.size:]
        lo_over = lab_lo == above[pending]  # the boundary lies further down: push lo out
        hi_over = lab_hi == below[pending]
        fine = (lab_lo == below[pending]) & (lab_hi == above[pending])
        lost = ~fine & ~((lo_over | (lab_lo == below[pending]))
                         & (hi_over | (lab_hi == above[pending])))
        ok[pending[lost]] = False
        lo[pending[lo_over]] *= _GROW
        hi[pending[hi_over]] *= _GROW
        grow = pending[~fine & ~lost]
        too_wide = grow[(hi[grow] - lo[grow]) > 2 * _MAX_BRACKET]
        ok[too_wide] = False
        pending = np.setdiff1d(grow, too_wide)
    active = ok.copy()
    while True:
        idx = np.flatnonzero(active & (hi - lo >= tol))
        if not idx.size:
            return lo, hi, ok
        mid = 0.5 * (lo[idx] + hi[idx])
        lab = labels(base[idx, 0] + mid * normal[idx, 0], base[idx, 1] + mid * normal[idx, 1])
        is_below, is_above = lab == below[idx], lab == above[idx]
        lo[idx[is_below]] = mid[is_below]
        hi[idx[is_above]] = mid[is_above]
        lost = idx[~(is_below | is_above)]
        ok[lost] = active[lost] = False


def trace_tilted(pendulum: Pendulum, theta_window, theta_dot_window, *,
                 tol: float = defaults.SEPARATRIX_TOL, max_spacing: float = defaults.MAX_SPACING,
                 dt: float = defaults.DT, t_max: float = defaults.T_MAX,
                 backend: str = "cpu", method: str = defaults.METHOD, exact=None,
                 barrier=None) -> xr.Dataset:
    """The basin boundaries of the RK4 map for a pendulum with torque 0 < |τ| < ω0², the
    counterpart of :func:`trace` (same arguments; ``t_max`` [s] the atlas's, to which the
    lingering time at a saddle is added).

    The exact boundaries are :class:`atlas.boundaries.tilted.TiltedBoundaries` (the stable branches of
    the tilted saddles, DOP853): they are the predictor. Vertices are taken along each branch
    in the window about ``max_spacing`` apart (the first polyline vertex at or beyond each
    multiple of it along the branch, so at most max_spacing + :data:`atlas.boundaries.tilted.MAX_SEGMENT`;
    none closer than 1e-3 to its saddle, where the vector field that gives the normal
    vanishes); vertices whose exact sides agree at ±1e-3 (a tongue thinner than that) are
    skipped and counted (``n_skipped``); across each, along the normal of the
    vector field, the exact sides are read on either side (well k or the running basin) and
    certified RK4 labels (:func:`atlas.labels.labelling.label` with the tilted trap and the running
    barrier) are bisected from ±1e-3 until the bracket is narrower than ``tol``. Nothing is
    copied: every branch in the window is located on its own labels, so the 2π shift, the
    symmetry that holds with torque, is checked, not assumed: ``shift_error`` is the largest
    distance between a located point and the located point of the same source vertex on the
    neighbouring copy, shifted by 2π (the point reflection of the untilted pendulum does not
    hold: ``symmetry_error`` is NaN). ``discrepancy`` is the largest distance of the located
    points from the exact boundaries (:meth:`TiltedBoundaries.distance`): the RK4 map's
    boundary shift, which sets d_cert. Crossings of the axis θ0 = 0 are located the same way
    along θ̇, from the exact polylines' crossings; a running side is stored as
    :data:`atlas.boundaries.tilted.RUNNING_SIDE` in ``k_below``/``k_above``.

    ``exact``: the :class:`atlas.boundaries.tilted.TiltedBoundaries` of this window, with ``barrier``
    the running barrier to label with (None: none), if the caller built them; both are built
    here otherwise.

    Same schema as :func:`trace` (``saddle_n`` = 2j + 1 for the saddle π − θ* + 2πj, the
    one near (2j + 1)π), plus the attributes ``torque``, ``shift_error`` and
    ``reference_error`` (the exact boundaries' own error: chord + DOP853).
    """
    from atlas.boundaries.tilted import RUNNING_SIDE, TiltedBoundaries
    from atlas.physics.running import running_barrier

    p = pendulum
    window = _checked(p, theta_window, theta_dot_window, tol, max_spacing, dt)
    if exact is None:
        exact = TiltedBoundaries(p, window.theta, window.theta_dot)
        barrier = running_barrier(p.alpha, p.omega0, p.torque, exact.cycle, dt=dt) \
            if exact.cycle is not None else None
    labels = _RunningLabeller(p, dt, t_max + _linger(p, tol), barrier, backend, method)

    rows = []  # (saddle j, branch, vertex index, θ, θ̇)
    for j, name, theta, theta_dot in exact.curves(clip=False):
        step = np.hypot(np.diff(theta), np.diff(theta_dot))
        along = np.concatenate([[0.0], np.cumsum(step)])
        picks = np.unique(np.searchsorted(along, np.arange(1e-3, along[-1], max_spacing)))
        picks = picks[picks < theta.size]
        inside = window.margin(theta[picks], theta_dot[picks]) >= 0
        for number in np.flatnonzero(inside):  # numbered along the branch: gaps outside
            i = picks[number]
            rows.append((j, BRANCHES.index(name), int(number), theta[i], theta_dot[i]))
    saddle_j = np.array([r[0] for r in rows], np.int64)
    branch = np.array([r[1] for r in rows], np.int8)
    vertex = np.array([r[2] for r in rows], np.int32)
    base = np.array([(r[3], r[4]) for r in rows], float).reshape(-1, 2)
    normal = np.column_stack(_normal(p, base[:, 0], base[:, 1])) if rows else base.copy()
    probe = 1e-3
    below = exact.side(base[:, 0] - probe * normal[:, 0], base[:, 1] - probe * normal[:, 1])
    above = exact.side(base[:, 0] + probe * normal[:, 0], base[:, 1] + probe * normal[:, 1])
    # a vertex whose exact sides agree at ±probe (a tongue thinner than that, or a fold)
    # has no boundary to bisect across there: it is left out, and counted
    keep = below != above
    skipped = int((~keep).sum())
    saddle_j, branch, vertex = saddle_j[keep], branch[keep], vertex[keep]
    base, normal, below, above = base[keep], normal[keep], below[keep], above[keep]
    lo, hi, ok = _bisect_between(labels, base, normal, below, above, tol=tol,
                                 half_width=probe)
    point = base + 0.5 * (lo + hi)[:, None] * normal
    dist, _ = exact.distance(point[:, 0], point[:, 1]) if point.size else (np.zeros(0), None)
    # a vertex that could not be located leaves the shift unmeasured there: NaN, so that d_cert
    # is NaN and no label is certified for the exact equation on a partial measurement
    discrepancy = float(dist.max(initial=0.0)) if ok.all() else math.nan
    # the 2π shift: every 8th located vertex, shifted by 2π and located again on its own
    # labels (the next well's side), must land on the shifted point
    pick = np.flatnonzero(ok)[::_SHIFT_STRIDE]
    shifted = base[pick] + np.array([2.0 * math.pi, 0.0])

    def next_well(side):
        return np.where(side == RUNNING_SIDE, side, side + 1)

    s_lo, s_hi, s_ok = _bisect_between(labels, shifted, normal[pick], next_well(below[pick]),
                                       next_well(above[pick]), tol=tol, half_width=probe)
    moved = shifted + 0.5 * (s_lo + s_hi)[:, None] * normal[pick]
    gap = np.hypot(*(moved - point[pick] - np.array([2.0 * math.pi, 0.0])).T)
    shift_error, shift_pairs = float(gap[s_ok].max(initial=0.0)), int(s_ok.sum())

    crossing, crossing_width, k_below, k_above = _tilted_crossings(exact, labels, window, tol)
    problems = []
    if not ok.all():
        problems.append(f"{int((~ok).sum())} of {ok.size} vertices could not be bisected to "
                        f"tol = {tol:g} on certified labels (unresolved orbits, a third "
                        f"basin in the bracket, or a boundary shift beyond {_MAX_BRACKET:g}: "
                        "lower dt); the RK4 map's boundary shift is not measured (NaN), so no "
                        "label is certified for the exact equation")
    if discrepancy > DISCREPANCY_BOUND:
        problems.append(f"separatrix points are up to {discrepancy:.2e} from the DOP853 "
                        f"stable manifolds (bound {DISCREPANCY_BOUND:.0e}): lower dt")
    stored_n = (2 * saddle_j + 1).astype(np.int32)
    order = np.lexsort((vertex, branch, stored_n))
    saddle_theta = np.array([exact.saddle_theta(int(j)) for j in saddle_j])
    return _group(
        theta=point[order, 0], theta_dot=point[order, 1], width=(hi - lo)[order],
        crossing=crossing, crossing_width=crossing_width, k_below=k_below, k_above=k_above,
        in_window=np.ones(crossing.size, np.int8), saddle_theta=saddle_theta[order],
        saddle_n=stored_n[order], branch=branch[order], vertex=vertex[order],
        saddle_name="theta of the saddle (pi - asin(torque/omega0^2) + 2 pi j, 0), n = 2j + 1",
        branch_comment="left: arrives with theta_dot > 0 from the left; right: arrives with "
                       "theta_dot < 0 from the right",
        k_comment=f"{RUNNING_SIDE}: the running basin",
        attrs={
            "alpha": p.alpha, "omega0": p.omega0, "torque": p.torque,
            "theta_window": np.array(window.theta),
            "theta_dot_window": np.array(window.theta_dot),
            "tol": float(tol), "max_spacing": float(max_spacing), "dt": float(dt),
            "t_max": labels.t_max,
            "n_boundaries": int(np.unique(stored_n).size),
            "symmetry_error": math.nan, "symmetry_bound": SYMMETRY_BOUND * tol,
            "shift_error": shift_error, "shift_pairs": np.int64(shift_pairs),
            "n_skipped": np.int64(skipped),
            "discrepancy": discrepancy, "discrepancy_bound": DISCREPANCY_BOUND,
            "polyline_error": exact.chord_error,
            "reference_error": exact.reference_error + exact.chord_error,
            "n_orbits": labels.orbits, "n_unresolved": labels.unresolved,
            "warnings": "\n".join(problems),
            "method": (
                f"basin boundaries of the RK4 map (step dt, method {method}) with torque: "
                "vertices on the exact stable branches of the tilted saddles (atlas.boundaries.tilted: "
                "DOP853 in reversed time, rtol = atol = 1e-13), at most max_spacing apart; "
                "each located by bisection across the curve on certified RK4 labels (tilted "
                "trap, running barrier) "
                "until the bracket is narrower than tol; every copy located on its own "
                "labels (shift_error: the 2 pi shift between copies); discrepancy = max "
                "distance of the points to the exact boundaries"),
        },
    )


def _tilted_crossings(exact, labels, window: Window, tol: float):
    """Where the label changes along the axis θ0 = 0 in the window: the exact polylines'
    crossings of θ = 0, each bisected along θ̇ on certified RK4 labels. Returns (θ̇0, bracket
    width, basin below, basin above)."""
    speeds = []
    for _, _, theta, theta_dot in exact.curves(clip=True):
        s = np.sign(theta)
        for i in np.flatnonzero(s[:-1] * s[1:] < 0):
            f = theta[i] / (theta[i] - theta[i + 1])
            speeds.append(theta_dot[i] + f * (theta_dot[i + 1] - theta_dot[i]))
    speeds = np.sort(np.array([v for v in speeds
                               if window.theta_dot[0] < v < window.theta_dot[1]]))
    empty = np.zeros(0)
    if (window.theta[0] > 0.0 or window.theta[1] < 0.0) or not speeds.size:
        return empty, empty, empty.astype(np.int64), empty.astype(np.int64)
    base = np.column_stack([np.zeros(speeds.size), speeds])
    up = np.column_stack([np.zeros(speeds.size), np.ones(speeds.size)])
    probe = 1e-3
    below = exact.side(np.zeros(speeds.size), speeds - probe)
    above = exact.side(np.zeros(speeds.size), speeds + probe)
    lo, hi, _ = _bisect_between(labels, base, up, below, above, tol=tol, half_width=probe)
    return speeds + 0.5 * (lo + hi), hi - lo, below, above
