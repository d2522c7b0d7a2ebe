"""The exact basin boundaries, one small interface (ExactBoundaries) and one factory.

What the certificate (:mod:`atlas.boundaries.certificate`) and the traces ask of the exact
equation's basin boundaries over a window: the side of a point (well k or the running
basin), its distance to the nearest boundary, the saddles of the boundaries near it, the exact
area of each basin in the window, and the boundaries' own error. :func:`exact_boundaries`
picks the implementation: :class:`UntiltedExact` (τ = 0: the stable manifolds of
:mod:`atlas.boundaries.manifold`, one DOP853 curve and its copies, areas by quadrature),
:class:`TiltedExact` (0 < |τ| < ω0²: :mod:`atlas.boundaries.tilted`, sides, distances,
areas and nearest points exact for the DOP853 dense output, polylines to search it) and
:class:`UnboundedExact` (|τ| > ω0²: no rest state, no boundary, the running basin is the
whole plane). Accuracy: distances and sides are exact for the
reference curves, whose error is ``reference_error`` (the change from DOP853 rtol 1e-12 to
1e-13). After Attractors.jl's small mapper
interface. Derivations: docs/design/separatrices.md, docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol, runtime_checkable

import numpy as np

from atlas.boundaries.basins import FIND_CYCLE, RUNNING_SIDE, ExactAreas
from atlas.boundaries.manifold import RTOL_CHECK, StableManifold, basin_areas, bins
from atlas.physics.pendulum import Pendulum

__all__ = ["ExactBoundaries", "ExactAreas", "Outline", "exact_boundaries", "UntiltedExact",
           "TiltedExact", "UnboundedExact", "RUNNING_SIDE", "FIND_CYCLE", "OUTLINE_PIECES"]

#: Points per sample interval of L on the outline of an untilted boundary.
OUTLINE_PIECES = 8

#: First search radius around the window for boundaries [rad-ish]; grown while needed.
_FIRST_MARGIN = 1.0
#: Cell side [rad-ish] of the bins over the tilted boundaries' vertices (the radii asked
#: for are about half a grid cell's diagonal).
_VERTEX_CELL = 0.05
#: Vertices farther than this [rad-ish] outside the window are not binned for points in it.
_VERTEX_MARGIN = 0.5

Box = tuple[tuple[float, float], tuple[float, float]]


@runtime_checkable
class ExactBoundaries(Protocol):
    """The exact basin boundaries of ``pendulum`` over ``window`` = ((θmin, θmax) [rad],
    (θ̇min, θ̇max) [rad s⁻¹]). Points are arrays (θ [rad], θ̇ [rad s⁻¹]) that broadcast;
    distances are Euclidean in the (θ, θ̇) plane, both as one unit ("rad-ish"). A boundary is
    named by its saddle n (odd: the saddle near nπ; with torque n = 2j + 1 for the saddle
    π − θ* + 2πj) and separates the wells (n − 1)/2 + ``lower_well`` … (n − 1)/2 +
    ``upper_well`` (and the running basin where ``running_possible``)."""

    pendulum: Pendulum
    window: Box
    running_possible: bool
    lower_well: int
    upper_well: int
    #: Whether there is a basin boundary at all (False without rest states, |τ| > ω0²: the
    #: running basin is the whole plane).
    has_boundary: bool
    #: How the RK4 map's separatrices along these boundaries are traced: the key of
    #: :data:`atlas.boundaries.trace.TRACES` ("untilted", "tilted"; "" where none).
    traced_as: str
    #: The running limit cycle these boundaries were built with (None where there is none).
    cycle: object
    #: The largest |θ̇| [rad s⁻¹] up to which :meth:`basin_outline` is drawn from these
    #: boundaries as built (inf: integrated further on demand).
    outline_reach: float

    @property
    def reference_error(self) -> float:
        """The reference curves' own error [rad-ish]: every side and distance holds to it."""

    @property
    def areas(self) -> ExactAreas:
        """The exact area fraction of the window in each basin, the running one included."""

    def side(self, theta, theta_dot) -> np.ndarray:
        """The basin each point of the window lies in: well k (int64), or
        :data:`RUNNING_SIDE`."""

    def distance(self, theta, theta_dot) -> tuple[np.ndarray, np.ndarray]:
        """(distance [rad-ish] to the nearest boundary, its saddle n); (inf, 0) if none."""

    def side_and_distance(self, theta, theta_dot) -> tuple[np.ndarray, np.ndarray,
                                                           np.ndarray]:
        """(:meth:`side`, then :meth:`distance`'s two arrays), as one call: the certifier
        asks for both (with torque, one search gives both)."""

    def saddles_within(self, theta, theta_dot, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """(lowest, highest) saddle n of the boundaries within ``radius`` [rad-ish] of each
        point, a superset (flattened; (0, 0) where none)."""

    def nearest_point(self, theta, theta_dot) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                       np.ndarray]:
        """(distance [rad-ish], θ [rad], θ̇ [rad s⁻¹], the distance's error [rad-ish]) of the
        nearest point of the nearest basin boundary to each point (the foot of
        :meth:`distance`); (inf, nan, nan, nan) if none. From a rest state: its minimal
        fatal shock (Halekotte & Feudel, Sci. Rep. 10, 11783, 2020)."""

    def running_shock(self) -> tuple[float, float, float, float, float, float]:
        """The running limit cycle's minimal fatal shock: (distance [rad-ish], the cycle's
        point θ [rad], θ̇ [rad s⁻¹], the boundary's point θ, θ̇, error [rad-ish]) of the
        nearest pair of the cycle and a basin boundary; NaN where there is no running cycle
        or no boundary."""

    def basin_outline(self, speed: float | None = None) -> Outline:
        """The basin as a shape: the boundary Γ that bounds well 0's basin, valid for |θ̇| <
        ``speed`` [rad s⁻¹] (default: as far as built, :attr:`outline_reach`); ValueError
        beyond :attr:`outline_reach`, or where there is no boundary."""


