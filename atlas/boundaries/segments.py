"""Nearest segments of polylines, exactly, and the crossings of vertical rays with them.

:class:`Segments` answers, for many points at once, the Euclidean distance [rad-ish] to the
nearest segment of a set of polylines and which polyline it belongs to, exact for the
polylines, and the parity of each point's upward ray's crossings with each polyline (the
side rule of :meth:`atlas.boundaries.tilted.TiltedBoundaries.side`): a compiled
bounding-volume hierarchy over the segments (:mod:`atlas.kernels.segments`).
The polygon tools of the tilted areas are compiled: :mod:`atlas.kernels.polygon`.
Derivation: docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Segments", "segment_distance"]


def segment_distance(px, py, ax, ay, bx, by):
    """Distance from points p to segments [a, b] (arrays broadcast)."""
    dx, dy = bx - ax, by - ay
    qx, qy = px - ax, py - ay
    s = (qx * dx + qy * dy) / np.maximum(dx * dx + dy * dy, np.finfo(float).tiny)
    np.clip(s, 0.0, 1.0, out=s)
    return np.hypot(qx - s * dx, qy - s * dy)


class Segments:
    """Nearest segments of polylines, exactly, and the vertical ray's crossings. ``runs``:
    list of (θ, θ̇, tag) polylines (those of fewer than two vertices are dropped), or of
    (θ, θ̇, tag, step, span, shift) where the chords stand for curves: segment i of the run is
    the chord of the polynomial of a dense output's step ``step[i]`` over the x range
    ``span[i]``, moved by (shift, 0) (−1: a straight piece; searched by
    :func:`atlas.kernels.segments.nearer_curves`).

    The segments, in their order along the runs (consecutive pieces of smooth curves: tight
    boxes; measured faster than a Morton order of their midpoints), are held in a
    bounding-volume hierarchy (:func:`atlas.kernels.segments.build`); :meth:`nearest`
    searches it nearest box first and skips every box farther than the best distance found
    (exact for the polylines: the distance to a box bounds the distance to every segment in
    it), :meth:`sides` counts the upward vertical ray's crossings per tag (compiled:
    :mod:`atlas.kernels.segments`)."""

    def __init__(self, runs):
        from atlas.kernels.segments import build

        runs = [r for r in runs if np.size(r[0]) >= 2]
        self.empty = not runs

        def cat(f):
            return np.ascontiguousarray(np.concatenate([f(r) for r in runs])) if runs \
                else np.zeros(0)

        self.ax, self.ay = cat(lambda r: r[0][:-1]), cat(lambda r: r[1][:-1])
        self.bx, self.by = cat(lambda r: r[0][1:]), cat(lambda r: r[1][1:])
        self.tag = cat(lambda r: np.full(r[0].size - 1, r[2], np.int64)).astype(np.int64)
        # the curves the chords stand for, where the runs give them: per segment the step of
        # a dense output and its x span, and the θ shift of the run (:meth:`nearest_curves`)
        curved = bool(runs) and all(len(r) == 6 for r in runs)
        self.step = cat(lambda r: r[3]).astype(np.int64) if curved else np.zeros(0, np.int64)
        self.span = cat(lambda r: r[4]).reshape(-1, 2) if curved else np.zeros((0, 2))
        self.shift = cat(lambda r: np.full(r[0].size - 1, r[5], float)) if curved \
            else np.zeros(0)
        self.xlo, self.xhi, self.ylo, self.yhi, self.start = build(self.ax, self.ay, self.bx,
                                                                   self.by)

    def nearest(self, px, py):
        """(distance, tag of the nearest segment) for points (px, py): exact for the
        polylines (class docstring; the curves' search with every segment straight and no
        slack, :func:`atlas.kernels.segments.nearer_curves`); (inf, 0) when there are none."""
        from atlas.kernels.segments import nearer_curves

        px = np.ascontiguousarray(px, dtype=np.float64).ravel()
        py = np.ascontiguousarray(py, dtype=np.float64).ravel()
        dist2, tag = np.full(px.size, np.inf), np.zeros(px.size, np.int64)
        n, none = self.ax.size, np.zeros(0)
        nearer_curves(px, py, self.ax, self.ay, self.bx, self.by, self.tag, self.xlo,
                      self.xhi, self.ylo, self.yhi, self.start, np.inf, -np.inf, 0.0,
                      np.full(n, -1, np.int64), np.zeros((n, 2)), np.zeros(n),
                      np.zeros((1, 7, 2)), np.zeros((1, 2)), dist2, tag, none, none)
        return np.sqrt(dist2), tag

    def sides(self, px, py, k_lo: int, k_hi: int, flip_from, bistable: bool, running: int):
        """The side of each point by the parity of its upward vertical ray's crossings with
        the segments of each tag k_lo … k_hi (:func:`atlas.kernels.segments.ray_sides`)."""
        from atlas.kernels.segments import ray_sides

        px = np.ascontiguousarray(px, dtype=np.float64).ravel()
        py = np.ascontiguousarray(py, dtype=np.float64).ravel()
        out = np.empty(px.size, np.int64)
        ray_sides(px, py, self.ax, self.ay, self.bx, self.by, self.tag, self.xlo, self.xhi,
                  self.start, int(k_lo), int(k_hi),
                  np.ascontiguousarray(flip_from, dtype=np.float64), bool(bistable),
                  int(running), out)
        return out
