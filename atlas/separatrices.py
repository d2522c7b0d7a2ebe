"""Separatrices, certified: the stable manifolds of the saddles ((2j+1)π, 0) located by bisection.

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

Method (:func:`trace`)
----------------------
1. *Predictor* (manifold growth): for L (if the window holds θ̇ > 0) and R (if it holds
   θ̇ < 0), start at distance 10⁻⁷ from the saddle along its stable eigenvector (1, −u2) of the
   linearisation (essay eqs. 22, 24; the neglected curvature of the manifold is O(10⁻¹⁴)
   there) and integrate eq. (1) in reversed time with RK4 at step dt/2.
   Vertices are taken along this orbit with chords ≤ ``max_spacing`` and ≤ max_spacing/√κ
   (κ the curvature in rad⁻¹, computed from the vector field), so the chord error of the
   polyline stays below max_spacing²/8 everywhere; near the saddle the spacing grows
   geometrically from max_spacing/10. A source branch is grown through the window's θ̇ band
   at every θ (its copies cover any θ range) until its energy exceeds every energy in the
   window, with a vertex placed on the band's edge at every crossing; only the stretch that
   its copies in the window use is kept.
2. *Corrector* (bisection on initial conditions): each predicted vertex is only a guess.
   Across the curve, along the normal of the vector field, certified labels of
   :func:`atlas.labels.label` at step ``dt`` bracket the boundary between basins k − 1 and k;
   the bracket is widened ×8 until its ends carry those labels, then shrunk by bisection (or
   multisection — several labels across each bracket in one kernel call — when few brackets
   are left), all vertices of both branches in one batch per call, until narrower than
   ``tol``. The stored point is the bracket's midpoint, so the labels at ±tol across the curve
   differ. Two passes share the work (:func:`_locate`): every 8th vertex is bisected from
   ±32·tol to tol/8; a spline of those offsets predicts the others so well that their first
   bracket, ±0.45·tol, is usually final — two orbits per vertex (≈ 4.5 orbits per point in
   all at the default settings instead of ≈ 17).
   Orbits near the manifold linger ≈ ln(1/δ)/u1 at the saddle: t_max is the predictor's
   travel time plus 2(ln(1/tol) + 5)/u1, enough down to δ ≈ tol². An ``unresolved`` orbit is
   never taken as either side: bisection treats it as no information (such orbits are stuck
   at a floating-point fixed point next to the saddle, see :class:`_Labeller`; the attribute
   ``n_unresolved`` counts them); a bracket that cannot get below tol because of them (only
   for α ≳ 3ω0 at tol = 1e-12) is kept with its true ``bracket_width`` and reported in the
   ``warnings`` attribute.
   The located curve is the basin boundary of the RK4 scheme at step ``dt``, the same one that
   colours the basin map; it differs from the exact manifold by O(dt⁴).
3. *Symmetry check*: R is located on its own labels, not reflected from L. The predictor is
   odd in floating point, so the vertices of R are the reflections of those of L; the largest
   distance between a located point of R and the reflected located point of L is the attribute
   ``symmetry_error``, below tol when the labels respect the symmetry (at rounding level in
   practice: the bisection is symmetric too); above ``SYMMETRY_BOUND``·tol the summary carries
   a warning.
4. *Copies*: copy j of L is the left branch of the saddle (1 + 2j)π, copy j of R the right
   branch of (−1 + 2j)π, both shifted by 2πj. Each copy that enters the window is stored with
   its points inside it and the one neighbour outside at either end of each inside run, so the
   polylines reach the window's edges; ``vertex`` keeps the index along the source branch.
5. *Independent check* (:func:`check_against_stable_manifold`): the reversed-time ODE is
   integrated from the 10⁻⁷ start with scipy's DOP853 (rtol = atol = 10⁻¹³, dense output);
   the distance from every bisected point of L and R to that curve is found by Newton's method
   on the dense output. Its maximum is the attribute ``discrepancy``: ≈ 6e-10 at α = 0.1,
   ω0 = 1, dt = 0.01 (≈ 7e-10 at α = 1 and α = 2), falling as dt⁴ — RK4's offset, not
   bisection error (tests/test_separatrices.py checks it against Richardson's estimate). Above
   ``DISCREPANCY_BOUND`` = 10⁻⁸ the summary carries a warning. The same curve measures
   ``polyline_error``, the largest distance from the manifold to the polyline.

:func:`atlas.limits.check_separatrix_settings` rejects, before any work, a ``tol`` below what
double precision resolves in the window and a ``max_spacing`` finer than the curve is
accurate; what can still fail during a run raises :class:`SeparatrixError`, one line for the
user.

The crossing of every boundary in the window with the axis θ0 = 0 (the initial speed at which
the label changes there, inside the window or not) is located by the same bisection along the
θ̇0 axis, from the predictor's value of L at θ = −(|n| − 1)π (:func:`_axis_crossings`).

References: Nusse & Yorke, "A procedure for finding numerical trajectories on chaotic saddles",
Physica D 36 (1989) 137 (straddle orbits: bisection between initial conditions of different
fate); Krauskopf et al., "A survey of methods for computing (un)stable manifolds of vector
fields", Int. J. Bifurcation Chaos 15 (2005) 763 (growing a manifold from its linearisation);
Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5 (DOP853).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import xarray as xr

from . import defaults
from .errors import SeparatrixError
from .kernels import TRAPPED, UNRESOLVED
from .kernels.rk4 import rk4_step
from .labels import label
from .limits import MAX_STEPS, MAX_WELL, check_separatrix_settings
from .model import Pendulum

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
    "merge_parameter_points",
    "select_parameter_point",
]

#: Branch names, in the order of the ``branch`` flag values 0, 1.
BRANCHES = ("left", "right")
#: Largest accepted distance [rad-ish] between bisected points and the DOP853 manifold.
DISCREPANCY_BOUND = 1e-8
#: Distance of the first point of the predictor and of the check from the saddle.
START_DISTANCE = 1e-7
#: Tolerances of the DOP853 reference.
CHECK_RTOL = CHECK_ATOL = 1e-13
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
_MAX_VERTICES = 1_000_000  # per branch: a branch 100 rad-ish long at MIN_MAX_SPACING
_FAR = 2 * math.pi * MAX_WELL  # [rad] the θ reach of an atlas: a source branch's θ range


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

    def max_energy(self, omega0: float) -> float:
        """Largest E = ½θ̇² + ω0²(1 − cos θ) in the window (a bound: ½max θ̇² + 2ω0²)."""
        return 0.5 * max(self.theta_dot[0] ** 2, self.theta_dot[1] ** 2) + 2.0 * omega0**2


# --------------------------------------------------------------------------- vector field


def _field(p: Pendulum, theta, theta_dot):
    """f = (θ̇, θ̈) of eq. (1) and its derivative along the flow, J·f."""
    w2, a2 = p.omega0**2, 2.0 * p.alpha
    f0, f1 = theta_dot, -w2 * np.sin(theta) - a2 * theta_dot
    return (f0, f1), (f1, -w2 * np.cos(theta) * f0 - a2 * f1)


def _normal(p: Pendulum, theta, theta_dot):
    """Unit normal (nθ, nθ̇) to the orbit through each point, oriented so that nθ̇ > 0.

    Along a branch θ̇ ≠ 0, so nθ̇ = |θ̇|/|f| > 0 is well defined; on the positive side lie the
    initial conditions of well k = (n+1)/2."""
    (f0, f1), _ = _field(p, theta, theta_dot)
    s = np.sign(f0) / np.hypot(f0, f1)
    return -f1 * s, f0 * s


def _energy(p: Pendulum, theta, theta_dot):
    return 0.5 * theta_dot**2 + p.omega0**2 * (1.0 - np.cos(theta))


def _saddle_start(p: Pendulum, n: int, branch: str, distance: float) -> tuple[float, float]:
    """The point at ``distance`` from the saddle nπ along its stable eigenvector (eqs. 22, 24)."""
    e_theta, e_theta_dot = p.saddle_stable_direction()
    sign = -1.0 if branch == "left" else 1.0
    return n * math.pi + sign * distance * e_theta, sign * distance * e_theta_dot


def _gone(p: Pendulum, window: Window, branch: str, theta: float, theta_dot: float) -> bool:
    """True once a branch, followed away from its saddle, can never re-enter the window: θ moves
    monotonically (left: decreasing) and E grows beyond every energy the window holds."""
    past = theta < window.theta[0] if branch == "left" else theta > window.theta[1]
    return past or _energy(p, theta, theta_dot) > window.max_energy(p.omega0)


# --------------------------------------------------------------------------- labels


class _Labeller:
    """Certified labels (:func:`atlas.labels.label`) with ``NO_LABEL`` where an orbit is not
    trapped — never taken as either side.

    Why orbits stay unresolved although t_max covers the lingering time ln(1/δ)/u1 down to
    δ ≈ 1e-24: an orbit that arrives at the saddle θs within |φ| < ulp(θs)/(2·dt·u1) of it
    (≈ 4e-13 for α = 2, ω0 = 1, θs = 3π, dt = 0.01) has RK4 increments dt·θ̇ below half an ulp
    of θ, so θ never changes again: a fixed point of the floating-point map. Bisection treats
    such samples as unknown and brackets around them (``unresolved`` counts them)."""

    def __init__(self, p: Pendulum, dt: float, t_max: float, backend: str = "cpu"):
        # never more steps than an orbit may take (atlas.limits.MAX_STEPS)
        self.p, self.dt, self.backend = p, dt, backend
        self.t_max = min(t_max, 0.99 * MAX_STEPS * dt)
        self.orbits = self.unresolved = self.nonfinite = 0

    def __call__(self, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
        res = label(theta, theta_dot, alpha=self.p.alpha, omega0=self.p.omega0, dt=self.dt,
                    t_max=self.t_max, backend=self.backend)
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
    """Locate the boundary between basins k − 1 and k on the lines base + s·direction.

    ``labels(theta, theta_dot) -> k`` gives certified labels, ``NO_LABEL`` where an orbit is
    not certified (:class:`_Labeller`); ``base``, ``direction``: (N, 2) arrays [rad, rad s⁻¹]
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


