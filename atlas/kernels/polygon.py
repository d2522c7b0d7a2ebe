"""Polygons clipped to a box, compiled: the chord polygons of the tilted basins.

:func:`clip` is Sutherland–Hodgman against one axis-parallel half-plane (exact for a simple
polygon against a convex region; Sutherland & Hodgman, Comm. ACM 17 (1974) 32), the same
operations as the numpy version it replaced; :func:`window_areas` measures, by the shoelace
formula, one polygon shifted by each of several multiples of 2π in θ and clipped to a box
(coordinates centred on the box, for rounding). The chord polygon of
:func:`atlas.kernels.dense_curves.window_areas`, the tilted basins' exact areas
(docs/design/tilted-boundaries.md).
"""

from __future__ import annotations

import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import cached_njit

__all__ = ["clip", "window_areas"]


@cached_njit(nogil=True)
def clip(x, y, axis, level, keep_above):
    """The closed polygon (x, y) clipped to {coordinate ``axis`` ≥ level} (``keep_above``)
    or ≤ level: for each edge (i, i + 1), its crossing of the line where it crosses, then
    vertex i + 1 where it lies inside."""
    n = x.size
    ox, oy = np.empty(2 * n), np.empty(2 * n)
    m = 0
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        c0 = x[i] if axis == 0 else y[i]
        c1 = x[j] if axis == 0 else y[j]
        s0 = c0 - level if keep_above else level - c0
        s1 = c1 - level if keep_above else level - c1
        in0, in1 = s0 >= 0.0, s1 >= 0.0
        if in0 != in1:
            f = s0 / (s0 - s1)
            if axis == 0:
                ox[m], oy[m] = level, y[i] + f * (y[j] - y[i])
            else:
                ox[m], oy[m] = x[i] + f * (x[j] - x[i]), level
            m += 1
        if in1:
            ox[m], oy[m] = x[j], y[j]
            m += 1
    return ox[:m], oy[:m]


#: Edges wider than this in θ [rad] are measured for every shift (the polygon's closing
#: edges); the others only for the shifts whose box they reach.
_WIDE = 0.1


@cached_njit(nogil=True)
def _piece(x0, y0, x1, y1, a, b):
    """Twice the signed shoelace contribution of the edge (x0, y0) → (x1, y1) with θ
    clamped into [a, b], the edge cut where it crosses a or b (what clipping to the strip
    makes of it: outside pieces run along the clip line, contributing a·Δθ̇ or b·Δθ̇)."""
    cuts = np.empty(4)
    cuts[0], m = 0.0, 1
    if x1 != x0:
        for level in (a, b):
            t = (level - x0) / (x1 - x0)
            if 0.0 < t < 1.0:
                cuts[m] = t
                m += 1
    if m == 3 and cuts[2] < cuts[1]:
        cuts[1], cuts[2] = cuts[2], cuts[1]
    cuts[m] = 1.0
    total = 0.0
    for i in range(m):
        t0, t1 = cuts[i], cuts[i + 1]
        ya, yb = y0 + t0 * (y1 - y0), y0 + t1 * (y1 - y0)
        mid = x0 + 0.5 * (t0 + t1) * (x1 - x0)
        if mid < a:
            total += a * (yb - ya)
        elif mid > b:
            total += b * (yb - ya)
        else:
            xa = min(max(x0 + t0 * (x1 - x0), a), b)
            xb = min(max(x0 + t1 * (x1 - x0), a), b)
            total += xa * yb - xb * ya
    return total


@cached_njit(nogil=True)
def window_areas(x, y, shifts, a, b, lo, hi, out):
    """out[i] = area of the closed polygon (x + shifts[i], y) ∩ [a, b] × [lo, hi]: clipped
    in θ̇ once; then, per shift, Sutherland–Hodgman in θ's area without building the
    clipped polygon. Clipping moves the outside vertices onto the clip line, so an edge
    wholly left of the box adds a·Δθ̇ to the shoelace sum, one wholly right b·Δθ̇ (those
    sums come from prefix sums over the edges sorted by their θ extent), and only the edges
    that reach the box are measured (:func:`_piece`): O(n log n) once and O(edges in the
    box) per shift, instead of O(n) per shift. Coordinates are centred on the box."""
    cx, cy = 0.5 * (a + b), 0.5 * (lo + hi)
    bx, by = clip(x, y, 1, lo, True)
    bx, by = clip(bx, by, 1, hi, False)
    n = bx.size
    if n < 3:
        out[:] = 0.0
        return
    by = by - cy
    nxt = np.roll(np.arange(n), -1)
    x0, x1, y0, y1 = bx, bx[nxt], by, by[nxt]
    xmin, xmax, dy = np.minimum(x0, x1), np.maximum(x0, x1), y1 - y0
    by_max = np.argsort(xmax)
    xmax_sorted = xmax[by_max]
    left = np.zeros(n + 1)
    left[1:] = np.cumsum(dy[by_max])
    by_min = np.argsort(xmin)
    xmin_sorted = xmin[by_min]
    below = np.zeros(n + 1)
    below[1:] = np.cumsum(dy[by_min])
    wide = np.flatnonzero(xmax - xmin > _WIDE)
    for i in range(shifts.size):
        lo_x, hi_x = a - shifts[i], b - shifts[i]  # the box in the polygon's θ
        off = shifts[i] - cx
        ca, cb = a - cx, b - cx
        total = ca * left[np.searchsorted(xmax_sorted, lo_x)]  # xmax < lo_x
        j = np.searchsorted(xmin_sorted, hi_x, side="right")  # xmin ≤ hi_x: [0, j)
        total += cb * (below[n] - below[j])
        reached = 0
        for t in range(np.searchsorted(xmin_sorted, lo_x - _WIDE), j):
            e = by_min[t]
            if xmax[e] >= lo_x and xmax[e] - xmin[e] <= _WIDE:
                total += _piece(x0[e] + off, y0[e], x1[e] + off, y1[e], ca, cb)
                reached += 1
        for e in wide:
            if xmax[e] >= lo_x and xmin[e] <= hi_x:
                total += _piece(x0[e] + off, y0[e], x1[e] + off, y1[e], ca, cb)
                reached += 1
        # no edge reaches the box: the polygon lies beside it, its area there is exactly 0
        # (the telescoped sums of Δθ̇ around it vanish only to rounding)
        out[i] = 0.5 * abs(total) if reached else 0.0