@dataclass(frozen=True)
class Outline:
    """One basin boundary Γ as a polyline (``theta`` [rad], ``theta_dot`` [rad s⁻¹]), from one
    end through its saddle to the other, valid for |θ̇| < ``speed``, with its chord error
    [rad-ish]; ``strip``: the basin it bounds is the strip between Γ and Γ − 2π (no running
    cycle), else the tongue inside Γ; ``well``: the well k whose basin it bounds (θ shifted by
    −2πk gives well 0's)."""

    theta: np.ndarray
    theta_dot: np.ndarray
    speed: float
    chord_error: float
    strip: bool
    well: int


def exact_boundaries(pendulum: Pendulum, window: Box, *, cycle=FIND_CYCLE) -> ExactBoundaries:
    """The exact basin boundaries of ``pendulum`` (α > 0) over ``window``: the one place
    where the torque picks an implementation (module docstring). ``cycle``: the running
    limit cycle if the caller has it (None: there is none), found here by default; used with
    torque only. The saddle-node |τ| = ω0², a degenerate point, has no certified boundaries:
    ValueError (configs refuse it)."""
    if pendulum.torque == 0.0:
        return UntiltedExact(pendulum, window)
    if pendulum.has_rest_states:
        return TiltedExact(pendulum, window, cycle=cycle)
    if abs(pendulum.torque) > pendulum.omega0**2:
        return UnboundedExact(pendulum, window)
    raise ValueError("|torque| = omega0^2: the saddle-node, whose basin atlas does not certify")