def _flow_back(p: Pendulum, theta: float, theta_dot: float, tau: float, dt_p: float):
    """The state reached after reversed time ``tau`` ≥ 0: RK4 with ⌈tau/dt_p⌉ equal steps."""
    m = max(1, math.ceil(tau / dt_p - 1e-9))
    h = -tau / m
    for _ in range(m):
        theta, theta_dot = rk4_step(theta, theta_dot, p.alpha, p.omega0, h)
    return theta, theta_dot


_EDGE_GRADIENT = ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0))


def _edge_point(p: Pendulum, window: Window, y, span: float, dt_p: float):
    """The point where the reversed-time orbit from ``y`` crosses the window's edge within
    reversed time ``span``: safeguarded Newton on the edge margin. Returns (state, time)."""
    def margin(z):
        sides = (z[0] - window.theta[0], window.theta[1] - z[0],
                 z[1] - window.theta_dot[0], window.theta_dot[1] - z[1])
        j = int(np.argmin(sides))
        return sides[j], _EDGE_GRADIENT[j]

    g_a = margin(y)[0]
    a, b = 0.0, span
    tau = span / 2
    for _ in range(40):
        z = _flow_back(p, *y, tau, dt_p)
        g, grad = margin(z)
        if abs(g) < 1e-14 * (1.0 + abs(z[0]) + abs(z[1])):
            break
        if (g > 0) == (g_a > 0):
            a = tau
        else:
            b = tau
        (f0, f1), _ = _field(p, z[0], z[1])
        slope = -(grad[0] * f0 + grad[1] * f1)  # d margin / d tau along the reversed flow
        tau = tau - g / slope if slope != 0 else 0.5 * (a + b)
        if not a < tau < b:
            tau = 0.5 * (a + b)
    return z, tau


