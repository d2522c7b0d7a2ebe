"""Polylines against points, compiled: the nearest segment and the vertical ray's crossings.

The tilted basin boundaries (:mod:`atlas.boundaries.tilted`) are polylines of some 10⁵
short segments each. :func:`build` groups them, in their order along the curves, into a
bounding-volume hierarchy: ``FAN`` consecutive segments per leaf box, ``FAN`` boxes per box
of the level above, until at most ``FAN`` boxes remain (consecutive pieces of a smooth curve
have tight boxes). :func:`nearest_segments` finds, per point (``prange``: independent of the
thread count), the Euclidean distance to the nearest segment and its tag by a depth-first
search, nearest box first, that skips every box farther than the best distance found: exact
for the polylines (the box distance is a lower bound). :func:`ray_sides` counts, per point,
the crossings of the upward vertical ray with the segments of each tag (a segment covers
θ ∈ [min, max) of its ends, its θ̇ at θ by linear interpolation), one column of equal θ at a
time, for the side rule of :meth:`atlas.boundaries.tilted.TiltedBoundaries.side`.
References: Ericson, *Real-Time Collision Detection* (2005), ch. 6 (bounding-volume
hierarchies, ordered traversal); docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from atlas.kernels import cached_njit

__all__ = ["FAN", "build", "nearest_segments", "ray_sides"]

#: Children per box of the hierarchy (segments per leaf box).
FAN = 16
_CHUNK = 256  # points per parallel task of nearest_segments


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
def nearest_segments(px, py, ax, ay, bx, by, tag, xlo, xhi, ylo, yhi, start, out_dist,
                     out_tag):
    """Per point (px, py): the distance to the nearest segment (ax, ay) → (bx, by) and that
    segment's ``tag`` into ``out_dist``, ``out_tag`` (inf, 0 without segments); the
    hierarchy from :func:`build`. Exact for the segments (module docstring)."""
    levels = start.size - 1
    capacity = FAN * (levels + 1)
    n_chunks = (px.size + _CHUNK - 1) // _CHUNK
    for chunk in nb.prange(n_chunks):  # the search's stacks allocated once per chunk
        st_level = np.empty(capacity, np.int64)
        st_box = np.empty(capacity, np.int64)
        st_lb = np.empty(capacity)
        lbs = np.empty(FAN)
        ids = np.empty(FAN, np.int64)
        for p in range(chunk * _CHUNK, min((chunk + 1) * _CHUNK, px.size)):
            out_dist[p], out_tag[p] = _nearest(px[p], py[p], ax, ay, bx, by, tag, xlo, xhi,
                                               ylo, yhi, start, st_level, st_box, st_lb, lbs,
                                               ids)


@nb.njit(inline="always")
def _nearest(x, y, ax, ay, bx, by, tag, xlo, xhi, ylo, yhi, start, st_level, st_box, st_lb,
             lbs, ids):
    """(distance, tag) of the segment nearest (x, y): depth-first, nearest box first, on
    squared distances (the root taken once, at the end)."""
    top = start.size - 2
    n_seg = ax.size
    best, best_tag = np.inf, 0
    sp = 0
    for b in range(start[top], start[top + 1]):  # the top boxes, farthest pushed first
        st_level[sp], st_box[sp] = top, b - start[top]
        st_lb[sp] = _box_distance2(x, y, xlo[b], xhi[b], ylo[b], yhi[b])
        sp += 1
    _sort_pushed(st_level, st_box, st_lb, 0, sp)
    while sp > 0:
        sp -= 1
        level, box, lb = st_level[sp], st_box[sp], st_lb[sp]
        if lb >= best:
            continue
        if level == 0:
            for s in range(box * FAN, min((box + 1) * FAN, n_seg)):
                d = _segment_distance2(x, y, ax[s], ay[s], bx[s], by[s])
                if d < best:
                    best, best_tag = d, tag[s]
            continue
        first = box * FAN
        last = min(first + FAN, start[level] - start[level - 1])
        m = 0
        for c in range(first, last):
            b = start[level - 1] + c
            d = _box_distance2(x, y, xlo[b], xhi[b], ylo[b], yhi[b])
            if d < best:
                lbs[m], ids[m] = d, c
                m += 1
        for i in range(m):  # push the farthest first: the nearest is searched next
            st_level[sp + i], st_box[sp + i], st_lb[sp + i] = level - 1, ids[i], lbs[i]
        _sort_pushed(st_level, st_box, st_lb, sp, sp + m)
        sp += m
    return math.sqrt(best), best_tag


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
    where there is none; else k_lo + the number of k of even parity. Points are taken column
    by column (equal θ), each column's crossings found once and swept from the top."""
    order = np.argsort(px)
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
            if bistable:
                label = running
                if odd > 0:
                    for k in range(n_k - 1, -1, -1):
                        if parity[k]:
                            label = k + k_lo
                            break
                out[q] = label
            else:
                out[q] = k_lo + n_k - odd
        i = j