class UntiltedExact:
    """:class:`ExactBoundaries` without torque: the strips between the stable manifolds of
    the saddles ((2j + 1)π, 0) (:class:`atlas.boundaries.manifold.StableManifold`, indexed by
    :class:`atlas.boundaries.manifold.BoundaryIndex`). The areas and the reference error are
    computed on first use; it pickles without its search indices, rebuilt on first use."""

    running_possible = False
    #: A boundary of saddle n (odd) separates the wells on either side of nπ.
    lower_well, upper_well = 0, 1
    has_boundary, traced_as, cycle = True, "untilted", None
    outline_reach = math.inf  # L is integrated as far as asked

    def __init__(self, pendulum: Pendulum, window: Box):
        self.pendulum, self.window = pendulum, window
        self._indices: dict[float, object] = {}

    def __getstate__(self):
        return {**self.__dict__, "_indices": {}}

    @cached_property
    def _areas(self):
        """(ExactAreas, the saddles (n_below, n_above) bounding the window, reference
        error): the left branch at rtol 1e-13 (the search index's) and at 1e-12, each
        integrated once."""
        fine = self._index(_FIRST_MARGIN).manifold
        coarse = StableManifold(self.pendulum, max(abs(v) for v in self.window[1]), RTOL_CHECK)
        areas = basin_areas(self.pendulum, *self.window, manifolds=(fine, coarse))
        return (ExactAreas(areas.k, areas.fraction, areas.error, 0.0, 0.0), areas.saddles,
                _reference_error(fine, coarse))

    @property
    def areas(self) -> ExactAreas:
        return self._areas[0]

    @property
    def reference_error(self) -> float:
        """Largest distance between the reference manifolds at rtol 1e-12 and 1e-13 over the
        window's θ̇ band: the DOP853 reference's own error, overestimated about tenfold."""
        return self._areas[2]

    def _index(self, margin: float):
        """The boundary index of the window grown by ``margin`` (cached)."""
        if margin not in self._indices:
            (t0, t1), (v0, v1) = self.window
            speed = max(abs(v0), abs(v1)) + margin
            manifold = StableManifold(self.pendulum, speed)
            self._indices[margin] = manifold.index(((t0 - margin, t1 + margin),
                                                    (v0 - margin, v1 + margin)))
        return self._indices[margin]

    def side(self, theta, theta_dot):
        return self._index(_FIRST_MARGIN).manifold.side(theta, theta_dot, self._areas[1])

    def distance(self, theta, theta_dot):
        """Distance [rad-ish] of each point to the nearest exact basin boundary, and that
        boundary's saddle n. Boundaries are searched within a margin around the window; a
        distance found is exact where it does not exceed the point's distance to the edge of
        the searched box (a boundary outside it is farther). The others are searched again
        with the margin grown past every distance found."""
        theta, theta_dot = np.broadcast_arrays(np.asarray(theta, float),
                                               np.asarray(theta_dot, float))
        if not (np.isfinite(theta).all() and np.isfinite(theta_dot).all()):
            raise ValueError("distance to the basin boundaries of a non-finite point")
        margin = _FIRST_MARGIN
        index = self._index(margin)
        dist, n = index.nearest(theta, theta_dot)
        todo = np.ones(theta.shape, bool)
        while True:
            (t0, t1), (v0, v1) = index.box
            edge = np.minimum(np.minimum(theta - t0, t1 - theta),
                              np.minimum(theta_dot - v0, v1 - theta_dot))
            todo &= ~(dist <= edge)
            if not todo.any():
                return dist, n
            finite = dist[todo][np.isfinite(dist[todo])]
            margin = 2.0 * max(margin, finite.max(initial=0.0))
            index = self._index(margin)
            dist[todo], n[todo] = index.nearest(theta[todo], theta_dot[todo])

    def side_and_distance(self, theta, theta_dot):
        return (self.side(theta, theta_dot), *self.distance(theta, theta_dot))

    def saddles_within(self, theta, theta_dot, radius: float):
        return self._index(_FIRST_MARGIN).saddles_within(theta, theta_dot, radius)

    def running_shock(self):
        return (math.nan,) * 6  # no torque, no running cycle

    def nearest_point(self, theta, theta_dot):
        """The foot of :meth:`distance` on the boundary of saddle n: Newton's method on the
        dense output of L (:meth:`StableManifold.foot_points`, ≈ 1e-13) for both branches of
        that saddle, integrated past the point's speed plus its distance."""
        from atlas.boundaries.manifold import to_left_branch

        theta, theta_dot = np.broadcast_arrays(np.asarray(theta, float),
                                               np.asarray(theta_dot, float))
        dist, n = self.distance(theta, theta_dot)
        speed = float(np.max(np.abs(theta_dot) + dist, initial=0.0)) + _FIRST_MARGIN
        manifold = StableManifold(self.pendulum, speed)
        best = np.full(theta.shape, np.inf)
        foot_theta, foot_theta_dot = np.full(theta.shape, np.nan), np.full(theta.shape, np.nan)
        for right in (False, True):
            x, v = to_left_branch(n, right, theta, theta_dot)
            tau, dist = manifold.foot_points(x, v)
            fx, fv = manifold.at(np.reshape(tau, theta.shape))
            fx = (n + 1) * math.pi - fx if right else fx + (n - 1) * math.pi
            better = np.reshape(dist, theta.shape) < best
            best = np.where(better, np.reshape(dist, theta.shape), best)
            foot_theta = np.where(better, fx, foot_theta)
            foot_theta_dot = np.where(better, -fv if right else fv, foot_theta_dot)
        return best, foot_theta, foot_theta_dot, np.full(theta.shape, self.reference_error)


    def basin_outline(self, speed: float | None = None) -> Outline:
        """Γ through (π, 0), well 0's upper boundary (a strip), from the DOP853 dense output of
        L integrated past ``speed`` (default: the window's |θ̇| + 2) at
        :data:`OUTLINE_PIECES` points per sample interval of L (≤ 0.02 of arc length): the
        chord error, measured at each chord's midpoint, is about 1e-7; its right branch is
        the point reflection of L through (π, 0)."""
        from atlas.boundaries.segments import segment_distance

        if speed is None:
            speed = max(abs(v) for v in self.window[1]) + 2.0
        m = StableManifold(self.pendulum, speed + 1.0)
        t = m.tau
        pieces = np.arange(OUTLINE_PIECES) / OUTLINE_PIECES
        fine = np.append((t[:-1, None] + np.diff(t)[:, None] * pieces).ravel(), t[-1])
        theta, theta_dot = m.at(fine)
        mid_t, mid_v = m.at(0.5 * (fine[1:] + fine[:-1]))
        chord = float(segment_distance(mid_t, mid_v, theta[:-1], theta_dot[:-1], theta[1:],
                                       theta_dot[1:]).max(initial=0.0))
        # L from its far end to the saddle, then its point reflection from the saddle outward
        left_t = np.append(theta[::-1], math.pi)
        left_v = np.append(theta_dot[::-1], 0.0)
        return Outline(np.concatenate([left_t, 2.0 * math.pi - theta]),
                       np.concatenate([left_v, -theta_dot]), float(speed), chord, True, 0)