@dataclass(frozen=True)
class _Predicted:
    """Predicted vertices of one branch: state, reversed time from the start point and index
    along the branch (0 its first vertex, next to the saddle)."""

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


def _grow(p: Pendulum, window: Window, n: int, branch: str, max_spacing: float,
          dt_p: float) -> _Predicted:
    """Grow one branch from its linearisation by reversed-time RK4 (step ``dt_p``), placing
    vertices with curvature-adapted spacing, and an extra vertex at every crossing of the
    window's edge; keep the part from its first to its last vertex in the window."""
    u2 = -p.saddle_eigenvalues()[1]
    y = _saddle_start(p, n, branch, START_DISTANCE)
    verts, inside = [], []
    if not _gone(p, window, branch, *y):
        tau = max(0.0, math.log(0.1 * max_spacing / START_DISTANCE) / u2)
        y = _flow_back(p, *y, tau, dt_p)
        was_inside = window.margin(*y) >= 0
        verts.append((*y, tau))
        inside.append(was_inside)
    while verts and not _gone(p, window, branch, *y):
        if len(verts) > _MAX_VERTICES:
            raise SeparatrixError(f"branch {branch} of saddle {n}π: more than {_MAX_VERTICES} "
                                  "vertices; raise separatrices.max_spacing or shrink the "
                                  "window")
        (f0, f1), (g0, g1) = _field(p, *y)
        speed = math.hypot(f0, f1)
        kappa = abs(f0 * g1 - f1 * g0) / speed**3  # curvature of the orbit [rad⁻¹]
        growth = abs(f0 * g0 + f1 * g1) / speed**2  # |d ln speed / d tau|
        h = max_spacing * min(1.0, 1.0 / math.sqrt(kappa)) if kappa > 0 else max_spacing
        span = min(_CHORD_AIM * h / speed, _SPEED_GROWTH / max(growth, 1e-300))
        while True:
            z = _flow_back(p, *y, span, dt_p)
            chord = math.hypot(z[0] - y[0], z[1] - y[1])
            if chord <= h:
                break
            span *= _CHORD_AIM * h / chord
        now_inside = window.margin(*z) >= 0
        if now_inside != was_inside:
            e, t_e = _edge_point(p, window, y, span, dt_p)
            verts.append((*e, tau + t_e))
            inside.append(True)
        tau += span
        y, was_inside = z, now_inside
        verts.append((*y, tau))
        inside.append(now_inside)
    keep = np.flatnonzero(inside)
    arr = np.array(verts[keep[0]:keep[-1] + 1] if keep.size else [], float).reshape(-1, 3)
    first = int(keep[0]) if keep.size else 0
    return _Predicted(n, branch, arr[:, 0], arr[:, 1], arr[:, 2],
                      np.arange(first, first + arr.shape[0]))


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


