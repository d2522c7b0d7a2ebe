"""Polylines, compiled: made from a dense output, and against points (the nearest segment, or
the nearest arc of the curve it is a chord of, and the vertical ray's crossings).

The tilted basin boundaries (:mod:`atlas.boundaries.tilted`) are polylines of some 10⁴–10⁵
short segments each, cut from DOP853's dense output by :func:`refine` until every chord lies
within a tolerance of the curve; the untilted trace's vertices are walked along L's dense
output by :func:`walk` (chords within a spacing and the curvature's share of it).
:func:`build` groups the segments, in their order along the curves, into a bounding-volume
hierarchy: ``FAN`` consecutive segments per leaf box, ``FAN`` boxes
per box of the level above, until at most ``FAN`` boxes remain (consecutive pieces of a
smooth curve have tight boxes). :func:`nearer_curves` finds, per point (``prange``:
independent of the thread count), the Euclidean distance to the nearest of the curves the
segments are chords of, and its tag, by a depth-first search, nearest box first, that skips
every box farther than the best distance found plus a slack (each arc within it of its
chord: the box distance less the slack is a lower bound) and measures each arc within reach
by Newton's method on its piece of the dense output: exact for the dense output (for
straight pieces and no slack, exact for the polylines). Each search starts from the leaf of
the previous point's nearest segment (neighbours on a grid share their nearest boundary: a
tight first bound), and from a bound the caller knows (a search among fewer segments
before).
:func:`ray_sides` counts, per point, the crossings of the upward vertical ray with the
segments of each tag (a segment covers θ ∈ [min, max) of its ends, its θ̇ at θ by linear
interpolation), for the side rule of :meth:`atlas.boundaries.tilted.TiltedBoundaries.side`:
one column of equal θ at a time for a grid, in one walk of the hierarchy for scattered
points. References: Ericson, *Real-Time Collision Detection* (2005), ch. 6 (bounding-volume
hierarchies, ordered traversal); docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import cached_njit
from atlas.kernels.dop853 import dense_component, dense_step

__all__ = ["FAN", "refine", "walk", "build", "nearer_curves", "ray_sides"]

#: Children per box of the hierarchy (segments per leaf box).
FAN = 16
_CHUNK = 256  # points per parallel task of nearer_curves (each seeds the next search)
#: :func:`ray_sides` walks the hierarchy once for all points (instead of once per column of
#: equal θ) when they hold fewer than this many a column on average (measured on the tilted
#: boundaries: scattered points ~2 µs each instead of ~13 µs; equal near 64 a column).
_SWEEP_BELOW = 32
#: Generations of cuts :func:`refine` may make (a chord cut into pieces is one generation
#: older than its pieces): a chord that would be cut beyond them fails the refinement.
MAX_GENERATIONS = 11
_TINY = 2.2250738585072014e-308  # the smallest normal double: a zero-length chord's divisor
#: Newton iterations for the nearest point of a curve piece (quadratic convergence from its
#: chord's nearest point, within a chord tolerance of it).
NEWTON = 4
#: A Newton step of :func:`_curve_distance2` this small (in the step's unit time x ∈ [0, 1])
#: ends it: the next would move x by its square.
_CONVERGED = 1e-9


@nb.njit(inline="always")
def _dense_at(tau, hint, t, t_old, h, y_old):
    """The step of the dense output that holds ``tau``: ``hint`` if it does (its step ends in
    ``t``), else found by bisection; and x = (τ − t_old)/h there (as
    :func:`atlas.kernels.dop853.dense_output`: the same step, the same doubles)."""
    last = h.size - 1
    if hint <= last and t[hint] <= tau < t[hint + 1]:
        step = hint
    else:
        step = dense_step(tau, t, last)
    return step, (tau - t_old[step]) / h[step]


@nb.njit(inline="always")
def _chord_distance(px, py, ax, ay, bx, by):
    """Distance from a point to a chord [a, b], as
    :func:`atlas.boundaries.segments.segment_distance` (the same operations in the same order:
    the same doubles)."""
    dx, dy = bx - ax, by - ay
    qx, qy = px - ax, py - ay
    s = (qx * dx + qy * dy) / max(dx * dx + dy * dy, _TINY)
    s = min(max(s, 0.0), 1.0)
    return math.hypot(qx - s * dx, qy - s * dy)


@cached_njit(nogil=True)
def refine(times, t, t_old, h, y_old, F, tol, longest):
    """The polyline of a dense output (step ends ``t``, ``t_old``, ``h``, ``y_old`` (steps,
    2), ``F`` (steps, powers, 2) highest power first: :func:`atlas.kernels.dop853.dense_output`)
    through the times ``times`` (increasing) and as many more as its chords need: every chord
    — its distance from the dense output at the middle of its time interval, measured once —
    within ``tol`` and no longer than ``longest`` [rad-ish]. A chord that is not is cut into
    max(⌈1.2√(distance/tol)⌉, ⌈length/longest⌉) pieces of equal time (the distance shrinks
    like the square of a piece), each measured in turn, at most ``MAX_GENERATIONS`` deep.

    Returns (times (n,), vertices (2, n), largest chord distance, ok): chord by chord in time
    order, depth first, the same doubles as cutting every chord of a generation at once (the
    numpy loop this replaces); ``ok`` false when the generations ran out."""
    capacity = 2 * times.size + 16
    out_t, out_xy = np.empty(capacity), np.empty((2, capacity))
    # the chords still to measure, last in first out: (start, end) times and vertices, and
    # generation; a chord's pieces are pushed last first, so they are measured in order
    st_t = np.empty((MAX_GENERATIONS * 64, 2))
    st_y = np.empty((MAX_GENERATIONS * 64, 4))
    st_gen = np.empty(MAX_GENERATIONS * 64, np.int64)
    out_t[0] = times[0]
    step, x = _dense_at(times[0], 0, t, t_old, h, y_old)
    out_xy[0, 0] = dense_component(F, step, 0, x, y_old)
    out_xy[1, 0] = dense_component(F, step, 1, x, y_old)
    n, worst_all = 1, 0.0
    for i in range(times.size - 1):
        hint = step  # the step of the chord's start: usually holds the whole chord
        sp = 1
        st_t[0, 0], st_t[0, 1] = times[i], times[i + 1]
        st_y[0, 0], st_y[0, 1] = out_xy[0, n - 1], out_xy[1, n - 1]
        step, x = _dense_at(times[i + 1], hint, t, t_old, h, y_old)
        st_y[0, 2] = dense_component(F, step, 0, x, y_old)
        st_y[0, 3] = dense_component(F, step, 1, x, y_old)
        st_gen[0] = 0
        while sp > 0:
            sp -= 1
            ta, tb, gen = st_t[sp, 0], st_t[sp, 1], st_gen[sp]
            ax, ay, bx, by = st_y[sp, 0], st_y[sp, 1], st_y[sp, 2], st_y[sp, 3]
            mid_step, x = _dense_at(0.5 * (ta + tb), hint, t, t_old, h, y_old)
            worst = _chord_distance(dense_component(F, mid_step, 0, x, y_old),
                                    dense_component(F, mid_step, 1, x, y_old), ax, ay, bx, by)
            pieces = int(max(math.ceil(math.sqrt(worst / tol) * 1.2),
                             math.ceil(math.hypot(bx - ax, by - ay) / longest)))
            if pieces <= 1:  # measured whole (0: a point): its end is the next vertex
                worst_all = max(worst_all, worst)
                if n == out_t.size:
                    grown_t, grown_xy = np.empty(2 * n), np.empty((2, 2 * n))
                    grown_t[:n], grown_xy[:, :n] = out_t, out_xy
                    out_t, out_xy = grown_t, grown_xy
                out_t[n], out_xy[0, n], out_xy[1, n] = tb, bx, by
                n += 1
                continue
            if gen + 1 >= MAX_GENERATIONS:
                return out_t[:n], out_xy[:, :n], worst_all, False
            if sp + pieces > st_gen.size:
                size = 2 * (sp + pieces)
                grown_st_t, grown_st_y = np.empty((size, 2)), np.empty((size, 4))
                grown_gen = np.empty(size, np.int64)
                grown_st_t[:sp], grown_st_y[:sp], grown_gen[:sp] = st_t[:sp], st_y[:sp], \
                    st_gen[:sp]
                st_t, st_y, st_gen = grown_st_t, grown_st_y, grown_gen
            span = (tb - ta) / float(pieces)
            end_t, end_x, end_y = tb, bx, by
            for o in range(pieces - 1, -1, -1):  # the last piece pushed first
                start_t = ta + float(o) * span
                if o > 0:
                    piece_step, x = _dense_at(start_t, hint, t, t_old, h, y_old)
                    start_x = dense_component(F, piece_step, 0, x, y_old)
                    start_y = dense_component(F, piece_step, 1, x, y_old)
                else:
                    start_x, start_y = ax, ay
                st_t[sp, 0], st_t[sp, 1] = start_t, end_t
                st_y[sp, 0], st_y[sp, 1], st_y[sp, 2], st_y[sp, 3] = start_x, start_y, \
                    end_x, end_y
                st_gen[sp] = gen + 1
                sp += 1
                end_t, end_x, end_y = start_t, start_x, start_y
    return out_t[:n], out_xy[:, :n], worst_all, True


@nb.njit(inline="always")
def _dense_point(tau, t, t_old, h, y_old, F, tau_end):
    """(θ, θ̇) of a dense output at τ clipped to [0, tau_end] (the step by bisection)."""
    tau = min(max(tau, 0.0), tau_end)
    step = dense_step(tau, t, h.size - 1)
    x = (tau - t_old[step]) / h[step]
    return dense_component(F, step, 0, x, y_old), dense_component(F, step, 1, x, y_old)


@cached_njit(nogil=True)
def walk(t, t_old, h, y_old, F, tau0, tau_end, max_spacing, alpha, omega0, torque, boxes,
         fine, chord_aim, speed_growth, most):
    """The reversed times [s] of vertices along an orbit's dense output (``t``, ``t_old``,
    ``h``, ``y_old``, ``F`` highest power first: :func:`atlas.kernels.dop853.dense_output`'s;
    θ and θ̇ its first two components) of θ̈ = τ − ω0² sin θ − 2αθ̇, from ``tau0`` to
    ``tau_end``: from each vertex y the next is the first whose chord from y is at most
    h = max_spacing·min(1, 1/√κ) (κ the orbit's curvature at y [rad⁻¹]; with ``boxes``
    (m, 4) rows (θ lo, θ hi, θ̇ lo, θ̇ hi) also at most max(``fine``, half the distance to
    the nearest box)), aiming at ``chord_aim``·h, the step in τ also at most
    ``speed_growth``/|d ln|f|/dτ| (the speed grows fast next to a saddle). Returns (times,
    ok): ok false when more than ``most`` vertices would be needed."""
    w2, a2 = omega0 * omega0, 2.0 * alpha
    out = np.empty(1024)
    n = 0
    tau = tau0
    y0, y1 = _dense_point(tau, t, t_old, h, y_old, F, tau_end)
    out[n] = tau
    n += 1
    while tau < tau_end:
        if n > most:
            return out[:n], False
        f0 = y1
        f1 = (torque - w2 * math.sin(y0)) - a2 * y1
        g0, g1 = f1, -w2 * math.cos(y0) * f0 - a2 * f1  # J·f, the acceleration
        speed = math.hypot(f0, f1)
        kappa = abs(f0 * g1 - f1 * g0) / speed**3
        growth = abs(f0 * g0 + f1 * g1) / speed**2
        longest = max_spacing * min(1.0, 1.0 / math.sqrt(kappa)) if kappa > 0 else max_spacing
        if boxes.shape[0]:
            near = math.inf
            for b in range(boxes.shape[0]):
                dx = max(boxes[b, 0] - y0, 0.0, y0 - boxes[b, 1])
                dy = max(boxes[b, 2] - y1, 0.0, y1 - boxes[b, 3])
                near = min(near, math.hypot(dx, dy))
            longest = min(longest, max(fine, 0.5 * near))
        span = min(chord_aim * longest / speed, speed_growth / max(growth, 1e-300))
        while True:
            nxt = min(tau + span, tau_end)
            z0, z1 = _dense_point(nxt, t, t_old, h, y_old, F, tau_end)
            chord = math.hypot(z0 - y0, z1 - y1)
            if chord <= longest:
                break
            span = (nxt - tau) * chord_aim * longest / chord
        if n == out.size:
            grown = np.empty(2 * n)
            grown[:n] = out
            out = grown
        out[n] = nxt
        n += 1
        tau, y0, y1 = nxt, z0, z1
    return out[:n], True


@cached_njit(nogil=True)
def build(ax, ay, bx, by):
    """The hierarchy over the segments (ax, ay) → (bx, by), in their order: (xlo, xhi, ylo,
    yhi) of every box, level by level from the leaves up, and each level's first box
    (levels + 1 entries, the last one the total)."""
    n = ax.size
    counts = [max(1, (n + FAN - 1) // FAN)]
    while counts[-1] > FAN:
        counts.append((counts[-1] + FAN - 1) // FAN)
    start = np.zeros(len(counts) + 1, np.int64)
    for i in range(len(counts)):
        start[i + 1] = start[i] + counts[i]
    total = start[-1]
    xlo, xhi = np.full(total, np.inf), np.full(total, -np.inf)
    ylo, yhi = np.full(total, np.inf), np.full(total, -np.inf)
    for s in range(n):  # the leaves: FAN segments each
        b = s // FAN
        xlo[b] = min(xlo[b], ax[s], bx[s])
        xhi[b] = max(xhi[b], ax[s], bx[s])
        ylo[b] = min(ylo[b], ay[s], by[s])
        yhi[b] = max(yhi[b], ay[s], by[s])
    for level in range(1, len(counts)):
        for c in range(counts[level - 1]):
            child, b = start[level - 1] + c, start[level] + c // FAN
            xlo[b] = min(xlo[b], xlo[child])
            xhi[b] = max(xhi[b], xhi[child])
            ylo[b] = min(ylo[b], ylo[child])
            yhi[b] = max(yhi[b], yhi[child])
    return xlo, xhi, ylo, yhi, start


@nb.njit(inline="always")
def _box_distance2(x, y, xlo, xhi, ylo, yhi):
    """The squared distance from (x, y) to a box (0 inside)."""
    dx = max(xlo - x, 0.0, x - xhi)
    dy = max(ylo - y, 0.0, y - yhi)
    return dx * dx + dy * dy


@nb.njit(inline="always")
def _segment_distance2(px, py, ax, ay, bx, by):
    """The squared distance from a point to a segment (as
    :func:`atlas.boundaries.segments.segment_distance`, squared: no root in the search)."""
    dx, dy = bx - ax, by - ay
    qx, qy = px - ax, py - ay
    s = (qx * dx + qy * dy) / max(dx * dx + dy * dy, 2.2250738585072014e-308)
    s = min(max(s, 0.0), 1.0)
    ex, ey = qx - s * dx, qy - s * dy
    return ex * ex + ey * ey


@cached_njit(parallel=True, nogil=True)
def nearer_curves(px, py, ax, ay, bx, by, tag, xlo, xhi, ylo, yhi, start, searched_lo,
                  searched_hi, slack, step, span, shift, F, y_old, dist2, near_tag, foot_x,
                  foot_y):
    """Per point (px, py), the nearest of the curves the chords stand for, from known
    bounds, on squared distances (the hierarchy from :func:`build`): segment s is the chord
    of the dense output's polynomial of step ``step[s]`` (``F``, ``y_old``:
    :func:`atlas.kernels.dop853.dense_output`'s) over x ∈ [``span[s, 0]``, ``span[s, 1]``],
    moved by (``shift[s]``, 0), and lies within ``slack`` [rad-ish] of it (a straight piece:
    ``step[s]`` = −1, the chord itself). Each point's squared distance to the nearest curve
    (:func:`_curve_distance2`: Newton's method on the polynomial) replaces ``dist2`` where
    nearer, with its tag and its foot (``foot_x``, ``foot_y``: the nearest point of that
    curve; zero-size arrays: not written). On entry ``dist2``, ``near_tag`` hold each
    point's squared distance to some curve and its tag (inf, 0 for none), the nearest of a
    search before; the search skips every box farther than √best + slack (no curve in it can
    be nearer) and every box within θ ∈ [``searched_lo``, ``searched_hi``] (the segments
    that search had: pass inf, −inf for none). The minimum over both searches' curves: the
    same doubles as one search over them all. Exact for the dense output, to Newton's
    convergence; with every segment a straight piece and no slack, exact for the chords."""
    for chunk in nb.prange((px.size + _CHUNK - 1) // _CHUNK):
        _nearest_run(chunk * _CHUNK, min((chunk + 1) * _CHUNK, px.size), px, py, ax, ay, bx,
                     by, tag, xlo, xhi, ylo, yhi, start, searched_lo, searched_hi, slack,
                     step, span, shift, F, y_old, dist2, near_tag, foot_x, foot_y)


@nb.njit(inline="always")
def _dense_jet(F, step, c, x):
    """(P, dP/dx, d²P/dx²) of component ``c`` of step ``step``'s polynomial at x, without
    its y_old: :func:`atlas.kernels.dop853.dense_component`'s nested product (the same
    doubles for P) carried with its two derivatives."""
    y = dy = ddy = 0.0
    for p in range(F.shape[1]):
        y += F[step, p, c]
        if p % 2 == 0:  # × x
            ddy = ddy * x + 2.0 * dy
            dy = dy * x + y
            y *= x
        else:  # × (1 − x)
            ddy = ddy * (1.0 - x) - 2.0 * dy
            dy = dy * (1.0 - x) - y
            y *= 1.0 - x
    return y, dy, ddy


@nb.njit(inline="always")
def _curve_distance2(px, py, F, y_old, step, xa, xb, shift, s0):
    """(squared distance, x) from (px, py) to the nearest point of the polynomial piece
    x ∈ [xa, xb] (either order) of step ``step`` moved by (``shift``, 0): Newton's method on
    g(x) = (P(x) − p)·P'(x) from the chord's nearest fraction ``s0``, kept within the piece,
    at most ``NEWTON`` iterations, ending at a step below ``_CONVERGED`` (the piece is a
    short arc within a tolerance of its chord: quadratic convergence from there)."""
    lo, hi = min(xa, xb), max(xa, xb)
    x = xa + s0 * (xb - xa)
    ox, oy = y_old[step, 0] + shift - px, y_old[step, 1] - py
    for _ in range(NEWTON):
        p0, d0, dd0 = _dense_jet(F, step, 0, x)
        p1, d1, dd1 = _dense_jet(F, step, 1, x)
        ex, ey = p0 + ox, p1 + oy
        g = ex * d0 + ey * d1
        curv = d0 * d0 + d1 * d1 + ex * dd0 + ey * dd1
        if not curv > 0.0:
            break
        moved = min(max(x - g / curv, lo), hi)
        if abs(moved - x) <= _CONVERGED:
            x = moved
            break
        x = moved
    p0, _, _ = _dense_jet(F, step, 0, x)
    p1, _, _ = _dense_jet(F, step, 1, x)
    ex, ey = p0 + ox, p1 + oy
    return ex * ex + ey * ey, x


@nb.njit(inline="always")
def _nearest_run(first, stop, px, py, ax, ay, bx, by, tag, xlo, xhi, ylo, yhi, start,
                 searched_lo, searched_hi, slack, step, span, shift, F, y_old, dist2,
                 near_tag, foot_x, foot_y):
    """:func:`_nearest` for the points [first, stop) in turn (one parallel task), each
    search's stacks allocated once and each point's search started from the leaf of the
    previous point's nearest segment: a grid's neighbours (a row's, in its order) share
    their nearest boundary, so the first bound is nearly the distance itself and prunes
    the search at once (about half the work of a search from the top alone). Where
    ``foot_x`` has room, the foot of each point's nearest curve is written too."""
    levels = start.size - 1
    capacity = FAN * (levels + 1)
    st_level = np.empty(capacity, np.int64)
    st_box = np.empty(capacity, np.int64)
    st_lb = np.empty(capacity)
    lbs = np.empty(FAN)
    ids = np.empty(FAN, np.int64)
    near = np.empty(FAN)
    seed = -1  # the previous point's nearest segment (−1: none yet)
    for p in range(first, stop):
        dist2[p], near_tag[p], nearest, at = _nearest(
            px[p], py[p], dist2[p], near_tag[p], seed // FAN if seed >= 0 else -1, ax, ay,
            bx, by, tag, xlo, xhi, ylo, yhi, start, searched_lo, searched_hi, slack, step,
            span, shift, F, y_old, st_level, st_box, st_lb, lbs, ids, near)
        if nearest >= 0:
            seed = nearest
            if foot_x.size:
                foot_x[p], foot_y[p] = _foot(px[p], py[p], nearest, at, ax, ay, bx, by,
                                             step, shift, F, y_old)


@nb.njit(inline="always")
def _foot(x, y, s, at, ax, ay, bx, by, step, shift, F, y_old):
    """The nearest point of segment ``s``'s curve to (x, y): the polynomial at ``at`` (a
    curve), or the chord's nearest point (a straight piece)."""
    if step.size and step[s] >= 0:
        g = step[s]
        p0, _, _ = _dense_jet(F, g, 0, at)
        p1, _, _ = _dense_jet(F, g, 1, at)
        return p0 + y_old[g, 0] + shift[s], p1 + y_old[g, 1]
    dx, dy = bx[s] - ax[s], by[s] - ay[s]
    f = ((x - ax[s]) * dx + (y - ay[s]) * dy) / max(dx * dx + dy * dy, _TINY)
    f = min(max(f, 0.0), 1.0)
    return ax[s] + f * dx, ay[s] + f * dy


@nb.njit(inline="always")
def _reach2(best, slack):
    """The squared distance beyond which no curve within ``slack`` of its chords can be
    nearer than √best: best itself for chords (slack 0, the same doubles)."""
    if slack == 0.0:
        return best
    r = math.sqrt(best) + slack
    return r * r


@nb.njit(inline="always")
def _nearest(x, y, best, best_tag, seed_leaf, ax, ay, bx, by, tag, xlo, xhi, ylo, yhi, start,
             searched_lo, searched_hi, slack, step, span, shift, F, y_old, st_level, st_box,
             st_lb, lbs, ids, near):
    """(squared distance, tag, index, foot parameter) of the segment (or, with curves, the
    curve) nearest (x, y), or (``best``, ``best_tag``, −1, 0) when none is nearer than that
    bound: the leaf ``seed_leaf`` first (−1: none), then depth-first from the top, nearest
    box first, skipping every box not within reach of the best so far (:func:`_reach2`;
    the leaf searched first among them) or within θ ∈ [searched_lo, searched_hi]
    (:func:`_box_bound2`)."""
    top = start.size - 2
    best_seg, at = -1, 0.0
    if seed_leaf >= 0:
        best, best_seg, at = _leaf_nearest(x, y, seed_leaf, ax, ay, bx, by, near, best,
                                           best_seg, at, slack, step, span, shift, F, y_old)
    sp = 0
    for b in range(start[top], start[top + 1]):  # the top boxes, farthest pushed first
        st_level[sp], st_box[sp] = top, b - start[top]
        st_lb[sp] = _box_bound2(x, y, xlo[b], xhi[b], ylo[b], yhi[b], searched_lo,
                                searched_hi)
        sp += 1
    _sort_pushed(st_level, st_box, st_lb, 0, sp)
    while sp > 0:
        sp -= 1
        level, box, lb = st_level[sp], st_box[sp], st_lb[sp]
        reach = _reach2(best, slack)
        if lb >= reach or (level == 0 and box == seed_leaf):
            continue
        if level == 0:
            best, best_seg, at = _leaf_nearest(x, y, box, ax, ay, bx, by, near, best,
                                               best_seg, at, slack, step, span, shift, F,
                                               y_old)
            continue
        first = box * FAN
        count = min(FAN, start[level] - start[level - 1] - first)
        below = start[level - 1] + first
        for c in range(count):  # all children measured first (a loop without branches)
            b = below + c
            near[c] = _box_bound2(x, y, xlo[b], xhi[b], ylo[b], yhi[b], searched_lo,
                                  searched_hi)
        m = 0
        for c in range(count):
            if near[c] < reach:
                lbs[m], ids[m] = near[c], first + c
                m += 1
        for i in range(m):  # push the farthest first: the nearest is searched next
            st_level[sp + i], st_box[sp + i], st_lb[sp + i] = level - 1, ids[i], lbs[i]
        _sort_pushed(st_level, st_box, st_lb, sp, sp + m)
        sp += m
    if best_seg >= 0:
        best_tag = tag[best_seg]
    return best, best_tag, best_seg, at


@nb.njit(inline="always")
def _box_bound2(x, y, xlo, xhi, ylo, yhi, searched_lo, searched_hi):
    """The squared distance from (x, y) to a box, or inf for a box within θ ∈ [searched_lo,
    searched_hi] (its segments searched before: nothing there to find)."""
    if searched_lo <= xlo and xhi <= searched_hi:
        return np.inf
    return _box_distance2(x, y, xlo, xhi, ylo, yhi)


@nb.njit(inline="always")
def _leaf_nearest(x, y, leaf, ax, ay, bx, by, near, best, best_seg, at, slack, step, span,
                  shift, F, y_old):
    """The leaf's segments measured into ``near`` (a loop without branches, which the
    compiler can vectorise), then the nearest of them where it is nearer than ``best`` (the
    first of equals, as segment by segment): (squared distance, index, foot parameter),
    else (best, best_seg, at). With curves (``step`` not empty), a chord within reach
    (:func:`_reach2`) of the best so far, or of the nearest chord's bound (a curve lies
    within ``slack`` of its chord, so no farther than its chord's distance + slack), stands
    for its curve, measured by :func:`_curve_distance2`: a leaf's curves are measured only
    where they may be the nearest, not wherever each is nearer than the ones before it
    (a third of the cost of a tile's certificate with torque)."""
    first = leaf * FAN
    count = min(FAN, ax.size - first)
    for i in range(count):
        s = first + i
        near[i] = _segment_distance2(x, y, ax[s], ay[s], bx[s], by[s])
    bound = best  # the leaf's best is at most this before any curve is measured
    if step.size:
        for i in range(count):
            bound = min(bound, _reach2(near[i], slack) if step[first + i] >= 0 else near[i])
    for i in range(count):
        s = first + i
        if step.size and step[s] >= 0:
            if near[i] < _reach2(min(best, bound), slack):
                best, best_seg, at = _nearer_curve(x, y, s, ax, ay, bx, by, step, span, shift,
                                                   F, y_old, best, best_seg, at)
        elif near[i] < best:
            best, best_seg, at = near[i], s, 0.0
    if best > bound:  # Newton measured the bounding arc farther than its chord promised
        # (it stopped short): the arcs skipped on the bound are measured after all
        for i in range(count):
            s = first + i
            if step.size and step[s] >= 0 and _reach2(bound, slack) <= near[i] \
                    < _reach2(best, slack):
                best, best_seg, at = _nearer_curve(x, y, s, ax, ay, bx, by, step, span,
                                                   shift, F, y_old, best, best_seg, at)
    return best, best_seg, at


@nb.njit(inline="always")
def _nearer_curve(x, y, s, ax, ay, bx, by, step, span, shift, F, y_old, best, best_seg, at):
    """Segment ``s``'s curve measured from (x, y) (:func:`_curve_distance2`, from the
    chord's nearest fraction): (squared distance, s, foot parameter) where nearer than
    ``best``, else (best, best_seg, at) unchanged."""
    dx, dy = bx[s] - ax[s], by[s] - ay[s]
    f = ((x - ax[s]) * dx + (y - ay[s]) * dy) / max(dx * dx + dy * dy, _TINY)
    d2, x_at = _curve_distance2(x, y, F, y_old, step[s], span[s, 0], span[s, 1], shift[s],
                                min(max(f, 0.0), 1.0))
    if d2 < best:
        return d2, s, x_at
    return best, best_seg, at


@nb.njit(inline="always")
def _sort_pushed(st_level, st_box, st_lb, lo, hi):
    """Insertion sort of the stack entries [lo, hi) by decreasing lower bound."""
    for i in range(lo + 1, hi):
        lb, box, level = st_lb[i], st_box[i], st_level[i]
        j = i - 1
        while j >= lo and st_lb[j] < lb:
            st_lb[j + 1], st_box[j + 1], st_level[j + 1] = st_lb[j], st_box[j], st_level[j]
            j -= 1
        st_lb[j + 1], st_box[j + 1], st_level[j + 1] = lb, box, level


@cached_njit(nogil=True)
def _column(x, ax, ay, bx, by, tag, xlo, xhi, start, cross_y, cross_tag):
    """The crossings of the vertical line θ = x with the segments (each covering
    [min θ, max θ) of its ends): their θ̇ and tags into ``cross_y``, ``cross_tag`` (grown
    ×2 when full); returns (count, cross_y, cross_tag)."""
    levels = start.size - 1
    n_seg = ax.size
    stack_level = np.empty(FAN * (levels + 1), np.int64)
    stack_box = np.empty(FAN * (levels + 1), np.int64)
    sp, count = 0, 0
    top = levels - 1
    for b in range(start[top], start[top + 1]):
        if xlo[b] <= x <= xhi[b]:
            stack_level[sp], stack_box[sp] = top, b - start[top]
            sp += 1
    while sp > 0:
        sp -= 1
        level, box = stack_level[sp], stack_box[sp]
        if level == 0:
            for s in range(box * FAN, min((box + 1) * FAN, n_seg)):
                x0, x1 = ax[s], bx[s]
                if x0 == x1:
                    continue
                if x0 < x1:
                    xl, yl, xr, yr = x0, ay[s], x1, by[s]
                else:
                    xl, yl, xr, yr = x1, by[s], x0, ay[s]
                if xl <= x < xr:
                    if count == cross_y.size:
                        grown_y, grown_tag = np.empty(2 * count), np.empty(2 * count, np.int64)
                        grown_y[:count], grown_tag[:count] = cross_y, cross_tag
                        cross_y, cross_tag = grown_y, grown_tag
                    cross_y[count] = (yr - yl) / (xr - xl) * (x - xl) + yl
                    cross_tag[count] = tag[s]
                    count += 1
            continue
        first = box * FAN
        last = min(first + FAN, start[level] - start[level - 1])
        for c in range(first, last):
            b = start[level - 1] + c
            if xlo[b] <= x <= xhi[b]:
                stack_level[sp], stack_box[sp] = level - 1, c
                sp += 1
    return count, cross_y, cross_tag


@cached_njit(nogil=True)
def ray_sides(px, py, ax, ay, bx, by, tag, xlo, xhi, start, k_lo, k_hi, flip_from, bistable,
              running, out):
    """The side of each point (px, py) by the parity of the upward vertical ray's crossings
    with the segments of each tag k ∈ [k_lo, k_hi] (the translates Γ_k), the parity of k
    flipped first where px < flip_from[k − k_lo] (a branch that continues beyond the band
    above: pass −inf for none). ``bistable``: the largest k of odd parity, or ``running``
    where there is none; else k_lo + the number of k of even parity. Points on a grid are
    taken column by column (equal θ), each column's crossings found once and swept from the
    top (:func:`_column_sides`); scattered points (fewer than ``_SWEEP_BELOW`` a column on
    average: each its own column, or nearly) are taken together, the hierarchy walked once
    for all of them (:func:`_swept_sides`). Both count the same crossings: the same sides."""
    order = np.argsort(px)
    columns = min(order.size, 1)
    for i in range(1, order.size):
        columns += px[order[i]] != px[order[i - 1]]
    if order.size < _SWEEP_BELOW * columns:
        _swept_sides(order, px, py, ax, ay, bx, by, tag, xlo, xhi, start, k_lo, k_hi,
                     flip_from, bistable, running, out)
    else:
        _column_sides(order, px, py, ax, ay, bx, by, tag, xlo, xhi, start, k_lo, k_hi,
                      flip_from, bistable, running, out)


@nb.njit(inline="always")
def _side(parity, odd, k_lo, bistable, running):
    """The side of a point from its parities per tag (``odd`` of them odd): ray_sides' rule."""
    n_k = parity.size
    if not bistable:
        return k_lo + n_k - odd
    if odd > 0:
        for k in range(n_k - 1, -1, -1):
            if parity[k]:
                return k + k_lo
    return running


@cached_njit(nogil=True)
def _column_sides(order, px, py, ax, ay, bx, by, tag, xlo, xhi, start, k_lo, k_hi,
                  flip_from, bistable, running, out):
    """:func:`ray_sides` column by column (``order``: the points by θ): each column's
    crossings found once (:func:`_column`), sorted from the top, and swept down the column's
    points."""
    n_k = k_hi - k_lo + 1
    parity = np.zeros(n_k, np.bool_)
    cross_y, cross_tag = np.empty(1024), np.empty(1024, np.int64)
    i = 0
    while i < order.size:
        x = px[order[i]]
        j = i
        while j < order.size and px[order[j]] == x:
            j += 1
        column = order[i:j]
        column = column[np.argsort(-py[column])]  # from the top down
        count, cross_y, cross_tag = _column(x, ax, ay, bx, by, tag, xlo, xhi, start, cross_y,
                                            cross_tag)
        down = np.argsort(-cross_y[:count])
        odd = 0
        for k in range(n_k):
            parity[k] = x < flip_from[k]
            odd += parity[k]
        c = 0
        for q in column:
            while c < count and cross_y[down[c]] > py[q]:
                k = cross_tag[down[c]] - k_lo
                if 0 <= k < n_k:
                    parity[k] = not parity[k]
                    odd += 1 if parity[k] else -1
                c += 1
            out[q] = _side(parity, odd, k_lo, bistable, running)
        i = j


@nb.njit(inline="always")
def _first_above(values, bound, lo, hi, strict):
    """The first index i in [lo, hi) of the sorted ``values`` with values[i] > ``bound``
    (``strict``) or ≥ it, hi if none: bisection."""
    while lo < hi:
        mid = (lo + hi) // 2
        if values[mid] > bound or (not strict and values[mid] == bound):
            hi = mid
        else:
            lo = mid + 1
    return lo


@cached_njit(nogil=True)
def _swept_sides(order, px, py, ax, ay, bx, by, tag, xlo, xhi, start, k_lo, k_hi, flip_from,
                 bistable, running, out):
    """:func:`ray_sides` for scattered points (``order``: the points by θ): the hierarchy is
    walked once, each box with the run of points whose θ it covers (a box with none is
    skipped), and each segment of a leaf crossed with the rays of its run's points below it
    (θ ∈ [min, max) of its ends, θ̇ there as :func:`_column` has it: the same crossings)."""
    n, n_k = order.size, k_hi - k_lo + 1
    sx, sy = px[order], py[order]
    parity = np.empty((n, n_k), np.bool_)
    odd = np.zeros(n, np.int64)
    for q in range(n):
        for k in range(n_k):
            parity[q, k] = sx[q] < flip_from[k]
            odd[q] += parity[q, k]
    levels = start.size - 1
    n_seg = ax.size
    st_level = np.empty(FAN * (levels + 1), np.int64)
    st_box = np.empty(FAN * (levels + 1), np.int64)
    st_lo = np.empty(FAN * (levels + 1), np.int64)
    st_hi = np.empty(FAN * (levels + 1), np.int64)
    sp = 0
    top = levels - 1
    for b in range(start[top], start[top + 1]):
        lo = _first_above(sx, xlo[b], 0, n, False)  # the points with xlo ≤ θ ≤ xhi
        hi = _first_above(sx, xhi[b], lo, n, True)
        if lo < hi:
            st_level[sp], st_box[sp], st_lo[sp], st_hi[sp] = top, b - start[top], lo, hi
            sp += 1
    while sp > 0:
        sp -= 1
        level, box, lo, hi = st_level[sp], st_box[sp], st_lo[sp], st_hi[sp]
        if level == 0:
            for s in range(box * FAN, min((box + 1) * FAN, n_seg)):
                k = tag[s] - k_lo
                x0, x1 = ax[s], bx[s]
                if x0 == x1 or not 0 <= k < n_k:
                    continue
                if x0 < x1:
                    xl, yl, xr, yr = x0, ay[s], x1, by[s]
                else:
                    xl, yl, xr, yr = x1, by[s], x0, ay[s]
                q = _first_above(sx, xl, lo, hi, False)
                while q < hi and sx[q] < xr:
                    if (yr - yl) / (xr - xl) * (sx[q] - xl) + yl > sy[q]:
                        parity[q, k] = not parity[q, k]
                        odd[q] += 1 if parity[q, k] else -1
                    q += 1
            continue
        first = box * FAN
        last = min(first + FAN, start[level] - start[level - 1])
        for c in range(first, last):
            b = start[level - 1] + c
            c_lo = _first_above(sx, xlo[b], lo, hi, False)
            c_hi = _first_above(sx, xhi[b], c_lo, hi, True)
            if c_lo < c_hi:
                st_level[sp], st_box[sp], st_lo[sp], st_hi[sp] = level - 1, c, c_lo, c_hi
                sp += 1
    for q in range(n):
        out[order[q]] = _side(parity[q], odd[q], k_lo, bistable, running)
