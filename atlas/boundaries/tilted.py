"""The exact basin boundaries of the pendulum with torque, 0 < |τ| < ω0².

    θ̈ = −ω0² sin θ − 2αθ̇ + τ        (α > 0 [s⁻¹], ω0 [rad s⁻¹], τ [rad s⁻²])

Units throughout: θ [rad], θ̇ [rad s⁻¹]; distances and areas are taken in the (θ, θ̇) plane
with both as one unit ("rad-ish", as in :mod:`atlas.boundaries.manifold`).

**Frame.** (θ, θ̇, τ) → (−θ, −θ̇, −τ) maps the equation to itself and well k to well −k, so
everything is computed for |τ| (the *canonical frame*) and mirrored. Below, τ > 0,
θ* = arcsin(τ/ω0²), the rest states are (θ* + 2πk, 0) — *well k*, the index the kernels
report as ``attractor`` and :meth:`atlas.physics.pendulum.Pendulum.well` computes — and the saddles
s_j = (π − θ* + 2πj, 0); well k lies between s_{k−1} and s_k.

**Branches.** Each saddle has two stable branches: L_j, arriving from the left with θ̇ > 0,
and R_j, arriving from the right with θ̇ < 0. Both are integrated once, for j = 0, by scipy's
DOP853 (rtol = atol = 1e-13, dense output) in reversed time from 1e-7 along the stable
eigenvector (the neglected curvature is O(1e-14)); every other branch is a 2π translate. In
reversed time dθ̇/dτ = 2αθ̇ + ω0² sin θ − τ, which is > 0 wherever θ̇ > c and < 0 wherever
θ̇ < −c, c = (ω0² + τ)/(2α): once a branch is faster than c it stays so, with θ̇ → ±∞
monotonically and θ → ∓∞. Each branch is therefore integrated until it first leaves the
*band* bottom < θ̇ < top, bottom = min(θ̇min, −c) − margin, top = max(θ̇max, c) + margin: all
of it that lies in the band is known, the rest lies beyond it. θ is monotone between zeros
of θ̇ (dθ/dτ = −θ̇), but a branch may fold, so branches are general parametric polylines.

**Topology** (checked when built: the end of L_0 must agree with
:func:`atlas.physics.running.limit_cycle`). Let P be the Poincaré map θ̇(s_0) ↦ θ̇(s_0 + 2π) of the
flow, increasing (orbits do not cross). Followed back from s_0, L_0 meets the previous saddle's
angle at the speed P⁻¹(0⁺), if 0⁺ is in P's range.

* *Bistable* (|τ| above the homoclinic torque, a running limit cycle exists). The unstable
  branch of s_{−1} that leaves to the right passes over s_0 (P(0⁺) > 0) and goes to the cycle;
  L_0 lies below it, so L_0 folds (θ̇ → 0) before s_{−1}, turns down and, like R_0, leaves
  the band at the bottom: L_0 ∪ R_0 bounds a tongue reaching down-right to θ̇ → −∞, the
  basin of well 0; the tongues of all wells are disjoint 2π translates, and the rest of the
  plane is the running basin (label :data:`RUNNING_SIDE`).
* *Monostable wells* (below the homoclinic torque, no cycle). The unstable branch falls back
  into well 0 and L_0 passes over s_{−1}, gaining speed every turn back (there P⁻¹(v) > v),
  and leaves the band at the top: Γ_j = L_j ∪ R_j runs from θ̇ = +∞ (left) to −∞ (right),
  and the basin of well k is the strip between Γ_{k−1} and Γ_k; the strips tile the plane.

In both cases the basin of well k lies on the right of Γ_k traversed along L_k towards s_k and
on along R_k (at s_k the well's unstable branch leaves to the lower left).

**Polylines.** Each branch is sampled from the dense output so that the chord error — the
distance of the dense output at the middle of each segment's time interval from its chord,
which for short segments is the largest distance of the arc from the chord to leading order
(κh²/8) — is at most ``CHORD_TOL`` (segments also at most ``MAX_SEGMENT`` long);
``chord_error`` records the largest measured. The first vertex of every branch is its saddle
itself. ``reference_error`` is the largest distance of the rtol 1e-12 polyline (sampled at the
same reversed times) from the 1e-13 one: the DOP853 reference's own error, overestimated
about tenfold.

**Side** (:meth:`TiltedBoundaries.side`): by the parity of crossings of the upward vertical ray
with each Γ_k (with their parts beyond the band: a branch that leaves at the top continues
left above the band, crossing every column left of its end once; one that leaves at the
bottom stays below every point in the band). Odd parity puts the point on the right of Γ_k:
in well k's tongue (bistable) or in a well ≤ k (monostable). Exact for the polylines.

**Distances** (:meth:`TiltedBoundaries.distance`): Euclidean distance to the nearest polyline
of all branch translates: a k-d tree over a coarse polyline (every few vertices) finds the
chords near the point, whose distance bounds the fine one to the chords' own deviation, and
exact point-to-segment distances are taken over the fine segments those bounds cannot
exclude (``_Segments``). Exact for the polylines; their error: ``chord_error`` +
``reference_error``.

**Areas** (:meth:`TiltedBoundaries.areas`): each well's closed polygon (a tongue closed along
θ̇ = bottom; a strip closed along θ̇ = bottom and θ̇ = top) clipped to the window by
Sutherland–Hodgman (exact for a simple polygon against a convex region; Sutherland &
Hodgman, Comm. ACM 17 (1974) 32) and measured by the shoelace formula. Error estimate: the
change from rtol 1e-12 to 1e-13, plus ``chord_error`` times the boundary length in the
window.

References: Krauskopf et al., Int. J. Bifurcation Chaos 15 (2005) 763 (computing stable
manifolds); Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5–6 (DOP853, dense output);
Levi, Hoppensteadt & Miranker, Q. Appl. Math. 36 (1978) 167 (the driven damped pendulum).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from atlas.boundaries.manifold import RTOL, RTOL_CHECK, START_DISTANCE, _DenseOutput
from atlas.kernels import ATTRACTOR_FILL
from atlas.physics.pendulum import Pendulum

__all__ = ["TiltedBoundaries", "TiltedAreas", "RUNNING_SIDE", "CHORD_TOL", "MAX_SEGMENT",
           "MARGIN"]

#: The side label of the running basin (the basin of the running limit cycle): the kernels'
#: ATTRACTOR_FILL, −32768, the attractor index of an orbit that settles in no well. Wells k
#: are |k| ≤ atlas.limits.MAX_WELL = 32767, so it names no well, and it survives int16.
RUNNING_SIDE = ATTRACTOR_FILL
#: Largest distance [rad-ish] of a branch from its polyline's chords, aimed for.
CHORD_TOL = 1e-8
#: Longest polyline segment [rad-ish] (keeps the coarse chords of the distance search short:
#: their length enters its pruning bound).
MAX_SEGMENT = 0.004
#: Default clearance [rad-ish] of the integrated band beyond the window's θ̇ range (and of the
#: boundary search beyond its θ range).
MARGIN = 2.0
_TWO_PI = 2.0 * math.pi
#: Default of :class:`TiltedBoundaries`' ``cycle``: find the limit cycle.
FIND_CYCLE = object()
_NEIGHBOURS = 8  # coarse vertices examined per point before the exactness test of distances
_CHUNK = 1 << 20  # fine segments measured at once (bounds the temporaries)
_STRIDE = 32  # at most this many fine segments per coarse chord in the distance search
_CHORD = 0.02  # and one coarse vertex at least every this much arc length [rad-ish]


class TiltedAreas(NamedTuple):
    """Exact area fractions of a window (:meth:`TiltedBoundaries.areas`).

    k:             the wells whose basins meet the window (int64).
    fraction:      each well's basin area ∩ window / window area.
    running:       the running basin's fraction (0 when there is no running limit cycle).
    error:         estimated error of each ``fraction``: the change from rtol 1e-12 to
                   1e-13 plus chord_error × that basin's boundary length in the window, over
                   the window area.
    running_error: the same for ``running`` (0 without a cycle).
    """

    k: np.ndarray
    fraction: np.ndarray
    running: float
    error: np.ndarray
    running_error: float


# --------------------------------------------------------------------------- integration

def _branch(p: Pendulum, sign: int, rtol: float, bottom: float, top: float):
    """DOP853 along the branch of the saddle (π − θ*, 0) of ``p`` (τ ≥ 0) arriving from the
    left (``sign`` −1, L) or right (+1, R), in reversed time from START_DISTANCE along the
    stable eigenvector, until θ̇ leaves (bottom, top). Returns (dense output of (θ, θ̇),
    reversed-time steps, 'top' or 'bottom')."""
    from scipy.integrate import solve_ivp

    tau, w2, a2 = p.torque, p.omega0**2, 2.0 * p.alpha
    s = p.saddle_angle
    e0, e1 = p.saddle_stable_direction()
    start = [s + sign * START_DISTANCE * e0, sign * START_DISTANCE * e1]

    def rhs(_, y):  # the flow reversed
        return [-y[1], a2 * y[1] + w2 * math.sin(y[0]) - tau]

    def above(_, y):
        return y[1] - top

    def below(_, y):
        return y[1] - bottom

    above.terminal = below.terminal = True
    above.direction, below.direction = 1, -1
    t_cap = 1e4 * (1.0 / p.alpha + 1.0 / p.omega0)
    sol = solve_ivp(rhs, (0.0, t_cap), start, method="DOP853", rtol=rtol, atol=rtol,
                    dense_output=True, events=(above, below))
    if sol.status != 1:
        raise RuntimeError(f"a stable branch did not leave the band ({sol.message})")
    return _DenseOutput.from_scipy([sol.sol]), sol.t, "top" if sol.t_events[0].size else "bottom"


def _refine(dense, t, tol: float, longest: float):
    """The polyline of ``dense`` (a curve of reversed time) through times ⊇ ``t``: (times,
    vertices (2, n), chord error). Its chord error — the distance of the dense output at the
    middle of each segment's time interval from the chord — is ≤ ``tol`` (it shrinks like
    the square of a segment, so a segment is cut into ⌈1.2√(error/tol)⌉ pieces), and no
    segment is longer than ``longest``. Each segment is measured once: only new pieces are
    measured again, and only new vertices evaluated."""
    y = dense(t)
    dev = np.full(t.size - 1, np.nan)
    for _ in range(12):
        todo = np.flatnonzero(np.isnan(dev))
        if todo.size == 0:
            return t, y, float(dev.max(initial=0.0))
        mid = dense(0.5 * (t[todo] + t[todo + 1]))
        (ax, ay), (bx, by) = y[:, todo], y[:, todo + 1]
        worst = _segment_distance(mid[0], mid[1], ax, ay, bx, by)
        pieces = np.ones(dev.size, np.int64)
        pieces[todo] = np.maximum(np.ceil(np.sqrt(worst / tol) * 1.2),
                                  np.ceil(np.hypot(bx - ax, by - ay) / longest))
        whole = pieces[todo] == 1
        dev[todo[whole]] = worst[whole]
        offset = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        t = np.append(np.repeat(t[:-1], pieces)
                      + offset * np.repeat(np.diff(t) / pieces, pieces), t[-1])
        new = np.append(offset > 0, False)
        grown = np.empty((2, t.size))
        grown[:, ~new] = y
        grown[:, new] = dense(t[new])
        y = grown
        dev = np.where(np.repeat(pieces, pieces) == 1, np.repeat(dev, pieces), np.nan)
    raise RuntimeError("the branch polyline did not reach its chord tolerance")


class _Fundamental:
    """Γ_0 = L_0 ∪ R_0 of the canonical pendulum ``p`` (τ > 0) as one polyline, from L_0's
    end through the saddle to R_0's end, at rtol ``rtol``; at ``times`` (the per-branch
    reversed times of another _Fundamental) if given, else refined to CHORD_TOL."""

    def __init__(self, p: Pendulum, rtol: float, bottom: float, top: float, times=None):
        self.times, self.ends, parts = [], [], []
        saddle = np.array([[p.saddle_angle], [0.0]])
        self.chord_error = 0.0
        for i, sign in enumerate((-1, 1)):
            dense, steps, end = _branch(p, sign, rtol, bottom, top)
            if times is None:
                t, xy, err = _refine(dense, steps, CHORD_TOL, MAX_SEGMENT)
                self.chord_error = max(self.chord_error, err)
            else:
                t = np.append(times[i][times[i] < steps[-1]], steps[-1])
                xy = dense(t)
            self.times.append(t)
            self.ends.append(end)
            parts.append(np.concatenate([saddle, xy], axis=1))
        self.left, self.right = parts
        self.theta, self.theta_dot = np.concatenate([self.left[:, ::-1], self.right[:, 1:]],
                                                    axis=1)

    @property
    def bistable(self) -> bool:
        """Whether L_0 turns down (leaves the band at the bottom): tongues, a running basin."""
        return self.ends[0] == "bottom"


# --------------------------------------------------------------------------- geometry

def _segment_distance(px, py, ax, ay, bx, by):
    """Distance from points p to segments [a, b] (arrays broadcast)."""
    dx, dy = bx - ax, by - ay
    qx, qy = px - ax, py - ay
    s = (qx * dx + qy * dy) / np.maximum(dx * dx + dy * dy, np.finfo(float).tiny)
    np.clip(s, 0.0, 1.0, out=s)
    return np.hypot(qx - s * dx, qy - s * dy)


class _Segments:
    """Nearest segments of polylines, exactly, in two levels. ``runs``: list of (θ, θ̇, tag)
    polylines (those of fewer than two vertices are dropped).

    The *coarse* polyline keeps every ``_STRIDE``-th vertex of each run, one at least every
    ``_CHORD`` of arc length, and its last. Each coarse chord c stands for the fine segments
    between its ends, which lie within δ_c of it (the largest distance of their vertices from
    it: a segment's distance from the chord is largest at an end), and every point of the
    chord lies within δ_c of them (it is the projection on the chord's line of some fine
    point, as the fine run goes from one end to the other). So the fine distance is at most
    D = min_c (d_c + δ_c) over any chords c at distances d_c, and only chords with
    d_c − δ_c ≤ D can hold the nearest fine segment. All those have an end within
    √((D + δ)² + Λ²/4) of the point (δ = max δ_c, Λ the longest chord: a chord at distance r
    has an end within √(r² + Λ²/4)): they are the chords at the k nearest coarse vertices (a
    k-d tree) when the k-th is farther than that, and are found by a ball query of that radius
    otherwise.

    Within chord c (length ℓ), a fine point whose projection on the chord's line lies ℓ|s − s*|
    from the point's (s the parameter along the chord) is at least √((ℓ(s − s*))² + h²) − δ_c
    away, h the point's distance from the line; so only the fine segments with
    ℓ|s − s*| ≤ √((D + δ_c)² − h²) can be the nearest, and only those are measured (all of a
    chord's when its fine vertices do not project in order). Exact for the fine polylines."""

    def __init__(self, runs):
        from scipy.spatial import cKDTree

        runs = [r for r in runs if r[0].size >= 2]
        self.empty = not runs
        if self.empty:
            return
        sizes = np.array([r[0].size for r in runs], np.int64)
        first = np.cumsum(sizes) - sizes
        self.x = np.concatenate([r[0] for r in runs])
        self.y = np.concatenate([r[1] for r in runs])
        # coarse vertices (fine indices); chord c joins fine vertices start[c] and stop[c]
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(self.x), np.diff(self.y)))])
        keep = []
        for n, f in zip(sizes, first):  # every _STRIDE-th vertex, and one per _CHORD of arc
            mark = np.floor((arc[f:f + n] - arc[f]) / _CHORD)
            turn = np.flatnonzero(np.diff(mark)) + 1
            keep.append(np.unique(np.concatenate([np.arange(0, n, _STRIDE), turn, [n - 1]]))
                        + f)
        vertex = np.concatenate(keep)
        last = np.cumsum([k.size for k in keep]) - 1
        self.start = np.delete(vertex, last)
        self.stop = np.delete(np.roll(vertex, -1), last)
        self.tag = np.concatenate([np.full(k.size - 1, r[2], np.int64)
                                   for k, r in zip(keep, runs)])
        chord = np.arange(self.start.size)
        run_of = np.repeat(np.arange(len(keep)), [k.size - 1 for k in keep])
        self.after = np.full(vertex.size, -1, np.int64)  # chords at each coarse vertex
        self.before = np.full(vertex.size, -1, np.int64)
        self.after[chord + run_of] = chord
        self.before[chord + run_of + 1] = chord
        ax, ay = self.x[self.start], self.y[self.start]
        dx, dy = self.x[self.stop] - ax, self.y[self.stop] - ay
        self.length = np.hypot(dx, dy)
        self.longest = float(self.length.max(initial=0.0))
        # each fine vertex's parameter s along its chord (the last one's: 1), as key c + s
        owner = np.repeat(chord, self.stop - self.start)
        fine = self._fine_segments(chord)
        ll = np.maximum(self.length**2, np.finfo(float).tiny)
        s = ((self.x[fine] - ax[owner]) * dx[owner] + (self.y[fine] - ay[owner]) * dy[owner]) \
            / ll[owner]
        self.key = np.empty(self.x.size)
        self.key[fine] = owner + np.clip(s, 0.0, 1.0)
        ends = first + sizes - 1
        self.key[ends] = np.searchsorted(self.start, ends) + 0.0  # last chord's + 1
        self.ordered = np.ones(chord.size, bool)
        step = np.diff(s) < 0
        np.logical_and.at(self.ordered, owner[1:][step & (owner[1:] == owner[:-1])], False)
        off = _segment_distance(self.x[fine], self.y[fine], ax[owner], ay[owner],
                                self.x[self.stop][owner], self.y[self.stop][owner])
        self.deviation = np.zeros(chord.size)  # δ_c
        np.maximum.at(self.deviation, owner, off)
        self.delta = float(self.deviation.max(initial=0.0))
        self.vertex = vertex
        self.tree = cKDTree(np.column_stack([self.x[vertex], self.y[vertex]]))

    def _fine_segments(self, chords):
        """The fine segments (by their first vertex) of each chord in turn."""
        count = self.stop[chords] - self.start[chords]
        return np.repeat(self.start[chords] - np.cumsum(count) + count, count) \
            + np.arange(count.sum())

    @staticmethod
    def _pairs(chords):
        """The distinct chords (≥ 0) of each row of ``chords``, as (row, chord) pairs sorted by
        row."""
        chords = np.sort(chords, axis=1)
        fresh = chords >= 0
        fresh[:, 1:] &= chords[:, 1:] != chords[:, :-1]
        rows, cols = np.nonzero(fresh)
        return rows, chords[rows, cols]

    def nearest(self, px, py):
        """(distance, tag of the nearest segment) for points (px, py): exact for the fine
        polylines (class docstring); (inf, 0) when there are none."""
        n = px.size
        if self.empty:
            return np.full(n, np.inf), np.zeros(n, np.int64)
        k = min(_NEIGHBOURS, self.vertex.size)
        pts = np.column_stack([px, py])
        dk, idx = self.tree.query(pts, k=k)
        dk, idx = dk.reshape(n, k), idx.reshape(n, k)
        who, chords = self._pairs(np.concatenate([self.before[idx], self.after[idx]], axis=1))
        d = self._chord_distance(px[who], py[who], chords)
        first = np.flatnonzero(np.r_[True, who[1:] != who[:-1]])
        bound = np.minimum.reduceat(d + self.deviation[chords], first)  # ≥ the fine distance
        radius = np.sqrt((bound + self.delta)**2 + 0.25 * self.longest**2) * (1 + 1e-12) \
            + 1e-15
        doubt = np.flatnonzero(dk[:, -1] <= radius) if k < self.vertex.size else []
        if len(doubt):  # all chords with an end within the radius, instead
            found = self.tree.query_ball_point(pts[doubt], radius[doubt])
            near = np.full((doubt.size, max(len(f) for f in found)), -1, np.int64)
            for row, f in enumerate(found):
                near[row, :len(f)] = f
            has = near >= 0
            rows, extra = self._pairs(np.concatenate([np.where(has, self.before[near], -1),
                                                      np.where(has, self.after[near], -1)],
                                                     axis=1))
            keep = ~np.isin(who, doubt)
            who = np.concatenate([who[keep], doubt[rows]])
            chords = np.concatenate([chords[keep], extra])
            d = np.concatenate([d[keep], self._chord_distance(px[doubt[rows]],
                                                              py[doubt[rows]], extra)])
        ok = d - self.deviation[chords] <= bound[who]
        return self._fine(px, py, who[ok], chords[ok], bound)

    def _chord_distance(self, px, py, chords):
        s, e = self.start[chords], self.stop[chords]
        return _segment_distance(px, py, self.x[s], self.y[s], self.x[e], self.y[e])

    def _fine(self, px, py, who, chords, bound):
        """Distances to the fine segments of the candidate chords that can be nearer than
        ``bound``."""
        s, e = self.start[chords], self.stop[chords]
        ax, ay = self.x[s], self.y[s]
        dx, dy = self.x[e] - ax, self.y[e] - ay
        ll = np.maximum(self.length[chords], np.finfo(float).tiny)
        qx, qy = px[who] - ax, py[who] - ay
        along = (qx * dx + qy * dy) / ll  # ℓ·s*
        h = np.abs(qx * dy - qy * dx) / ll
        reach = bound[who] + self.deviation[chords]
        width = np.sqrt(np.maximum(reach**2 - h * h, 0.0)) * (1 + 1e-9) + 1e-15
        lo = np.searchsorted(self.key, chords + (along - width) / ll, "right") - 1
        hi = np.searchsorted(self.key, chords + (along + width) / ll, "left")
        whole = ~self.ordered[chords]
        lo = np.where(whole, s, np.clip(lo, s, e - 1))
        hi = np.where(whole, e, np.clip(hi, lo + 1, e))
        count = hi - lo
        d_pair = np.empty(who.size)
        bounds = np.searchsorted(np.cumsum(count), np.arange(1, 1 + count.sum() // _CHUNK)
                                 * _CHUNK)
        for part in np.split(np.arange(who.size), np.unique(bounds)):
            c, w, l0 = count[part], who[part], lo[part]
            seg = np.repeat(l0 - np.cumsum(c) + c, c) + np.arange(c.sum())
            pw = np.repeat(w, c)
            d = _segment_distance(px[pw], py[pw], self.x[seg], self.y[seg], self.x[seg + 1],
                                  self.y[seg + 1])
            d_pair[part] = np.minimum.reduceat(d, np.cumsum(c) - c) if part.size else d
        order = np.lexsort((d_pair, who))  # by point, nearest first
        head = order[np.r_[True, who[order][1:] != who[order][:-1]]]
        dist = np.full(px.size, np.inf)
        tag = np.zeros(px.size, np.int64)
        dist[who[head]] = d_pair[head]
        tag[who[head]] = self.tag[chords[head]]
        return dist, tag


def _clip(x, y, axis: int, level: float, keep_above: bool):
    """Sutherland–Hodgman: the closed polygon (x, y) clipped to the half-plane
    {coordinate ``axis`` ≥ level} (``keep_above``) or ≤ level."""
    if x.size == 0:
        return x, y
    c = x if axis == 0 else y
    s = c - level if keep_above else level - c
    inside = s >= 0
    x1, y1, s1, in1 = np.roll(x, -1), np.roll(y, -1), np.roll(s, -1), np.roll(inside, -1)
    cross = inside != in1
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(cross, s / (s - s1), 0.0)
    cx, cy = x + f * (x1 - x), y + f * (y1 - y)
    if axis == 0:
        cx = np.where(cross, level, cx)
    else:
        cy = np.where(cross, level, cy)
    keep = np.column_stack([cross, in1]).ravel()
    return (np.column_stack([cx, x1]).ravel()[keep], np.column_stack([cy, y1]).ravel()[keep])


def _shoelace(x, y) -> float:
    """|area| of the closed polygon (x, y) (coordinates should be centred, for rounding)."""
    if x.size < 3:
        return 0.0
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)))