def _to_reference(saddle_n, branch, theta, theta_dot):
    """Map points of branch (n, left|right) onto the left branch of the saddle π.

    Eq. (1) is invariant under θ → θ + 2π and under (θ, θ̇) → (−θ, −θ̇); the left branch of nπ
    is the left branch of π shifted by (n − 1)π, and the right branch of nπ is the point
    reflection of the left branch of −nπ. Both maps are isometries, so distances survive."""
    left = np.asarray(branch) == 0
    n = np.asarray(saddle_n, float)
    return (np.where(left, theta - (n - 1) * np.pi, (n + 1) * np.pi - theta),
            np.where(left, theta_dot, -theta_dot))


def check_against_stable_manifold(ds: xr.Dataset) -> ManifoldCheck:
    """Recompute the independent check of a traced ``/separatrices`` group (see
    :func:`_check`): per-point distances to the DOP853 stable manifold, polyline error."""
    return _check(Pendulum(float(ds.attrs["alpha"]), float(ds.attrs["omega0"])),
                  Window(tuple(ds.attrs["theta_window"]), tuple(ds.attrs["theta_dot_window"])),
                  ds["saddle_n"].values, ds["branch"].values, ds["vertex"].values,
                  ds["theta"].values, ds["theta_dot"].values)


def _check(p: Pendulum, window: Window, saddle_n, branch, vertex, theta,
           theta_dot) -> ManifoldCheck:
    """Independent check of traced separatrix points against the stable manifold.

    The left branch of the saddle (π, 0) is integrated in reversed time, θ' = −θ̇,
    θ̇' = ω0² sin θ + 2αθ̇, with scipy's DOP853 (rtol = atol = 1e-13, dense output) from
    10⁻⁷ along the stable eigenvector (linearisation error 10⁻¹⁴), until it is one radian past
    the farthest point or beyond the window's energies; all other branches are its images
    under the symmetries of eq. (1) (:func:`_to_reference`). The distance of each point to
    that curve is found by Newton's method for the foot point on the dense output (accurate
    to ≈ 1e-13).

    ``branch`` holds flag values (0 left, 1 right); ``vertex`` orders the points of a branch,
    and the polyline joins consecutive vertices only (a branch may leave the window and come
    back: the points in between are not stored). The window bounds the energy of the points.
    """
    from scipy.integrate import solve_ivp
    from scipy.spatial import cKDTree

    saddle_n, branch, vertex = (np.asarray(a, np.int64) for a in (saddle_n, branch, vertex))
    theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
    if theta.size == 0:
        return ManifoldCheck(np.zeros(0), 0.0)
    x, v = _to_reference(saddle_n, branch, theta, theta_dot)
    w2, a2 = p.omega0**2, 2.0 * p.alpha
    # the reference runs one radian past the farthest mapped point (θ falls along it), so
    # every foot point lies inside it, or until no point of the window's energy is left
    theta_end = float(x.min()) - 1.0
    energy_end = window.max_energy(p.omega0)

    def rhs(t, y):
        return np.array([-y[1], w2 * math.sin(y[0]) + a2 * y[1]])

    def gone(t, y):
        return min(y[0] - theta_end, energy_end - _energy(p, y[0], y[1]))

    gone.terminal, gone.direction = True, -1
    y0 = _saddle_start(p, 1, "left", START_DISTANCE)
    t_cap = 1e3 * (1.0 / p.alpha + 1.0 / p.omega0) + 10 * abs(theta_end)
    sol = solve_ivp(rhs, (0.0, t_cap), y0, method="DOP853", rtol=CHECK_RTOL, atol=CHECK_ATOL,
                    dense_output=True, events=gone)
    if sol.status < 0:
        raise SeparatrixError(f"DOP853 reference of the separatrix check failed: {sol.message}")
    curve = sol.sol

    # foot points: nearest dense sample, then Newton on (c(t) − q)·c'(t) = 0
    t_samples = np.union1d(sol.t, (sol.t[:-1, None] + np.diff(sol.t)[:, None]
                                   * np.linspace(0, 1, 16, endpoint=False)).ravel())
    _, nearest = cKDTree(curve(t_samples).T).query(np.column_stack([x, v]))
    t = t_samples[nearest]
    for _ in range(4):
        c = curve(t)
        d0, d1 = -c[1], w2 * np.sin(c[0]) + a2 * c[1]
        t = np.clip(t - ((c[0] - x) * d0 + (c[1] - v) * d1) / (d0 * d0 + d1 * d1),
                    0.0, sol.t[-1])
    c = curve(t)
    distance = np.hypot(c[0] - x, c[1] - v)

    # polyline: sample the manifold between consecutive vertices, distance to the chord
    order = np.lexsort((vertex, branch, saddle_n))
    same = ((np.diff(saddle_n[order]) == 0) & (np.diff(branch[order]) == 0)
            & (np.diff(vertex[order]) == 1))
    i0, i1 = order[:-1][same], order[1:][same]
    frac = np.linspace(0.0, 1.0, 17)[1:-1]
    ts = t[i0, None] + (t[i1] - t[i0])[:, None] * frac
    c = curve(ts.ravel())
    cx, cv = c[0].reshape(ts.shape), c[1].reshape(ts.shape)
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


