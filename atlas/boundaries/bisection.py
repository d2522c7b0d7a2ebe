"""Bisection on certified labels: where the basin label changes along lines across a curve.

A labeller maps points to certified RK4 labels (:class:`Labeller`: well k, the running basin,
or ``NO_LABEL`` where an orbit is not certified — never taken as either side). Brackets
across the predicted curve, along the normal of the vector field, are widened until their
ends carry the two basins, then shrunk by bisection or multisection (several labels across a
bracket in one kernel call) until narrower than ``tol`` [rad-ish]: :func:`bisect_across`
(usable with any labeller), :func:`bisect_between` (with torque: either side may be running),
:func:`locate` (two passes sharing the work: every 8th vertex first, a spline of their
offsets predicting the others). Accuracy: the located point is a bracket's midpoint, so the
labels at ±tol across it differ; a bracket that cannot shrink below tol is kept with its
width. Method: straddle orbits, Nusse & Yorke, Physica D 36 (1989) 137.
Derivation and costs: docs/design/separatrices.md.
"""

from __future__ import annotations

import math

import numpy as np

from atlas import defaults
from atlas.boundaries.basins import RUNNING_SIDE
from atlas.boundaries.predictor import not_a_knot_spline
from atlas.errors import SeparatrixError
from atlas.labels.labelling import label
from atlas.limits import MAX_STEPS
from atlas.physics.pendulum import Pendulum
from atlas.status import RUNNING, TRAPPED, UNRESOLVED

__all__ = ["NO_LABEL", "Labeller", "bisect_across", "bisect_between", "locate",
           "predict_offsets", "linger", "field_normal", "FIRST_BRACKET", "MAX_BRACKET"]

#: ``attractor`` of an orbit without a certified label, as seen by the bisection.
NO_LABEL = np.iinfo(np.int64).min
#: Initial half-width of a bracket, in units of tol.
FIRST_BRACKET = 32.0
#: No bracket end farther than this [rad-ish] from the prediction it starts around (so no
#: bracket wider than twice it): the predictor is far better than that.
MAX_BRACKET = 0.1
_GROW = 8.0  # widening factor while a bracket has equal labels at both ends
_BATCH = 64  # below this many orbits per kernel call, add multisection points
_MAX_SECTIONS = 7
_COARSE_STRIDE = 8  # every 8th vertex is bisected first, to tol/_COARSE_TOL
_COARSE_TOL = 8.0
_FINE_BRACKET = 0.45  # half-width of the other vertices' first bracket, in units of tol
_MAX_STALLS = 20  # rounds in a row without a certified label inside a bracket


