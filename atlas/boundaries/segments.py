"""Nearest segments of polylines, exactly, and the polygon tools of the tilted areas.

:class:`Segments` answers, for many points at once, the Euclidean distance [rad-ish] to the
nearest segment of a set of polylines and which polyline it belongs to: exact for the
polylines (a two-level search, a k-d tree over coarse chords that bound the fine segments,
then exact point-to-segment distances where the bounds cannot exclude them).
:func:`clip` (Sutherland–Hodgman: exact for a simple polygon against a convex region;
Sutherland & Hodgman, Comm. ACM 17 (1974) 32), :func:`shoelace` (a polygon's area) and
:func:`inside_length` (a polyline's length in a box) measure the tilted basins' areas
(:meth:`atlas.boundaries.tilted.TiltedBoundaries.areas`).
Derivation of the search's bounds: docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Segments", "segment_distance", "clip", "shoelace", "inside_length"]

_NEIGHBOURS = 8  # coarse vertices examined per point before the exactness test of distances
_CHUNK = 1 << 20  # fine segments measured at once (bounds the temporaries)
_STRIDE = 32  # at most this many fine segments per coarse chord in the distance search
_CHORD = 0.02  # and one coarse vertex at least every this much arc length [rad-ish]


def segment_distance(px, py, ax, ay, bx, by):
    """Distance from points p to segments [a, b] (arrays broadcast)."""
    dx, dy = bx - ax, by - ay
    qx, qy = px - ax, py - ay
    s = (qx * dx + qy * dy) / np.maximum(dx * dx + dy * dy, np.finfo(float).tiny)
    np.clip(s, 0.0, 1.0, out=s)
    return np.hypot(qx - s * dx, qy - s * dy)


class Segments:
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
        off = segment_distance(self.x[fine], self.y[fine], ax[owner], ay[owner],
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
        return segment_distance(px, py, self.x[s], self.y[s], self.x[e], self.y[e])

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
            d = segment_distance(px[pw], py[pw], self.x[seg], self.y[seg], self.x[seg + 1],
                                  self.y[seg + 1])
            d_pair[part] = np.minimum.reduceat(d, np.cumsum(c) - c) if part.size else d
        order = np.lexsort((d_pair, who))  # by point, nearest first
        head = order[np.r_[True, who[order][1:] != who[order][:-1]]]
        dist = np.full(px.size, np.inf)
        tag = np.zeros(px.size, np.int64)
        dist[who[head]] = d_pair[head]
        tag[who[head]] = self.tag[chords[head]]
        return dist, tag


def clip(x, y, axis: int, level: float, keep_above: bool):
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


def shoelace(x, y) -> float:
    """|area| of the closed polygon (x, y) (coordinates should be centred, for rounding)."""
    if x.size < 3:
        return 0.0
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)))


def inside_length(x, y, box) -> float:
    """Length of the polyline's segments whose ends both lie in ``box`` (≈ its length in it)."""
    (a, b), (lo, hi) = box
    inside = (x >= a) & (x <= b) & (y >= lo) & (y <= hi)
    both = inside[:-1] & inside[1:]
    return float(np.hypot(np.diff(x), np.diff(y))[both].sum())