def _linger(p: Pendulum, tol: float) -> float:
    """Time [s] an orbit within δ of a stable manifold lingers at its saddle, ≈ ln(1/δ)/u1,
    with room for δ down to ≈ tol² and the fall into the well after it."""
    return 2.0 * (math.log(1.0 / tol) + 5.0) / p.saddle_eigenvalues()[0]


def _band(window: Window) -> Window:
    """The window's θ̇ band over the θ reach of an atlas: where a source branch is needed, since
    its copies shifted by multiples of 2π cover every θ range. Growth in it ends by energy."""
    return Window((-_FAR, _FAR), window.theta_dot)


def _sources(window: Window) -> list[tuple[int, str]]:
    """The source branches whose copies can enter the window: the left branch of π (θ̇ > 0
    along it) if the window holds θ̇ > 0, the right branch of −π (θ̇ < 0) if it holds θ̇ < 0."""
    return [(n, b) for n, b, present in ((1, "left", window.theta_dot[1] > 0.0),
                                         (-1, "right", window.theta_dot[0] < 0.0)) if present]


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


def _left_branch_at(p: Pendulum, thetas: np.ndarray, dt_p: float):
    """θ̇ [rad s⁻¹] and reversed time τ [s] where the predictor of the left branch of π — RK4
    in reversed time at step ``dt_p`` from ``START_DISTANCE`` along the stable eigenvector —
    passes each θ < π of ``thetas`` [rad]: marching step by step, then Newton on the step that
    crosses (:func:`_edge_point`, with θ = target the only edge in reach). Along the branch θ
    falls monotonically, so each θ is passed once."""
    y, tau = _saddle_start(p, 1, "left", START_DISTANCE), 0.0
    speed, when = np.empty(thetas.size), np.empty(thetas.size)
    for i in np.argsort(thetas)[::-1]:
        while (z := _flow_back(p, *y, dt_p, dt_p))[0] > thetas[i]:
            y, tau = z, tau + dt_p
        line = Window((float(thetas[i]), _FAR), (-_FAR, _FAR))
        crossing, t = _edge_point(p, line, y, dt_p, dt_p)
        speed[i], when[i] = crossing[1], tau + t
    return speed, when