class Labeller:
    """Certified labels (:func:`atlas.labels.labelling.label`) of the pendulum ``p`` at step
    ``dt`` [s] up to ``t_max`` [s]: well k where trapped, :data:`RUNNING_SIDE` where the orbit
    entered the running ``barrier`` (with torque; None: no running certificate), and
    ``NO_LABEL`` otherwise — never taken as either side. Counts the ``orbits`` labelled, the
    ``unresolved`` ones and the ``nonfinite`` ones (NaN/inf met).

    Why orbits stay unresolved although t_max covers the lingering time ln(1/δ)/u1 down to
    δ ≈ 1e-24: an orbit that arrives at the saddle θs within |φ| < ulp(θs)/(2·dt·u1) of it
    (≈ 4e-13 for α = 2, ω0 = 1, θs = 3π, dt = 0.01) has RK4 increments dt·θ̇ below half an ulp
    of θ, so θ never changes again: a fixed point of the floating-point map. Bisection treats
    such samples as unknown and brackets around them."""

    def __init__(self, p: Pendulum, dt: float, t_max: float, backend: str = "cpu",
                 method: str = defaults.METHOD, barrier=None):
        # never more steps than an orbit may take (atlas.limits.MAX_STEPS)
        self.p, self.dt, self.backend, self.method = p, dt, backend, method
        self.t_max = min(t_max, 0.99 * MAX_STEPS * dt)
        self.barrier = barrier
        self.orbits = self.unresolved = self.nonfinite = 0

    def __call__(self, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
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


def linger(p: Pendulum, tol: float) -> float:
    """Time [s] an orbit within δ of a stable manifold lingers at its saddle, ≈ ln(1/δ)/u1,
    with room for δ down to ≈ tol² and the fall into the well after it."""
    return 2.0 * (math.log(1.0 / tol) + 5.0) / p.saddle_eigenvalues()[0]


def field_normal(p: Pendulum, theta, theta_dot):
    """Unit normal (nθ, nθ̇) to the orbit through each point, oriented so that nθ̇ > 0.

    Along a boundary branch θ̇ ≠ 0, so nθ̇ = |θ̇|/|f| > 0 is well defined; without torque the
    initial conditions of well k = (n+1)/2 lie on its positive side."""
    f0, f1 = p.field(theta, theta_dot)
    s = np.sign(f0) / np.hypot(f0, f1)
    return -f1 * s, f0 * s


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
    where a point has none (for a trace, certified RK4 labels, :class:`Labeller`; any
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
        if np.any(grown & (step > MAX_BRACKET)):
            raise fail(int(np.argmax(grown & (step > MAX_BRACKET))),
                       f"no certified bracket within {MAX_BRACKET}")
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


def bisect_between(labels, base, normal, below, above, *, tol: float, half_width: float,
                   grow: float = _GROW):
    """Vectorised bisection of labels along base + s·normal between basin ``below`` (s < 0
    side) and ``above`` (s > 0; either may be :data:`RUNNING_SIDE`), from the bracket
    ±half_width. While an end carries the other end's basin, the boundary lies beyond it:
    that end becomes the other end (a certified point of the other side) and is pushed out
    ×``grow`` (both ends while both do), up to ``MAX_BRACKET`` from the base; only the ends
    that moved are labelled again. Returns (s_lo, s_hi, ok), ``ok`` False where an end carries
    neither basin or the bracket outgrew the limit, or a midpoint carries neither (the
    bracket is then left as it was: its width says how far it got)."""
    if not grow > 1.0:
        raise ValueError(f"grow must be > 1, got {grow!r}")
    n = base.shape[0]
    lo, hi = np.full(n, -half_width), np.full(n, half_width)
    lab_lo, lab_hi = np.full(n, NO_LABEL), np.full(n, NO_LABEL)
    ok = np.ones(n, bool)
    new_lo = new_hi = np.arange(n)  # the ends to label: every end first
    while new_lo.size or new_hi.size:
        at = np.concatenate([new_lo, new_hi])
        s_at = np.concatenate([lo[new_lo], hi[new_hi]])
        lab = labels(base[at, 0] + s_at * normal[at, 0], base[at, 1] + s_at * normal[at, 1])
        lab_lo[new_lo], lab_hi[new_hi] = lab[:new_lo.size], lab[new_lo.size:]
        i = np.union1d(new_lo, new_hi)
        lo_over, hi_over = lab_lo[i] == above[i], lab_hi[i] == below[i]
        lost = ~((lo_over | (lab_lo[i] == below[i])) & (hi_over | (lab_hi[i] == above[i])))
        ok[i[lost]] = False
        both, down, up = (i[~lost & lo_over & hi_over], i[~lost & lo_over & ~hi_over],
                          i[~lost & hi_over & ~lo_over])
        hi[down], lab_hi[down] = lo[down], lab_lo[down]  # lo is above's: the new hi
        lo[up], lab_lo[up] = hi[up], lab_hi[up]
        lo[down] = grow * hi[down]
        hi[up] = grow * lo[up]
        lo[both], hi[both] = grow * lo[both], grow * hi[both]
        moved = np.concatenate([both, down, up])
        too_wide = moved[np.maximum(-lo[moved], hi[moved]) > MAX_BRACKET]
        ok[too_wide] = False
        new_lo = np.setdiff1d(np.concatenate([both, down]), too_wide)
        new_hi = np.setdiff1d(np.concatenate([both, up]), too_wide)
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


def locate(labels, base, normal, k, run, tau, tol):
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
                                           half_width=FIRST_BRACKET * tol, strict=False)
    offset, _ = predict_offsets(tau, 0.5 * (lo + hi), coarse, ~coarse, start, stop)
    fine = ~coarse
    lo_f, hi_f = bisect_across(labels, base[fine] + offset[fine, None] * normal[fine],
                               normal[fine], k[fine], tol=tol, half_width=_FINE_BRACKET * tol,
                               strict=False)
    lo[fine], hi[fine] = offset[fine] + lo_f, offset[fine] + hi_f
    return lo, hi


def predict_offsets(along, centre, known, pick, start, stop):
    """(offsets, predicted) of the vertices ``pick`` from those ``known`` (their located
    offsets ``centre``), run by run (runs [start, stop)): a not-a-knot cubic spline over
    ``along`` (increasing within a run) where a run has four known vertices or more, else
    linear interpolation; where a run has fewer than two, its vertices are not predicted
    (offset 0, ``predicted`` False)."""
    offset, predicted = np.zeros(pick.size), np.zeros(pick.size, bool)
    for a, b in zip(start, stop, strict=True):
        have = np.flatnonzero(known[a:b]) + a
        todo = np.flatnonzero(pick[a:b]) + a
        if not (todo.size and have.size >= 2):
            continue
        if have.size >= 4 and np.all(np.diff(along[have]) > 0):
            offset[todo] = not_a_knot_spline(along[have], centre[have], along[todo])
        else:
            offset[todo] = np.interp(along[todo], along[have], centre[have])
        predicted[todo] = True
    return offset, predicted