def _reference_error(fine: StableManifold, coarse: StableManifold) -> float:
    """Largest distance of the reference manifold at rtol 1e-12 (``coarse``) from the one at
    1e-13 (``fine``) over the window's θ̇ band."""
    speed = coarse.speed
    box = ((coarse.theta.min() - 1.0, math.pi + 1.0), (-speed, speed))
    inside = coarse.theta_dot <= speed  # both integrations end just beyond it
    dist, _ = fine.index(box).nearest(coarse.theta[inside], coarse.theta_dot[inside])
    return float(dist.max(initial=0.0))


class TiltedExact:
    """:class:`ExactBoundaries` with torque 0 < |τ| < ω0²: the stable branches of the tilted
    saddles (:class:`atlas.boundaries.tilted.TiltedBoundaries`, kept as ``tilted``; ``cycle``
    as there, or ``tilted`` itself if the caller built it). A boundary's saddle s_j is named
    n = 2j + 1 (the saddle near (2j + 1)π). Sides and distances are the branches' (their
    dense output), found through polylines."""

    def __init__(self, pendulum: Pendulum, window: Box, *, cycle=FIND_CYCLE, tilted=None):
        from atlas.boundaries.tilted import TiltedBoundaries

        self.pendulum, self.window = pendulum, window
        self.tilted = (TiltedBoundaries(pendulum, *window, cycle=cycle) if tilted is None
                       else tilted)
        self.running_possible = self.tilted.bistable
        # the wells a boundary of saddle n = 2j + 1 separates: bistable, one well from the
        # running basin — well j for τ > 0, and for τ < 0 (the mirror of canonical saddle
        # −j − 1, whose tongue holds canonical well −j − 1, i.e. actual well j + 1) well j + 1;
        # monostable, wells j and j + 1
        if not self.tilted.bistable:
            self.lower_well, self.upper_well = 0, 1
        else:
            self.lower_well = self.upper_well = 0 if pendulum.torque > 0 else 1
        self.areas = self.tilted.areas()
        self._vertices = {}  # the polylines' vertices binned, built on first use

    has_boundary, traced_as = True, "tilted"

    @property
    def cycle(self):
        return self.tilted.cycle

    @property
    def outline_reach(self) -> float:
        """The window's smaller |θ̇| edge: the branches are integrated over a band reaching
        beyond it (a point outside the window needs boundaries of its own)."""
        (_, _), (v0, v1) = self.window
        return min(abs(v0), abs(v1))

    def basin_outline(self, speed: float | None = None) -> Outline:
        """Γ through the saddle s_j of the first branch (:meth:`TiltedBoundaries.curves`'
        polyline, as integrated, no clipping; chord error ≤ 1e-8), the strip's upper
        boundary when monostable, the tongue's outline when bistable, over the band the
        branches were integrated in (ValueError where ``speed`` asks for more)."""
        tilted = self.tilted
        band = min(-tilted.band[0], tilted.band[1]) - 1e-9
        if speed is not None and speed > band:
            raise ValueError(f"the boundaries reach |theta_dot| < {band:g}, not {speed:g}")
        curves = tilted.curves(clip=False)
        j = curves[0][0]
        branch = {name: (t, v) for i, name, t, v in curves if i == j}
        (lt, lv), (rt, rv) = branch["left"], branch["right"]
        strip = not tilted.bistable
        # the boundary of saddle j bounds well j + upper_well from below when a strip, and
        # holds well j + lower_well as a tongue
        well = j + (self.upper_well - 1 if strip else self.lower_well)
        return Outline(np.concatenate([lt[::-1], rt[1:]]), np.concatenate([lv[::-1], rv[1:]]),
                       float(band if speed is None else speed), float(tilted.curves_chord_error),
                       strip, int(well))

    def __getstate__(self):
        return {**self.__dict__, "_vertices": {}}

    @property
    def reference_error(self) -> float:
        """The branches' error: their change from rtol 1e-12 (made on first use)."""
        return self.tilted.reference_error

    def side(self, theta, theta_dot):
        return self.tilted.side(theta, theta_dot)

    def side_and_distance(self, theta, theta_dot):
        side, dist, j = self.tilted.side_and_distance(theta, theta_dot)
        return side, dist, 2 * np.asarray(j, np.int64) + 1

    def running_shock(self):
        return self.tilted.running_shock()

    def nearest_point(self, theta, theta_dot):
        """The nearest point of every translate of the boundary, exact for the dense output of
        the branches (:meth:`atlas.boundaries.tilted.TiltedBoundaries.nearest_point`; its
        error the change from rtol 1e-12), one point at a time."""
        theta, theta_dot = np.broadcast_arrays(np.asarray(theta, float),
                                               np.asarray(theta_dot, float))
        out = [np.empty(theta.shape) for _ in range(4)]
        for i in np.ndindex(theta.shape):
            for part, value in zip(out, self.tilted.nearest_point(float(theta[i]),
                                                                 float(theta_dot[i]))):
                part[i] = value
        return tuple(out)

    def distance(self, theta, theta_dot):
        dist, j = self.tilted.distance(theta, theta_dot)
        return dist, 2 * np.asarray(j, np.int64) + 1

    def saddles_within(self, theta, theta_dot, radius: float):
        """(lowest, highest) saddle n = 2j + 1 of the boundaries with a vertex within
        ``radius`` + the longest segment of each point (a superset of the boundaries within
        ``radius``); (0, 0) where none."""
        from atlas.boundaries.tilted import MAX_SEGMENT
        from atlas.kernels.foot import saddles_near

        theta = np.ascontiguousarray(np.ravel(theta), dtype=float)
        theta_dot = np.ascontiguousarray(np.ravel(theta_dot), dtype=float)
        lo, hi = np.zeros(theta.size, np.int64), np.zeros(theta.size, np.int64)
        if not theta.size:
            return lo, hi
        (w0, w1), (u0, u1) = self.window
        reach = radius + MAX_SEGMENT
        # the vertices near the window suffice for points in it (the usual case)
        near = (reach <= _VERTEX_MARGIN and theta.min() >= w0 and theta.max() <= w1
                and theta_dot.min() >= u0 and theta_dot.max() <= u1)
        key = "window" if near else "all"
        if key not in self._vertices:  # every branch's vertices (near: in the window's margin)
            m = _VERTEX_MARGIN if near else math.inf
            t, v, j = self.tilted.vertices_within((w0 - m, w1 + m), (u0 - m, u1 + m))
            n = 2 * j + 1
            box = ((t.min(), t.max()), (v.min(), v.max())) if t.size else ((0, 1), (0, 1))
            self._vertices[key] = (t, v, n, box, bins(t, v, box, _VERTEX_CELL))
        t, v, n, ((t0, _), (v0, _)), (cell, shape, start, items) = self._vertices[key]
        saddles_near(theta, theta_dot, float(radius + MAX_SEGMENT), t, v, n.astype(np.int64),
                     start, items, float(t0), float(v0), float(cell), shape[0], shape[1],
                     lo, hi)
        return lo, hi


