"""The exact basin boundaries of the pendulum with torque, 0 < |τ| < ω0² (TiltedBoundaries).

θ̈ = −ω0² sin θ − 2αθ̇ + τ (α > 0 [s⁻¹], ω0 [rad s⁻¹], τ [rad s⁻²]). The rest states are
(θ* + 2πk, 0), θ* = arcsin(τ/ω0²) (*well k*), the saddles s_j = (π − θ* + 2πj, 0). Each
saddle's two stable branches are integrated once, for j = 0, by DOP853 (rtol = atol
= 1e-13, dense output; compiled, :mod:`atlas.kernels.dop853`) in reversed time from 1e-7
along the stable eigenvector until they leave a band of θ̇ around the window; every other
branch is a 2π translate, and
(θ, θ̇, τ) → (−θ, −θ̇, −τ) gives τ < 0. Above the homoclinic torque the basins are tongues
in a running basin (*bistable*, checked against :func:`atlas.physics.running.limit_cycle`),
below it strips. Sides (ray parity over polylines of chord error ≤ ``CHORD_TOL``, the nearest
point's side within reach of the arcs), distances (the chords searched,
:class:`atlas.boundaries.segments.Segments`, the arcs measured by Newton's method) and areas
(curved polygons clipped) are exact for the dense output, their error ``reference_error``
(the change from rtol 1e-12 to 1e-13). Units: θ [rad], θ̇ [rad s⁻¹], distances and areas in
the (θ, θ̇) plane with both as one unit ("rad-ish"). References: Krauskopf et al., Int. J.
Bifurcation Chaos 15 (2005) 763; Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5–6; Levi,
Hoppensteadt & Miranker, Q. Appl. Math. 36 (1978) 167. Derivation: docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import math
from functools import cached_property, partial

import numpy as np

from atlas.boundaries.basins import FIND_CYCLE, RUNNING_SIDE, ExactAreas
from atlas.boundaries.branches import CHORD_TOL, MAX_SEGMENT, FundamentalBranches, Polyline
from atlas.boundaries.manifold import RTOL, RTOL_CHECK
from atlas.boundaries.segments import Segments
from atlas.physics.pendulum import Pendulum

__all__ = ["TiltedBoundaries", "RUNNING_SIDE", "CHORD_TOL", "CURVE_CHORD_TOL", "MAX_SEGMENT",
           "MARGIN"]

#: The same for the finer polylines of :meth:`TiltedBoundaries.curves` (the basin polygons
#: of the Gaussian basin stability, whose error their chord error enters).
CURVE_CHORD_TOL = 1e-8
#: How far [units of the largest chord distance measured, at the middle time of each chord]
#: a branch is taken to stray from its chords: the distance search's reach beyond them, and
#: the band around the curves where a side is read off the nearest point instead.
SLACK = 2.0
#: Default clearance [rad-ish] of the integrated band beyond the window's θ̇ range (and of the
#: boundary search beyond its θ range).
MARGIN = 2.0
#: How far [rad] points may lie beyond the window's θ range and still be answered by the
#: window's distance index (the trace's probes and located points lie about 1e-3 off
#: vertices in the window).
_INDEX_SLACK = 0.01
_TWO_PI = 2.0 * math.pi


def _runs_around(inside: np.ndarray):
    """(start, stop) of each run of vertices where ``inside`` holds, widened by one vertex at
    either end (so that the run's polyline reaches the edge of the region), the runs that
    then touch merged."""
    near = inside.copy()
    near[1:] |= inside[:-1]
    near[:-1] |= inside[1:]
    edges = np.flatnonzero(np.diff(near, prepend=False, append=False))
    return zip(edges[::2].tolist(), edges[1::2].tolist())


def _first_where(x: np.ndarray, shift: float, bound: float, side: str) -> int:
    """The first index of the sorted ``x`` where x + ``shift`` (rounded, so monotone in x)
    is ≥ ``bound`` (side 'left') or > it ('right'): numpy's bisection on x against
    bound − shift, then moved while the rounded sums say otherwise."""
    i = int(np.searchsorted(x, bound - shift, side=side))

    def beyond(j):
        return x[j] + shift > bound if side == "right" else x[j] + shift >= bound

    while i > 0 and beyond(i - 1):
        i -= 1
    while i < x.size and not beyond(i):
        i += 1
    return i


# --------------------------------------------------------------------------- the boundaries

class TiltedBoundaries:
    """The exact basin boundaries of ``pendulum`` (α > 0, 0 < |τ| < ω0²) for the window
    θ ∈ ``theta_window`` [rad] × θ̇ ∈ ``theta_dot_window`` [rad s⁻¹]
    (docs/design/tilted-boundaries.md).

    The branches are integrated over the band of θ̇ reaching ``margin`` [rad-ish] beyond the
    window (and beyond ±(ω0² + |τ|)/(2α)); :meth:`side` answers for any θ and θ̇ in that
    band, :meth:`distance` for any point.

    Attributes: ``pendulum``; ``window``; ``bistable`` (a running limit cycle exists, checked
    against :func:`atlas.physics.running.limit_cycle`); ``cycle`` (that limit cycle, or None);
    ``band`` (bottom, top) [rad s⁻¹] in the actual frame; ``chord_error`` and
    ``reference_error`` [rad-ish] (docs/design/tilted-boundaries.md). It pickles without its
    distance search indices, which are rebuilt on first use.
    """

    def __init__(self, pendulum: Pendulum, theta_window, theta_dot_window, *,
                 rtol: float = RTOL, margin: float = MARGIN, cycle=FIND_CYCLE):
        """``cycle``: :func:`atlas.physics.running.limit_cycle`'s result for this pendulum if the
        caller has it (None: there is none); found here by default."""
        from atlas.physics.running import cycle_escapes

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
        self.fundamental = FundamentalBranches(canon, rtol, *self._band)
        self.fundamental_check = FundamentalBranches(canon, RTOL_CHECK, *self._band)
        ends, check = self.fundamental.ends, self.fundamental_check.ends
        if ends[1] != "bottom" or check != ends:
            raise RuntimeError(f"unexpected stable branches: ends {ends} "
                               f"(rtol {rtol:g}), {check} ({RTOL_CHECK:g})")
        self.bistable = self.fundamental.bistable
        self._escapes = None
        if cycle is FIND_CYCLE:  # found on first use; its existence checked now
            self._escapes = cycle_escapes(p.alpha, p.omega0, p.torque)
            exists = all(x > 0.0 for x in self._escapes)
        else:
            self.cycle = cycle
            exists = cycle is not None
        if exists != self.bistable:
            raise RuntimeError("the stable branch L_0 disagrees with atlas.physics.running "
                               "about the running limit cycle (too close to the homoclinic "
                               "torque?)")
        self._indices = {}  # (θ lo, θ hi) → Segments: the window's, and the last one beyond

    def __getstate__(self):  # sent to workers without the distance indices (rebuilt there)
        return {**self.__dict__, "_indices": {}}

    @cached_property
    def cycle(self):
        """The running limit cycle (:func:`atlas.physics.running.limit_cycle`), None if there
        is none; found on first use unless the caller gave it."""
        from atlas.physics.running import limit_cycle

        p = self.pendulum
        return limit_cycle(p.alpha, p.omega0, p.torque) if self.bistable else None

    # ------------------------------------------------------------------ polylines
    @cached_property
    def _fine(self) -> Polyline:
        """Γ_0 at rtol, its polyline refined to CHORD_TOL (made on first use: the areas and
        nearest points do not need it): the chords of the sides and distances."""
        return self.fundamental.polyline()

    @cached_property
    def _coarse(self) -> Polyline:
        """Γ_0 at RTOL_CHECK, its polyline through the fine one's reversed times."""
        return self.fundamental_check.polyline(times=self._fine.times)

    @cached_property
    def chord_error(self) -> float:
        """The search polylines' chord error [rad-ish] (≤ CHORD_TOL): how far apart the
        chords the sides and distances search and the curves they stand for are (the
        results are the curves': it is not their error)."""
        return self._fine.chord_error

    @property
    def curves_chord_error(self) -> float:
        """The chord error [rad-ish] (≤ CURVE_CHORD_TOL) of :meth:`curves`' polylines."""
        return self.fundamental.polyline(CURVE_CHORD_TOL).chord_error

    @property
    def _slack(self) -> float:
        """How far [rad-ish] a branch is taken to stray from its search chords."""
        return SLACK * self.chord_error

    @cached_property
    def reference_error(self) -> float:
        """The polylines' change from rtol 1e-13 to 1e-12 [rad-ish]
        (:meth:`_reference_error`)."""
        return self._reference_error()

    # ------------------------------------------------------------------ frames
    def _canonical(self, theta, theta_dot):
        theta, theta_dot = np.broadcast_arrays(np.asarray(theta, float),
                                               np.asarray(theta_dot, float))
        return self.sign * theta, self.sign * theta_dot

    def canonical_window(self):
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
        """Largest distance of the rtol 1e-12 branches from the 1e-13 ones, over the former's
        polyline vertices (canonical frame, Γ_0 only: the translates are exact copies): each
        vertex's nearest point of the 1e-13 branch, from the vertex at the same reversed time
        (the two solutions drift apart along the curve far more than across it, ~1e-5
        against ~1e-10), by Gauss–Newton steps along the branch (its velocity is the vector
        field's: dy/dτ = −f(y) in reversed time), three of them: each leaves the square of the
        drift times the curvature."""
        canon = Pendulum(self.pendulum.alpha, self.pendulum.omega0, abs(self.pendulum.torque))
        worst = 0.0
        for i, coarse in enumerate((self._coarse.left, self._coarse.right)):
            dense, sol, _ = self.fundamental.branches[i]
            times = self._coarse.times[i]
            first, last = times[0], sol.t[-1]
            cx, cy = coarse[0, 1:], coarse[1, 1:]  # the saddle left out: the same point
            tau = np.minimum(times, last)
            for _ in range(3):
                x, v = dense(tau)
                f0, f1 = canon.field(x, v)
                along = (x - cx) * f0 + (v - cy) * f1  # the velocity is −f
                tau = np.clip(tau + along / (f0 * f0 + f1 * f1), first, last)
            x, v = dense(tau)
            worst = max(worst, float(np.hypot(x - cx, v - cy).max(initial=0.0)))
        return worst

    # ------------------------------------------------------------------ curves
    def curves(self, clip: bool = True):
        """The branches that meet the window: a list of (saddle index j, branch 'left' or
        'right', θ [rad], θ̇ [rad s⁻¹]) in the actual frame, each from its saddle outward
        (the first vertex is the saddle itself) to where it leaves the band, as polylines
        with chord error ≤ CURVE_CHORD_TOL (:attr:`curves_chord_error`). With ``clip``,
        only the parts in the window (each run of vertices inside, with one vertex beyond
        either end so that it reaches the window's edge), one entry per run."""
        return list(self.iter_curves(clip))

    def iter_curves(self, clip: bool = True):
        """:meth:`curves` one entry at a time (unclipped, all translates of a monostable
        pendulum's branches together take hundreds of MB; one at a time, a few)."""
        (a, b), (v0, v1) = self.window
        for j, branch, vertices, _ in self.branches(CURVE_CHORD_TOL):
            theta, theta_dot = vertices()
            if not clip:
                yield j, branch, theta, theta_dot
                continue
            inside = (theta >= a) & (theta <= b) & (theta_dot >= v0) & (theta_dot <= v1)
            for start, stop in _runs_around(inside):
                yield j, branch, theta[start:stop], theta_dot[start:stop]

    def branches(self, tol: float = CHORD_TOL):
        """The unclipped branches (polylines of chord error ≤ ``tol``), each as (saddle
        index j, branch, ``vertices``, ``on_curve``): ``vertices(index=slice(None))`` gives
        (θ [rad], θ̇ [rad s⁻¹]) of the vertices ``index`` (a slice or an index array) of that
        branch — the same doubles as the whole branch's there, without shifting the whole
        polyline to Γ_k for a few —, ``on_curve(segment, fraction)`` the points of the
        branch itself (its dense output) at the reversed time that fraction of the way along
        each segment (between vertices segment and segment + 1)."""
        f = self.fundamental.polyline(tol)
        for k in self._translates(*self.canonical_window()[0]):
            for i, (name, xy) in enumerate((("left", f.left), ("right", f.right))):
                branch = name if self.sign > 0 else {"left": "right", "right": "left"}[name]
                yield (self._saddle(k), branch, partial(self._translate, xy, k),
                       partial(self._on_curve, i, f.times[i], k))

    def _translate(self, xy, k: int, index=slice(None)):
        """(θ [rad], θ̇ [rad s⁻¹]) in the actual frame of the vertices ``index`` of Γ_0's
        polyline ``xy`` (canonical) shifted to Γ_k: the one place the curves, the branches,
        the axis crossings and the binned vertices take them from (the same doubles for a
        vertex, however many are asked)."""
        return self.sign * (xy[0, index] + _TWO_PI * k), self.sign * xy[1, index]

    def _on_curve(self, branch: int, times, k, segment, fraction):
        """(θ [rad], θ̇ [rad s⁻¹]) in the actual frame of Γ_k's branch ``branch`` (0: L, 1: R)
        at the reversed time ``fraction`` of the way along its polyline's segments
        ``segment`` (vertex times ``times``, the saddle as vertex 0; the first segment is the
        straight piece from the saddle)."""
        dense = self.fundamental.branches[branch][0]
        segment, fraction = np.asarray(segment, np.int64), np.asarray(fraction, float)
        t = np.concatenate([[0.0], times])
        at = t[segment] + fraction * (t[segment + 1] - t[segment])
        x, v = dense(np.maximum(at, times[0]))
        # the straight piece: the saddle to the branch's first point
        straight = segment == 0
        if straight.any():
            f = fraction[straight]
            x[straight] = self.fundamental.saddle + f * (x[straight] - self.fundamental.saddle)
            v[straight] = f * v[straight]
        return self.sign * (x + _TWO_PI * np.asarray(k)), self.sign * v

    def axis_speeds(self) -> np.ndarray:
        """θ̇ [rad s⁻¹] where the branches in the window (the search polylines' runs, clipped
        as :meth:`curves` clips its own) cross the axis θ = 0, on the branches themselves (a
        segment whose ends have θ of opposite signs holds a crossing of its arc, found by
        bisection in reversed time on the dense output, :meth:`_axis_crossings`); unsorted. Found on
        Γ_0: Γ_k's segment crosses θ = 0 where Γ_0's crosses θ = −2πk (each segment, shorter
        than MAX_SEGMENT, can cross one line only), so only the segments that cross and their
        neighbours (the clipping) are shifted."""
        (a, b), (v0, v1) = self.window
        ks = self._translates(*self.canonical_window()[0])
        speeds = []
        f = self._fine
        for branch, xy in enumerate((f.left, f.right)):
            x = xy[0]
            k = np.rint(-0.5 * (x[:-1] + x[1:]) / _TWO_PI).astype(np.int64)  # the one line
            seg = np.flatnonzero((k >= ks.start) & (k < ks.stop))
            shifted = (x[seg] + _TWO_PI * k[seg], x[seg + 1] + _TWO_PI * k[seg])
            seg = seg[np.sign(shifted[0]) * np.sign(shifted[1]) < 0]
            crossing = []
            for i, k_i in zip(seg.tolist(), k[seg].tolist()):
                # the segment belongs to a clipped run when both ends are next to a vertex of
                # Γ_k in the window (:meth:`iter_curves`)
                near = np.arange(max(i - 1, 0), min(i + 2, x.size - 1) + 1)
                theta, theta_dot = self._translate(xy, k_i, near)
                inside = (theta >= a) & (theta <= b) & (theta_dot >= v0) & (theta_dot <= v1)
                at = i - near[0]  # the segment's first end within ``near``
                if inside[max(at - 1, 0):at + 2].any() and inside[at:at + 3].any():
                    crossing.append((i, k_i))
            if crossing:
                speeds.append(self._axis_crossings(branch, f.times[branch],
                                                   *np.array(crossing).T))
        return np.concatenate(speeds) if speeds else np.zeros(0)

    def _axis_crossings(self, branch: int, times, segment, k) -> np.ndarray:
        """θ̇ [rad s⁻¹] where Γ_k's branch ``branch`` crosses θ = 0 within each of its
        polyline's segments ``segment`` (whose ends have θ of opposite signs): bisection on
        the fraction of each segment's reversed time, all at once, to 2⁻⁵⁰ of it."""
        lo, hi = np.zeros(segment.size), np.ones(segment.size)
        start, _ = self._on_curve(branch, times, k, segment, lo)
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            theta, _ = self._on_curve(branch, times, k, segment, mid)
            same = np.sign(theta) == np.sign(start)
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        theta, theta_dot = self._on_curve(branch, times, k, segment, 0.5 * (lo + hi))
        return theta_dot

    def vertices_within(self, theta_range, theta_dot_range):
        """(θ [rad], θ̇ [rad s⁻¹], saddle j) of every vertex of every branch's search polyline
        (:meth:`branches`, unclipped) with θ ∈ ``theta_range`` and θ̇ ∈ ``theta_dot_range``
        (closed; infinite bounds allowed), in no particular order. Γ_0's vertices within the
        θ̇ range are sorted by θ once; Γ_k's within the θ range are then a slice of them
        (θ0 + 2πk, rounded, is monotone in θ0), its ends found by bisection and checked on the
        shifted values."""
        (t0, t1), (u0, u1) = theta_range, theta_dot_range
        f = self._fine
        xy = np.concatenate([f.left, f.right], axis=1)
        speed = self.sign * xy[1]
        xy = xy[:, (speed >= u0) & (speed <= u1)]
        xy = xy[:, np.argsort(xy[0], kind="stable")]
        lo, hi = sorted((self.sign * t0, self.sign * t1))  # θ0 + 2πk ∈ [lo, hi], canonical
        parts = []
        for k in self._translates(*self.canonical_window()[0]):
            first = _first_where(xy[0], _TWO_PI * k, lo, "left")
            stop = _first_where(xy[0], _TWO_PI * k, hi, "right")
            theta, theta_dot = self._translate(xy, k, slice(first, stop))
            parts.append((theta, theta_dot, np.full(theta.size, self._saddle(k), np.int64)))
        return tuple(np.concatenate([q[i] for q in parts]) for i in range(3))

    # ------------------------------------------------------------------ side
    def side(self, theta, theta_dot):
        """The basin of the exact equation each point (θ [rad], θ̇ [rad s⁻¹], broadcast) lies
        in: the well k (rest state (arcsin(τ/ω0²) + 2πk, 0), the kernels' ``attractor``), or
        :data:`RUNNING_SIDE` for the running basin (:meth:`side_and_distance`; the branches
        are searched only as far as its band around them). θ̇ must lie within ``band``;
        ValueError otherwise."""
        return self._sides(theta, theta_dot, full=False)[0]

    def side_and_distance(self, theta, theta_dot):
        """(:meth:`side`, :meth:`distance`'s distance and saddle) of each point, from one
        search. The side is the parity of the upward vertical ray's crossings with the
        search polylines' chords, exact for the branches (their dense output) wherever a
        point lies farther from them than the chords stray (SLACK·``chord_error``): only
        between a chord and its arc can the two differ. A point nearer than twice that is
        given the side of the point 3·SLACK·``chord_error`` from its nearest point of the
        branches, on its own side (along the normal there: beyond the chords). Its error:
        ``reference_error``."""
        return self._sides(theta, theta_dot, full=True)

    def _sides(self, theta, theta_dot, full: bool):
        """:meth:`side_and_distance`; without ``full`` the branches are searched within the
        band 2·SLACK·``chord_error`` only (the distances are inf beyond it)."""
        x, v = self._canonical(theta, theta_dot)
        shape = x.shape
        x, v = x.ravel(), v.ravel()
        bottom, top = self._band
        if not np.all((v > bottom) & (v < top)):
            raise ValueError(f"theta_dot must lie within the band {self.band} of the "
                             "integrated boundaries")
        if x.size == 0:
            return (np.zeros(shape, np.int64), np.zeros(shape), np.zeros(shape, np.int64))
        dist, k, foot_x, foot_y = self._nearest_curves(
            x, v, None if full else 2.0 * self._slack)
        out = self._ray_sides(x, v)
        near = np.flatnonzero((dist <= 2.0 * self._slack) & (dist > 0.0))
        if near.size:
            reach = 3.0 * self._slack / dist[near]
            out[near] = self._ray_sides(foot_x[near] + reach * (x[near] - foot_x[near]),
                                        foot_y[near] + reach * (v[near] - foot_y[near]))
        if self.sign < 0:
            out = np.where(out == RUNNING_SIDE, out, -out)
        return (out.reshape(shape), dist.reshape(shape), self._saddle(k).reshape(shape))

    def _ray_sides(self, x, v):
        """The side of canonical points by the ray's crossings with the search chords."""
        lo, hi = float(x.min()), float(x.max())
        ks = self._translates(lo, hi)
        f = self._fine
        # L_k continues left above the band when it leaves at the top
        flip = (f.theta[0] + _TWO_PI * np.arange(ks.start, ks.stop)
                if self.fundamental.ends[0] == "top" else np.full(len(ks), -np.inf))
        index = self._index(lo - self.margin - MAX_SEGMENT, hi + self.margin + MAX_SEGMENT)
        return index.sides(x, v, ks.start, ks.stop - 1, flip, self.bistable, RUNNING_SIDE)

    # ------------------------------------------------------------------ distance
    def _index(self, theta_lo: float, theta_hi: float) -> Segments:
        """Segments of every Γ_k (canonical) that hold those with a vertex in θ ∈ [lo, hi] and
        their neighbours: sides and distances of points are the same for any such superset
        (they need only segments within reach of the points). An index built before whose θ
        range covers [lo, hi] is used; else the window's (its θ range ± ``margin``,
        MAX_SEGMENT and ``_INDEX_SLACK``: every query of points in the window, or next to it,
        whatever asks), built once and kept; else, for a query beyond it, [lo, hi]'s (the
        last such one kept too)."""
        for (lo, hi), index in self._indices.items():
            if lo <= theta_lo and theta_hi <= hi:
                return index
        (a, b), _ = self.canonical_window()
        reach = self.margin + MAX_SEGMENT + _INDEX_SLACK
        window = (a - reach, b + reach)
        key = window if window[0] <= theta_lo and theta_hi <= window[1] \
            else (theta_lo, theta_hi)
        kept = {k: index for k, index in self._indices.items() if k == window}
        self._indices = {**kept, key: self._segments(*key)}
        return self._indices[key]

    def _segments(self, theta_lo: float, theta_hi: float) -> Segments:
        """The segments of every Γ_k (canonical) with a vertex in θ ∈ [lo, hi], and their
        neighbours, with the curves they stand for: per translate k, the runs of Γ_0's
        search polyline's vertices in [lo − 2πk, hi − 2πk], one vertex beyond either end,
        shifted by 2πk."""
        f = self._fine
        runs = []
        for k in self._translates(theta_lo, theta_hi):
            shift = _TWO_PI * k
            inside = (f.theta >= theta_lo - shift) & (f.theta <= theta_hi - shift)
            runs.extend((f.theta[start:stop] + shift, f.theta_dot[start:stop], k,
                         f.step[start:stop - 1], f.span[start:stop - 1], shift)
                        for start, stop in _runs_around(inside))
        return Segments(runs)

    def distance(self, theta, theta_dot):
        """(distance, saddle): the Euclidean distance [rad-ish, θ and θ̇ as one unit] from each
        point (θ [rad], θ̇ [rad s⁻¹], broadcast) to the nearest basin boundary, and the index j
        of that boundary's saddle s_j (the translate of the branches through it).

        The distance is to the branches themselves, their dense output: the search
        polylines' chords, each within SLACK·``chord_error`` of its arc, are searched for
        the arcs that may be nearest, and each such arc is measured by Newton's method on its
        polynomial (:func:`atlas.kernels.segments.nearer_curves`). The boundaries within
        θ ± ``margin`` of the points are searched first (the window's index, :meth:`_index`).
        A point is done when the distance found is at most its clearance from the θ range
        the searched segments cover (less MAX_SEGMENT and the slack): every other arc lies
        beyond that range, farther. The others are searched again on the boundaries within
        θ ± the largest distance found (no nearer boundary can lie beyond; a whole turn more
        if none was found), each from its squared distance found, a bound that prunes the
        wider search at once, skipping the boxes within the θ range searched before: the
        same minimum as a search of the wider index alone, and so on. Exact for the dense
        output wherever the distance is at most the point's clearance from the band's edges
        beyond which the boundaries continue (the bottom, and the top when the branches
        leave there: ``bistable`` false); for points of the window that is at least
        ``margin``. The error: ``reference_error``."""
        x, v = self._canonical(theta, theta_dot)
        shape = x.shape
        if x.size == 0:
            return np.zeros(shape), np.zeros(shape, np.int64)
        dist, k, _, _ = self._nearest_curves(x.ravel(), v.ravel())
        return dist.reshape(shape), self._saddle(k).reshape(shape)

    def _nearest_curves(self, x, v, within: float | None = None):
        """(distance, canonical k, foot θ, foot θ̇) of canonical points (flat) to the nearest
        branch (:meth:`distance`'s search); with ``within`` [rad-ish], only the branches that
        near (inf and NaN feet beyond: one search of the window's index, which holds every
        branch within reach of its points)."""
        from atlas.kernels.segments import nearer_curves

        dist2 = np.full(x.size, np.inf if within is None else within * within)
        k = np.zeros(x.size, np.int64)
        foot_x, foot_y = np.full(x.size, np.nan), np.full(x.size, np.nan)
        F, y_old, _ = self.fundamental.packed
        slack = self._slack
        todo, reach = np.arange(x.size), self.margin
        searched = (math.inf, -math.inf)  # θ where every segment has been searched
        while todo.size:
            lo, hi = float(x[todo].min()), float(x[todo].max())
            wanted = (lo - reach - MAX_SEGMENT, hi + reach + MAX_SEGMENT)
            index = self._index(*wanted)
            # the θ range whose segments it holds: its key (a kept index may cover more)
            covered = next((key for key, kept in self._indices.items() if kept is index),
                           wanted)
            px, py, d2, near = x[todo], v[todo], dist2[todo], k[todo]
            fx, fy = foot_x[todo], foot_y[todo]
            nearer_curves(px, py, index.ax, index.ay, index.bx, index.by, index.tag,
                          index.xlo, index.xhi, index.ylo, index.yhi, index.start, *searched,
                          slack, index.step, index.span, index.shift, F, y_old, d2, near, fx,
                          fy)
            dist2[todo], k[todo], foot_x[todo], foot_y[todo] = d2, near, fx, fy
            if within is not None:
                return np.where(np.isnan(foot_x), np.inf, np.sqrt(dist2)), k, foot_x, foot_y
            found = np.sqrt(d2)
            # every arc the index lacks lies beyond the θ range it covers (its chords do,
            # and the arc strays from them by the slack at most)
            beyond = found > (np.minimum(px - covered[0], covered[1] - px) - MAX_SEGMENT
                              - slack)
            todo, found = todo[beyond], found[beyond]
            # the segments there are searched (the index holds every one with a vertex in its
            # θ range: those within it, to the rounding of the translates' shifts)
            searched = (covered[0] + MAX_SEGMENT, covered[1] - MAX_SEGMENT)
            # none nearer than the distance found lies beyond it (a whole turn if none found)
            reach = float(found.max(initial=reach + _TWO_PI)) if np.all(np.isfinite(found)) \
                else reach + _TWO_PI
        return np.sqrt(dist2), k, foot_x, foot_y

    # ------------------------------------------------------------------ areas, shocks
    def areas(self) -> ExactAreas:
        """The exact area fraction of the window in each basin
        (:func:`atlas.boundaries.tilted_areas.window_areas`)."""
        from atlas.boundaries.tilted_areas import window_areas

        return window_areas(self)

    def running_shock(self):
        """The running limit cycle's minimal fatal shock
        (:func:`atlas.boundaries.tilted_nearest.running_shock`)."""
        from atlas.boundaries.tilted_nearest import running_shock

        return running_shock(self)

    def nearest_point(self, theta: float, theta_dot: float):
        """The nearest point of the boundaries to (θ, θ̇)
        (:func:`atlas.boundaries.tilted_nearest.nearest_point`)."""
        from atlas.boundaries.tilted_nearest import nearest_point

        return nearest_point(self, theta, theta_dot)

    @property
    def known_cycle(self):
        """The running limit cycle where it was given or found already, else None (not
        searched for here)."""
        return self.__dict__.get("cycle")

    @property
    def escapes(self):
        """The running cycle's escape test of :func:`atlas.physics.running.cycle_escapes`,
        where the cycle was not given (None otherwise)."""
        return self._escapes