def _inside_length(x, y, box) -> float:
    """Length of the polyline's segments whose ends both lie in ``box`` (≈ its length in it)."""
    (a, b), (lo, hi) = box
    inside = (x >= a) & (x <= b) & (y >= lo) & (y <= hi)
    both = inside[:-1] & inside[1:]
    return float(np.hypot(np.diff(x), np.diff(y))[both].sum())


# --------------------------------------------------------------------------- the boundaries

class TiltedBoundaries:
    """The exact basin boundaries of ``pendulum`` (α > 0, 0 < |τ| < ω0²) for the window
    θ ∈ ``theta_window`` [rad] × θ̇ ∈ ``theta_dot_window`` [rad s⁻¹] (module docstring).

    The branches are integrated over the band of θ̇ reaching ``margin`` [rad-ish] beyond the
    window (and beyond ±(ω0² + |τ|)/(2α)); :meth:`side` answers for any θ and θ̇ in that
    band, :meth:`distance` for any point.

    Attributes: ``pendulum``; ``window``; ``bistable`` (a running limit cycle exists, checked
    against :func:`atlas.physics.running.limit_cycle`); ``cycle`` (that limit cycle, or None);
    ``band`` (bottom, top) [rad s⁻¹] in the actual frame; ``chord_error`` and
    ``reference_error`` [rad-ish] (module docstring). It pickles without its distance
    search indices, which are rebuilt on first use.
    """

    def __init__(self, pendulum: Pendulum, theta_window, theta_dot_window, *,
                 rtol: float = RTOL, margin: float = MARGIN, cycle=FIND_CYCLE):
        """``cycle``: :func:`atlas.physics.running.limit_cycle`'s result for this pendulum if the
        caller has it (None: there is none); found here by default."""
        from atlas.physics.running import limit_cycle

        p = self.pendulum = pendulum
        if not p.alpha > 0.0:
            raise ValueError("the stable manifolds bound basins only for alpha > 0")
        if p.torque == 0.0 or not p.has_rest_states:
            raise ValueError(f"torque must satisfy 0 < |torque| < omega0² (got "
                             f"{p.torque!r}); for torque 0 use atlas.boundaries.manifold")
        (a, b), (v0, v1) = theta_window, theta_dot_window
        if not (a < b and v0 < v1 and margin > 0):
            raise ValueError("the window must have theta_min < theta_max and "
                             "theta_dot_min < theta_dot_max, and margin > 0")
        self.window = ((float(a), float(b)), (float(v0), float(v1)))
        self.rtol, self.margin = rtol, float(margin)
        self.sign = 1 if p.torque > 0 else -1
        canon = Pendulum(p.alpha, p.omega0, abs(p.torque))
        ceiling = (p.omega0**2 + abs(p.torque)) / (2.0 * p.alpha)
        lo, hi = sorted((self.sign * v0, self.sign * v1))
        self._band = (min(lo, -ceiling) - margin, max(hi, ceiling) + margin)  # canonical
        self.band = tuple(sorted(self.sign * v for v in self._band))
        self._fine = _Fundamental(canon, rtol, *self._band)
        self._coarse = _Fundamental(canon, RTOL_CHECK, *self._band, times=self._fine.times)
        if self._fine.ends[1] != "bottom" or self._coarse.ends != self._fine.ends:
            raise RuntimeError(f"unexpected stable branches: ends {self._fine.ends} "
                               f"(rtol {rtol:g}), {self._coarse.ends} ({RTOL_CHECK:g})")
        self.bistable = self._fine.bistable
        self.cycle = (limit_cycle(p.alpha, p.omega0, p.torque) if cycle is FIND_CYCLE
                      else cycle)
        if (self.cycle is not None) != self.bistable:
            raise RuntimeError("the stable branch L_0 disagrees with atlas.physics.running about the "
                               "running limit cycle (too close to the homoclinic torque?)")
        self.chord_error = self._fine.chord_error
        self.reference_error = self._reference_error()
        self._pieces = self._monotone_pieces()
        self._indices = {}

    def __getstate__(self):  # sent to workers without the distance indices (rebuilt there)
        return {**self.__dict__, "_indices": {}}

    # ------------------------------------------------------------------ frames
    def _canonical(self, theta, theta_dot):
        theta, theta_dot = np.broadcast_arrays(np.asarray(theta, float),
                                               np.asarray(theta_dot, float))
        return self.sign * theta, self.sign * theta_dot

    def _canonical_window(self):
        (a, b), (v0, v1) = self.window
        return tuple(sorted((self.sign * a, self.sign * b))), \
            tuple(sorted((self.sign * v0, self.sign * v1)))

    def _saddle(self, j):
        """The actual saddle index of the canonical saddle s_j: j, or −j − 1 mirrored
        (−(π − θ* + 2πj) = π + θ* − 2π(j + 1))."""
        return j if self.sign > 0 else -j - 1

    def saddle_theta(self, j: int) -> float:
        """θ [rad] of the saddle s_j = π − arcsin(τ/ω0²) + 2πj."""
        return self.pendulum.saddle_angle + _TWO_PI * j

    def _translates(self, theta_lo: float, theta_hi: float) -> range:
        """Canonical k whose Γ_k (within the band) reaches θ ∈ [theta_lo, theta_hi]."""
        f = self._fine
        return range(math.floor((theta_lo - f.theta.max()) / _TWO_PI),
                     math.ceil((theta_hi - f.theta.min()) / _TWO_PI) + 1)

    def _reference_error(self) -> float:
        """Largest distance of the rtol 1e-12 polyline's vertices from the 1e-13 polyline
        (canonical frame, Γ_0 only: the translates are exact copies). Both are sampled at
        the same reversed times, so each coarse vertex is compared with the two fine segments
        at its own index (an overestimate wherever its foot lies farther along)."""
        worst = 0.0
        for fine, coarse in ((self._fine.left, self._coarse.left),
                             (self._fine.right, self._coarse.right)):
            n = min(fine.shape[1], coarse.shape[1])
            (fx, fy), (cx, cy) = fine[:, :n], coarse[:, :n]
            before = _segment_distance(cx[1:], cy[1:], fx[:-1], fy[:-1], fx[1:], fy[1:])
            after = _segment_distance(cx[:-1], cy[:-1], fx[:-1], fy[:-1], fx[1:], fy[1:])
            dist = np.minimum(np.append(np.inf, before), np.append(after, np.inf))
            worst = max(worst, float(dist.max(initial=0.0)))
        return worst

    # ------------------------------------------------------------------ curves
    def curves(self, clip: bool = True):
        """The branches that meet the window: a list of (saddle index j, branch 'left' or
        'right', θ [rad], θ̇ [rad s⁻¹]) in the actual frame, each from its saddle outward
        (the first vertex is the saddle itself) to where it leaves the band. With ``clip``,
        only the parts in the window (each run of vertices inside, with one vertex beyond
        either end so that it reaches the window's edge), one entry per run."""
        (a, b), (v0, v1) = self.window
        ct, _ = self._canonical_window()
        out = []
        f = self._fine
        for k in self._translates(*ct):
            for name, xy in (("left", f.left), ("right", f.right)):
                theta = self.sign * (xy[0] + _TWO_PI * k)
                theta_dot = self.sign * xy[1]
                branch = name if self.sign > 0 else {"left": "right", "right": "left"}[name]
                j = self._saddle(k)
                if not clip:
                    out.append((j, branch, theta, theta_dot))
                    continue
                inside = (theta >= a) & (theta <= b) & (theta_dot >= v0) & (theta_dot <= v1)
                near = inside.copy()
                near[1:] |= inside[:-1]
                near[:-1] |= inside[1:]
                edges = np.flatnonzero(np.diff(np.concatenate([[0], near, [0]]).astype(int)))
                for start, stop in zip(edges[::2], edges[1::2]):
                    out.append((j, branch, theta[start:stop], theta_dot[start:stop]))
        return out

    # ------------------------------------------------------------------ side
    def _monotone_pieces(self):
        """Γ_0's polyline cut where θ turns: (θ ascending, θ̇ there) per piece, for the
        vertical-ray crossings (each piece covers θ ∈ [min, max), as its segments do)."""
        f = self._fine
        step = np.sign(np.diff(f.theta))
        cuts = np.concatenate([[0], np.flatnonzero(step[1:] != step[:-1]) + 1,
                               [f.theta.size - 1]])
        pieces = []
        for i, j in zip(cuts[:-1], cuts[1:]):
            x, y = f.theta[i:j + 1], f.theta_dot[i:j + 1]
            if x[0] == x[-1]:
                continue
            if x[0] > x[-1]:
                x, y = x[::-1], y[::-1]
            pieces.append((x, y))
        return pieces

    def side(self, theta, theta_dot):
        """The basin of the exact equation each point (θ [rad], θ̇ [rad s⁻¹], broadcast) lies
        in: the well k (rest state (arcsin(τ/ω0²) + 2πk, 0), the kernels' ``attractor``), or
        :data:`RUNNING_SIDE` for the running basin. Exact for the polylines (points within
        ``chord_error`` + ``reference_error`` of a boundary may get the other side). θ̇ must
        lie within ``band``; ValueError otherwise."""
        x, v = self._canonical(theta, theta_dot)
        shape = x.shape
        x, v = x.ravel(), v.ravel()
        bottom, top = self._band
        if not np.all((v > bottom) & (v < top)):
            raise ValueError(f"theta_dot must lie within the band {self.band} of the "
                             "integrated boundaries")
        if x.size == 0:
            return np.zeros(shape, np.int64)
        order = np.argsort(x, kind="stable")
        xs, vs = x[order], v[order]
        ks = self._translates(xs[0], xs[-1])
        f = self._fine
        top_end = f.theta[0] if f.ends[0] == "top" else None
        label = np.full(x.size, RUNNING_SIDE if self.bistable else ks.start, np.int64)
        odd = np.zeros(x.size, bool)
        for k in ks:
            odd[:] = False
            shift = _TWO_PI * k
            for px, py in self._pieces:
                i0, i1 = np.searchsorted(xs, [px[0] + shift, px[-1] + shift])
                if i1 > i0:
                    odd[i0:i1] ^= np.interp(xs[i0:i1] - shift, px, py) > vs[i0:i1]
            if top_end is not None:  # L_k continues left above the band
                odd[:np.searchsorted(xs, top_end + shift)] ^= True
            if self.bistable:
                label[odd] = k
            else:
                label += ~odd  # well k' < smallest k with odd parity
        out = np.empty(x.size, np.int64)
        out[order] = label
        if self.sign < 0:
            out = np.where(out == RUNNING_SIDE, out, -out)
        return out.reshape(shape)

    # ------------------------------------------------------------------ distance
    def _index(self, theta_lo: float, theta_hi: float) -> _Segments:
        """The segments of every Γ_k (canonical) with a vertex in θ ∈ [lo, hi], and their
        neighbours (the last two indices are kept)."""
        key = (theta_lo, theta_hi)
        if key not in self._indices:
            f = self._fine
            runs = []
            for k in self._translates(theta_lo, theta_hi):
                x = f.theta + _TWO_PI * k
                inside = (x >= theta_lo) & (x <= theta_hi)
                near = inside.copy()
                near[1:] |= inside[:-1]
                near[:-1] |= inside[1:]
                edges = np.flatnonzero(np.diff(np.concatenate([[0], near, [0]]).astype(int)))
                for start, stop in zip(edges[::2], edges[1::2]):
                    runs.append((x[start:stop], f.theta_dot[start:stop], k))
            self._indices = {**dict(list(self._indices.items())[-1:]), key: _Segments(runs)}
        return self._indices[key]

    def distance(self, theta, theta_dot):
        """(distance, saddle): the Euclidean distance [rad-ish, θ and θ̇ as one unit] from each
        point (θ [rad], θ̇ [rad s⁻¹], broadcast) to the nearest basin boundary, and the index j
        of that boundary's saddle s_j (the translate of the branches through it).

        The boundaries within θ ± ``margin`` of the points are searched first, then, for
        points farther than that from all of them, those within θ ± the distance found (no
        nearer boundary can lie beyond), and so on. Exact for the polylines wherever the
        distance is at most the point's clearance from the band's edges beyond which the
        boundaries continue (the bottom, and the top when the branches leave there:
        ``bistable`` false); for points of the window that is at least ``margin``. The
        error: ``chord_error`` + ``reference_error``."""
        x, v = self._canonical(theta, theta_dot)
        shape = x.shape
        x, v = x.ravel(), v.ravel()
        if x.size == 0:
            return np.zeros(shape), np.zeros(shape, np.int64)
        dist, k = np.full(x.size, np.inf), np.zeros(x.size, np.int64)
        todo, reach = np.arange(x.size), self.margin
        while todo.size:
            lo, hi = float(x[todo].min()), float(x[todo].max())
            index = self._index(lo - reach - MAX_SEGMENT, hi + reach + MAX_SEGMENT)
            dist[todo], k[todo] = index.nearest(x[todo], v[todo])
            todo = todo[dist[todo] > reach]
            # none nearer than the distance found lies beyond it (a whole turn if none found)
            reach = float(dist[todo].max(initial=reach + _TWO_PI)) \
                if np.all(np.isfinite(dist[todo])) else reach + _TWO_PI
        return dist.reshape(shape), self._saddle(k).reshape(shape)

    # ------------------------------------------------------------------ areas
    def _polygon(self, f: _Fundamental):
        """Well 0's basin ∩ {bottom < θ̇ < top} (canonical) as a closed polygon: the tongue
        Γ_0 closed along θ̇ = bottom, or the strip between Γ_{−1} and Γ_0 closed along
        θ̇ = bottom and θ̇ = top."""
        if self.bistable:
            return f.theta, f.theta_dot
        return (np.concatenate([f.theta, f.theta[::-1] - _TWO_PI]),
                np.concatenate([f.theta_dot, f.theta_dot[::-1]]))

    def _fractions(self, f: _Fundamental, ks, window):
        """Area fraction of ``window`` (canonical) in well k's basin, for each k in ``ks``,
        and the boundary length in the window (for the chord error)."""
        (a, b), (lo, hi) = window
        cx, cy = 0.5 * (a + b), 0.5 * (lo + hi)  # centred coordinates for the shoelace
        x, y = self._polygon(f)
        x, y = _clip(*_clip(x, y, 1, lo, True), 1, hi, False)
        area = (b - a) * (hi - lo)
        fractions, lengths = [], []
        for k in ks:
            shift = _TWO_PI * k
            px, py = _clip(*_clip(x + shift - cx, y - cy, 0, a - cx, True), 0, b - cx, False)
            fractions.append(_shoelace(px, py) / area)
            box = ((a - shift, b - shift), (lo, hi))
            length = _inside_length(f.theta, f.theta_dot, box)
            if not self.bistable:
                length += _inside_length(f.theta, f.theta_dot, ((a - shift + _TWO_PI,
                                                                  b - shift + _TWO_PI),
                                                                 (lo, hi)))
            lengths.append(length)
        return np.array(fractions), np.array(lengths)

    def areas(self) -> TiltedAreas:
        """The exact area fraction of the window in each well's basin and in the running basin
        (:class:`TiltedAreas`; module docstring). The fractions sum to 1 (to their errors)."""
        window = self._canonical_window()
        (a, b), (lo, hi) = window
        ks = self._translates(a, b)
        if not self.bistable:  # the strip of well k lies between Γ_{k−1} and Γ_k
            ks = range(ks.start, ks.stop + 1)
        fine, length = self._fractions(self._fine, ks, window)
        coarse, _ = self._fractions(self._coarse, ks, window)
        scale = self.chord_error / ((b - a) * (hi - lo))
        error = np.abs(fine - coarse) + scale * length + 4 * np.finfo(float).eps
        running = running_error = 0.0
        if self.bistable:
            running = 1.0 - float(fine.sum())
            running_error = float(abs(fine.sum() - coarse.sum()) + scale * length.sum()
                                  + 4 * np.finfo(float).eps)
        keep = fine > 0.0
        k = self.sign * np.array(ks, np.int64)[keep]
        order = np.argsort(k)
        return TiltedAreas(k=k[order], fraction=fine[keep][order], running=running,
                           error=error[keep][order], running_error=running_error)