def _axis_crossings(p: Pendulum, saddles: np.ndarray, tol: float, dt: float, backend: str):
    """θ̇0 [rad s⁻¹] where the stable manifold of each saddle nπ meets the axis θ0 = 0, the
    boundary between basins (n − 1)/2 below and (n + 1)/2 above.

    The branch arriving from the side of θ = 0 meets it: for n ≥ 1 the left branch of nπ, the
    left branch of π shifted by (n − 1)π, at θ̇ = L(−(n − 1)π); for n ≤ −1 the right branch,
    the reflection of L shifted by (n + 1)π, at θ̇ = −L((n + 1)π). The predictor gives L there
    (:func:`_left_branch_at`); the crossing is bisected along the θ̇0 axis on certified labels,
    with t_max covering the travel time to the saddle. Returns (θ̇0, bracket width, k above,
    the labeller)."""
    speed, travel = _left_branch_at(p, -(np.abs(saddles) - 1) * np.pi, 0.5 * dt)
    labels = _Labeller(p, dt, travel.max(initial=0.0) + _linger(p, tol), backend)
    predicted = np.sign(saddles) * speed
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
    from scipy.interpolate import CubicSpline

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
            offset[f] = CubicSpline(tau[c], offset[c])(tau[f])
    fine = ~coarse
    lo_f, hi_f = bisect_across(labels, base[fine] + offset[fine, None] * normal[fine],
                               normal[fine], k[fine], tol=tol, half_width=_FINE_BRACKET * tol,
                               strict=False)
    lo[fine], hi[fine] = offset[fine] + lo_f, offset[fine] + hi_f
    return lo, hi


def _symmetry_error(run: np.ndarray, tau: np.ndarray, point: np.ndarray) -> float:
    """Largest distance [rad-ish] between a located point of the right branch of −π (run 1)
    and the point reflection of the located point of the left branch of π (run 0) with the
    same predictor time τ; NaN if they share none (one source only).

    The predictor is odd in floating point (rounding is symmetric, sin is odd, the vertex
    spacing depends on |f| only), so the predicted vertices of the two pair up exactly. The
    normal of a pair is one vector, so both brackets lie on one line; if the label boundary is
    symmetric, as eq. (1) is, both brackets — each narrower than tol — hold its crossing with
    that line and the midpoints differ by less than tol. The bisection's sample points are
    symmetric about the vertex too, so labels that are odd in floating point give an error at
    rounding level; labels that break the symmetry show as an error of order tol or more."""
    _, i, j = np.intersect1d(tau[run == 0], tau[run == 1], return_indices=True)
    if i.size == 0:
        return math.nan
    gap = point[run == 0][i] + point[run == 1][j]
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