class UnboundedExact:
    """:class:`ExactBoundaries` of a pendulum without rest states (|τ| > ω0²): the running
    limit cycle is its only attractor, so its basin is the whole plane and there is no
    boundary: every side is :data:`RUNNING_SIDE`, every distance +inf, the running fraction
    1, exactly."""

    running_possible = True
    lower_well = upper_well = 0
    reference_error = 0.0
    has_boundary, traced_as, cycle, outline_reach = False, "", None, 0.0

    def __init__(self, pendulum: Pendulum, window: Box):
        self.pendulum, self.window = pendulum, window
        self.areas = ExactAreas(np.zeros(0, np.int64), np.zeros(0), np.zeros(0), 1.0, 0.0)

    def side(self, theta, theta_dot):
        shape = np.broadcast_shapes(np.shape(theta), np.shape(theta_dot))
        return np.full(shape, RUNNING_SIDE, np.int64)

    def distance(self, theta, theta_dot):
        shape = np.broadcast_shapes(np.shape(theta), np.shape(theta_dot))
        return np.full(shape, np.inf), np.zeros(shape, np.int64)

    def side_and_distance(self, theta, theta_dot):
        return (self.side(theta, theta_dot), *self.distance(theta, theta_dot))

    def nearest_point(self, theta, theta_dot):
        shape = np.broadcast_shapes(np.shape(theta), np.shape(theta_dot))
        return (np.full(shape, np.inf), np.full(shape, np.nan), np.full(shape, np.nan),
                np.full(shape, np.nan))

    def running_shock(self):
        return (math.nan,) * 6  # the running basin is the whole plane: no boundary

    def basin_outline(self, speed: float | None = None) -> Outline:
        raise ValueError("a pendulum without rest states has no well basins")

    def saddles_within(self, theta, theta_dot, radius: float):
        size = np.broadcast_shapes(np.shape(theta), np.shape(theta_dot))
        zeros = np.zeros(int(np.prod(size)), np.int64)
        return zeros, zeros.copy()