def trace(
    pendulum: Pendulum,
    theta_window,
    theta_dot_window,
    *,
    tol: float = defaults.SEPARATRIX_TOL,
    max_spacing: float = defaults.MAX_SPACING,
    dt: float = defaults.DT,
    backend: str = "cpu",
) -> xr.Dataset:
    """Trace every basin boundary in the window: the branches of the stable manifolds of the
    saddles (nπ, 0), inside the window or not, that enter it.

    ``theta_window`` = (θmin, θmax) [rad], ``theta_dot_window`` = (θ̇min, θ̇max) [rad s⁻¹];
    ``tol``: bisection tolerance, the width [rad-ish] across the curve below which a point is
    accepted; ``max_spacing``: largest distance between vertices (the chord error stays below
    max_spacing²/8); ``dt`` [s]: RK4 step of the labels, the same as the basin map's.

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
    _require_damping(p)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a finite number > 0, got {dt!r}")
    check_separatrix_settings(theta_window, theta_dot_window, tol, max_spacing)
    window = Window(tuple(map(float, theta_window)), tuple(map(float, theta_dot_window)))

    # the two source branches, over the stretch their copies in the window use
    band = _band(window)
    grown = [g for n, b in _sources(window)
             if (g := _needed(_grow(p, band, n, b, max_spacing, 0.5 * dt), window)).theta.size]
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
    labels = _Labeller(p, dt, tau.max(initial=0.0) + _linger(p, tol), backend)
    normal = np.column_stack(_normal(p, base[:, 0], base[:, 1]))
    lo, hi = _locate(labels, base, normal, (saddle_n + 1) // 2, run, tau, tol)
    point = base + 0.5 * (lo + hi)[:, None] * normal
    check = _check(p, band, saddle_n, branch, vertex, point[:, 0], point[:, 1])
    symmetry_error = _symmetry_error(run, tau, point)
    source, copy = _place(run, point, window)
    stored_n = (saddle_n[source] + 2 * copy).astype(np.int32)
    order = np.lexsort((vertex[source], branch[source], stored_n))
    source, copy, stored_n = source[order], copy[order], stored_n[order]
    saddles = np.unique(stored_n).astype(np.int64)
    crossing, crossing_width, k_above, axis_labels = _axis_crossings(p, saddles, tol, dt,
                                                                     backend)
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

    return xr.Dataset(
        data_vars={
            "theta": ("point", point[source, 0] + 2.0 * math.pi * copy,
                      {"units": "rad", "long_name": "angle theta"}),
            "theta_dot": ("point", point[source, 1],
                          {"units": "rad s-1", "long_name": "angular velocity theta_dot"}),
            "bracket_width": ("point", (hi - lo)[source], {
                "units": "1", "long_name": "final bisection bracket width across the curve "
                "(phase-plane distance, rad and rad s-1 mixed)"}),
            "crossing_theta_dot": ("crossing", crossing, {
                "units": "rad s-1", "long_name": "theta_dot0 where the label changes on the "
                "axis theta0 = 0"}),
            "k_below": ("crossing", (k_above - 1).astype(np.int16),
                        {"units": "1", "long_name": "attractor k just below the crossing"}),
            "k_above": ("crossing", k_above.astype(np.int16),
                        {"units": "1", "long_name": "attractor k just above the crossing"}),
            "crossing_bracket_width": ("crossing", crossing_width, {
                "units": "rad s-1", "long_name": "final bisection bracket width"}),
            "crossing_in_window": ("crossing", crossing_in_window, {
                "long_name": "whether the crossing (0, theta_dot0) lies in the window",
                "flag_values": np.array([0, 1], np.int8), "flag_meanings": "outside inside"}),
        },
        coords={
            "saddle_theta": ("point", stored_n * np.pi,
                             {"units": "rad", "long_name": "theta of the saddle (n*pi, 0)"}),
            "saddle_n": ("point", stored_n, {"units": "1", "long_name": "saddle at n*pi"}),
            "branch": ("point", branch[source], {
                "long_name": "branch of the stable manifold",
                "flag_values": np.array([0, 1], np.int8), "flag_meanings": "left right",
                "comment": "left: arrives with theta_dot > 0 from theta < n*pi; right: "
                           "arrives with theta_dot < 0 from theta > n*pi"}),
            "vertex": ("point", vertex[source], {
                "units": "1", "long_name": "index along the branch, 0 nearest the saddle",
                "comment": "gaps where the branch leaves the window and comes back"}),
        },
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
                "stable manifolds of the saddles: the left branch of pi and the right branch "
                "of -pi, vertices predicted by reversed-time RK4 (step dt/2) from 1e-7 along "
                "the stable eigenvector (essay eqs. 22, 24), spacing <= max_spacing and <= "
                "max_spacing/sqrt(curvature); each vertex located by bisection/multisection "
                "across the curve on certified RK4 labels (step dt) until the bracket is "
                "narrower than tol; every other branch is a copy shifted by a multiple of 2 pi "
                "(symmetry_error: the right branch of -pi vs the point reflection of the left "
                "branch of pi); checked against DOP853 (rtol = atol = 1e-13) in reversed time: "
                "discrepancy = max distance of the points to it, polyline_error = max distance "
                "of it to the polyline"),
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
        "symmetry: right branch of -pi vs reflected left branch of pi: "
        + (f"max distance {symmetry:.1e} ({'within' if symmetry <= symmetry_bound else 'EXCEEDS'}"
           f" bound {symmetry_bound:.0e})" if symmetry == symmetry else
           "not checked (the window needs one of them only)"),
        f"check vs DOP853 stable manifold: max distance {disc:.1e} "
        f"({'within' if disc <= bound else 'EXCEEDS'} bound {bound:.0e}); "
        f"polyline error {float(ds.attrs['polyline_error']):.1e}; "
        f"{int(ds.attrs['n_orbits'])} orbits labelled, {int(ds.attrs['n_unresolved'])} "
        "uncertified (left out, never counted as either side)",
    ]
    inside = ds["crossing_in_window"].values if "crossing_in_window" in ds else None
    cross = [f"{v:+.10f} ({int(lo)}|{int(hi)}){'' if inside is None or inside[i] else '*'}"
             for i, (v, lo, hi) in enumerate(zip(ds["crossing_theta_dot"].values,
                                                 ds["k_below"].values, ds["k_above"].values,
                                                 strict=True))]
    lines.append("basin boundaries on theta0 = 0: theta_dot0 = "
                 + (", ".join(cross) if cross else "none") + " rad/s (k below|above; "
                 "* outside the window)")
    lines += [f"warning: {w}" for w in warnings(ds)]
    return lines


def merge_parameter_points(traced: list[tuple[float, float, xr.Dataset]]) -> xr.Dataset:
    """One group for a parameter atlas: the (α, ω0, :func:`trace`) of every point, curves
    and crossings concatenated, tagged by ``point_alpha``/``point_omega0`` and
    ``crossing_alpha``/``crossing_omega0``; the check's figures are the worst over all."""
    parts = {"point": [], "crossing": []}
    for a, w, ds in traced:
        for dim in parts:
            names = [n for n in ds.variables if ds[n].dims == (dim,)]
            part = ds[names].assign_coords({f"{dim}_alpha": (dim, np.full(ds.sizes[dim], a)),
                                            f"{dim}_omega0": (dim, np.full(ds.sizes[dim], w))})
            parts[dim].append(part.drop_attrs())
    merged = xr.merge([xr.concat(parts[dim], dim=dim) for dim in parts])
    attrs = [ds.attrs for *_, ds in traced]
    merged.attrs = {k: v for k, v in attrs[0].items() if k not in ("alpha", "omega0")}
    for key, combine in [("discrepancy", max), ("polyline_error", max), ("n_orbits", sum),
                         ("n_unresolved", sum), ("n_boundaries", max),
                         ("symmetry_error", np.fmax.reduce)]:
        merged.attrs[key] = combine([a[key] for a in attrs])
    merged.attrs["warnings"] = "\n".join(a["warnings"] for a in attrs if a.get("warnings"))
    return merged


def select_parameter_point(sep: xr.Dataset, alpha: float, omega0: float) -> xr.Dataset:
    """The separatrices of one (α, ω0) of a parameter atlas (the group itself otherwise)."""
    if "point_alpha" not in sep.coords:
        return sep
    picks = {}
    for dim in ("point", "crossing"):
        picks[dim] = np.flatnonzero((sep[f"{dim}_alpha"].values == alpha)
                                    & (sep[f"{dim}_omega0"].values == omega0))
    return sep.isel(picks)
