"""Labels certified for the exact equation, and the honest error of grid-counted fractions.

The energy trap (:mod:`atlas.labels.labelling`) certifies that the orbit of the *RK4 map* at step dt
stays in its well. Before it is trapped, that orbit carries RK4's global error, so next to a
basin boundary the exact equation's orbit may end in the other well. The RK4 map's basin
boundaries are displaced from the exact ones — the stable manifolds of the saddles,
integrated independently by DOP853 (:mod:`atlas.boundaries.manifold`) — by at most ``shift``, which
:func:`atlas.boundaries.separatrices.trace` measures: the largest distance of its bisected boundary
points (located on RK4 labels to within ``tol``) from the DOP853 manifold. A label is
therefore certified for the exact equation when

* the RK4 label is the basin on whose side of the exact boundaries the point lies, and
* the point's distance to the nearest exact boundary exceeds

      d_cert = SAFETY · (shift + tol + reference_error),

  with ``reference_error`` the measured change of the reference from rtol 1e-12 to 1e-13.

Why SAFETY = 10: the shift is measured at every traced vertex, at most ``max_spacing`` apart
along the whole boundary; it is the smooth O(dt⁴) offset of the RK4 scheme (it interpolates
between vertices by a cubic spline to ≈ tol/16, see :mod:`atlas.boundaries.separatrices`), so between
vertices it exceeds its largest vertex value by far less than tenfold; the copies of the
traced branches are exact images of them (the RK4 map commutes with θ → θ + 2π and
(θ, θ̇) → (−θ, −θ̇) up to the rounding of θ, ≈ 1e-15). Trapped labels that fail either test
get the status ``near_boundary``: certified for the RK4 map only.

With a torque τ the same argument holds with the tilted boundaries of :mod:`atlas.boundaries.tilted`
(their reference error includes the polylines' chord error) and the running basin as one more
basin: a ``running`` label (the RK4 map's orbit entered the running barrier,
:mod:`atlas.physics.running`) on the running side and beyond d_cert is certified for the exact
equation, otherwise it becomes ``running_near_boundary``. The RK4 map commutes with the 2π
shift (checked: :func:`atlas.boundaries.separatrices.trace_tilted`'s ``shift_error``); there is no point
reflection, so every copy of a boundary is located on its own labels. Without rest states
(|τ| > ω0²) there is no boundary and the running cycle attracts everything
(:class:`NoBoundaries`).

A grid count is not an area. The grid fraction f_k = (points labelled k)/N differs from the
exact area fraction F_k = Σ_cells area(cell ∩ basin k)/A by the sum over cells of
1{label = k}/N − area(cell ∩ basin k)/A. A cell (the part of the window nearest its grid
point) whose point is certified and farther than the cell's half-diagonal from every boundary
lies wholly in its basin: it contributes |1/N − a/A| (a its area). Every other cell — cut by
a boundary, uncertified or unresolved — contributes at most max(1/N, a/A) to each basin it
may meet (the labelled one, the exact side, and those of every boundary within the
half-diagonal). The sum is ``basin_fraction_grid_error_bound``, a bound of first order in
the cell size; ``basin_fraction_grid_error`` is the measured |f_k − F_k|.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.boundaries.manifold import RTOL_CHECK, StableManifold, basin_areas
from atlas.kernels import (
    ATTRACTOR_FILL,
    NEAR_BOUNDARY,
    RUNNING,
    RUNNING_NEAR_BOUNDARY,
    TRAPPED,
)
from atlas.physics.pendulum import Pendulum

__all__ = ["SAFETY", "cert_distance", "Certifier", "NoBoundaries", "certifier_for",
           "exact_boundaries", "labelled", "add_tallies", "RUNNING_SIDE"]

#: Safety factor of d_cert over the measured RK4-vs-exact boundary shift (module docstring).
SAFETY = 10.0
#: The exact side of a point in the running basin (the kernels' fill value: no well).
RUNNING_SIDE = ATTRACTOR_FILL
#: First search radius around the grid for boundaries [rad-ish]; grown while needed.
_FIRST_MARGIN = 1.0
#: Cell side [rad-ish] of the bins over the tilted boundaries' vertices (the radii asked
#: for are about half a grid cell's diagonal).
_VERTEX_CELL = 0.05
#: Vertices farther than this [rad-ish] outside the window are not binned for points in it.
_VERTEX_MARGIN = 0.5


def cert_distance(shift: float, tol: float, reference_error: float) -> float:
    """d_cert [rad-ish]: the distance from the exact boundaries beyond which RK4 labels are
    labels of the exact equation (module docstring). NaN when ``shift`` was not measured."""
    return SAFETY * (shift + tol + reference_error)


def labelled(status):
    """Where an orbit has a well label: certified for the ODE (trapped) or for the RK4 map
    only (near_boundary)."""
    status = np.asarray(status)
    return (status == TRAPPED) | (status == NEAR_BOUNDARY)


class _Untilted:
    """The exact basin boundaries of the pendulum without torque (:mod:`atlas.boundaries.manifold`):
    side, distance, the boundaries near a point, exact areas and the reference's own error,
    for :class:`Certifier`."""

    running_possible = False
    #: The wells a boundary of saddle n (odd) separates: (n − 1)/2 + lower_well to
    #: (n − 1)/2 + upper_well (here the wells on either side of the saddle nπ).
    lower_well, upper_well = 0, 1

    def __init__(self, pendulum: Pendulum, window):
        self.pendulum, self.window = pendulum, window
        self._indices: dict[float, object] = {}
        # the left branch at rtol 1e-13 (the search index's) and at 1e-12, each integrated
        # once: for the exact areas and for the reference's own error
        fine = self._index(_FIRST_MARGIN).manifold
        coarse = StableManifold(pendulum, max(abs(v) for v in window[1]), RTOL_CHECK)
        areas = basin_areas(pendulum, *window, manifolds=(fine, coarse))
        self.k, self.fraction, self.error = areas.k, areas.fraction, areas.error
        self.running, self.running_error = 0.0, 0.0
        self._saddles = areas.saddles
        self.reference_error = self._reference_error(fine, coarse)

    def __getstate__(self):
        return {**self.__dict__, "_indices": {}}

    def _reference_error(self, fine: StableManifold, coarse: StableManifold) -> float:
        """Largest distance between the reference manifolds at rtol 1e-12 (``coarse``) and
        1e-13 (``fine``) over the window's θ̇ band: the DOP853 reference's own error,
        overestimated about tenfold."""
        speed = coarse.speed
        box = ((coarse.theta.min() - 1.0, math.pi + 1.0), (-speed, speed))
        inside = coarse.theta_dot <= speed  # both integrations end just beyond it
        dist, _ = fine.index(box).nearest(coarse.theta[inside], coarse.theta_dot[inside])
        return float(dist.max(initial=0.0))

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
        return self._index(_FIRST_MARGIN).manifold.side(theta, theta_dot, self._saddles)

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

    def saddles_within(self, theta, theta_dot, radius: float):
        return self._index(_FIRST_MARGIN).saddles_within(theta, theta_dot, radius)


class _Tilted:
    """The exact basin boundaries of the pendulum with torque 0 < |τ| < ω0²
    (:class:`atlas.boundaries.tilted.TiltedBoundaries`), with the interface of :class:`_Untilted`; a
    boundary's saddle s_j is named n = 2j + 1 (the saddle near (2j + 1)π). The reference
    error includes the polylines' chord error (the distances are measured to polylines)."""

    def __init__(self, pendulum: Pendulum, window, boundaries=None):
        from atlas.boundaries.tilted import TiltedBoundaries

        self.exact = (TiltedBoundaries(pendulum, *window) if boundaries is None
                      else boundaries)
        self.running_possible = self.exact.bistable
        # the wells a boundary of saddle n = 2j + 1 separates: bistable, one well from the
        # running basin — well j for τ > 0, and for τ < 0 (the mirror of canonical saddle
        # −j − 1, whose tongue holds canonical well −j − 1, i.e. actual well j + 1) well j + 1;
        # monostable, wells j and j + 1
        if not self.exact.bistable:
            self.lower_well, self.upper_well = 0, 1
        else:
            self.lower_well = self.upper_well = 0 if pendulum.torque > 0 else 1
        areas = self.exact.areas()
        self.k, self.fraction, self.error = areas.k, areas.fraction, areas.error
        self.running, self.running_error = areas.running, areas.running_error
        self.reference_error = self.exact.reference_error + self.exact.chord_error
        self.window = window
        self._vertices = {}  # the polylines' vertices binned, built on first use

    def __getstate__(self):
        return {**self.__dict__, "_vertices": {}}

    def side(self, theta, theta_dot):
        return self.exact.side(theta, theta_dot)

    def distance(self, theta, theta_dot):
        dist, j = self.exact.distance(theta, theta_dot)
        return dist, 2 * np.asarray(j, np.int64) + 1

    def saddles_within(self, theta, theta_dot, radius: float):
        """(lowest, highest) saddle n = 2j + 1 of the boundaries with a vertex within
        ``radius`` + the longest segment of each point (a superset of the boundaries within
        ``radius``); (0, 0) where none."""
        from atlas.boundaries.manifold import bins
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
        if key not in self._vertices:
            curves = self.exact.curves(clip=False)
            t = np.concatenate([t for _, _, t, _ in curves])
            v = np.concatenate([v for _, _, _, v in curves])
            n = np.concatenate([np.full(t.size, 2 * j + 1) for j, _, t, _ in curves])
            if near:
                m = _VERTEX_MARGIN
                keep = (t >= w0 - m) & (t <= w1 + m) & (v >= u0 - m) & (v <= u1 + m)
                t, v, n = t[keep], v[keep], n[keep]
            box = ((t.min(), t.max()), (v.min(), v.max())) if t.size else ((0, 1), (0, 1))
            self._vertices[key] = (t, v, n, box, bins(t, v, box, _VERTEX_CELL))
        t, v, n, ((t0, _), (v0, _)), (cell, shape, start, items) = self._vertices[key]
        saddles_near(theta, theta_dot, float(radius + MAX_SEGMENT), t, v, n.astype(np.int64),
                     start, items, float(t0), float(v0), float(cell), shape[0], shape[1],
                     lo, hi)
        return lo, hi


def exact_boundaries(pendulum: Pendulum, window, tilted=None):
    """The exact basin boundaries of ``pendulum`` over ``window`` ((θmin, θmax) [rad],
    (θ̇min, θ̇max) [rad s⁻¹]); None where atlas has none (|τ| ≥ ω0²: no rest state, no
    boundary; see :class:`NoBoundaries`). ``tilted``: the
    :class:`atlas.boundaries.tilted.TiltedBoundaries` of this window if the caller already built them."""
    if pendulum.torque == 0.0:
        return _Untilted(pendulum, window)
    if pendulum.has_rest_states:
        return _Tilted(pendulum, window, tilted)
    return None


class Certifier:
    """Boundary distances, certificates and grid-error tallies of one parameter point's
    basin map, tile by tile: grid axes ``theta0`` [rad] (columns) and ``theta_dot0``
    [rad s⁻¹] (rows), the window being their ranges; ``shift`` [rad-ish], the measured
    distance of the RK4 map's boundaries from the exact ones, located to ``tol`` (NaN when
    not measured: then no label is certified for the exact equation). With torque the
    running basin is one more basin: a running label is certified for the exact equation
    (status ``running``) on the same terms as a well's, else it becomes
    ``running_near_boundary``.

    A certifier is sent to where tiles are computed (a Dask worker): it pickles without its
    boundary indices, which are rebuilt on first use."""

    def __init__(self, pendulum: Pendulum, theta0, theta_dot0, shift: float, tol: float,
                 tilted=None):
        self.pendulum = pendulum
        self.theta0, self.theta_dot0 = np.asarray(theta0, float), np.asarray(theta_dot0, float)
        self.window = ((self.theta0[0], self.theta0[-1]), (self.theta_dot0[0],
                                                           self.theta_dot0[-1]))
        self.exact = exact_boundaries(pendulum, self.window, tilted)
        self.shift = float(shift)
        self.reference_error = self.exact.reference_error
        self.d_cert = cert_distance(shift, tol, self.reference_error)
        d_theta = np.diff(self.window[0])[0] / (self.theta0.size - 1)
        d_speed = np.diff(self.window[1])[0] / (self.theta_dot0.size - 1)
        self.half_diagonal = 0.5 * math.hypot(d_theta, d_speed)
        self.n_points = self.theta0.size * self.theta_dot0.size
        area = np.diff(self.window[0])[0] * np.diff(self.window[1])[0]
        # cell areas a/A: interior cells dθ·dθ̇, half of that on an edge, a quarter at corners
        self._col_weight = _edge_weights(self.theta0.size) * d_theta
        self._row_weight = _edge_weights(self.theta_dot0.size) * d_speed / area

    @property
    def areas(self):
        """The exact areas: ``k``, ``fraction``, ``error``, ``running``, ``running_error``."""
        return self.exact

    def distance(self, theta, theta_dot):
        """Distance [rad-ish] of each point to the nearest exact basin boundary, and that
        boundary's saddle n (odd)."""
        return self.exact.distance(theta, theta_dot)

    def certify(self, theta, theta_dot, attractor, status):
        """Certify labelled points (arrays broadcast to one shape; θ [rad], θ̇ [rad s⁻¹]):
        returns (status, with ``near_boundary`` / ``running_near_boundary`` where a trapped /
        running label is not certified for the exact equation; boundary distance
        [rad-ish]; the exact side: k, or RUNNING_SIDE for the running basin; the saddle n of
        the nearest boundary)."""
        theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
        full = np.broadcast_shapes(theta.shape, theta_dot.shape, np.shape(status))
        side = self.exact.side(theta, theta_dot)
        theta, theta_dot = np.broadcast_to(theta, full), np.broadcast_to(theta_dot, full)
        dist, n_near = self.distance(theta, theta_dot)
        status = np.asarray(status)
        has_label, running = labelled(status), status == RUNNING
        agree = (has_label | running) & (_basin(attractor, status) == side)
        certified = agree & (dist > self.d_cert)
        status = np.where(has_label & ~certified, NEAR_BOUNDARY, status)
        status = np.where(running & ~certified, RUNNING_NEAR_BOUNDARY, status).astype(np.int8)
        return status, dist, np.broadcast_to(side, full), n_near

    def tile(self, rows: slice, attractor, status):
        """Certify the grid rows ``rows`` (arrays shaped (rows, columns)) with
        :meth:`certify`; returns (status, boundary distance as float32, the tile's tally:
        basin counts and grid-error bounds over the wells k0, k0 + 1, …, the running count
        and bound, and the certified, mismatched and unlabelled counts; tallies of tiles add
        up, :func:`add_tallies`)."""
        theta, theta_dot = self.theta0[None, :], self.theta_dot0[rows][:, None]
        new_status, dist, side, n_near = self.certify(theta, theta_dot, attractor, status)
        has_label, running = labelled(status), status == RUNNING
        basin = _basin(attractor, status)
        k = attractor.astype(np.int64)
        agree = (has_label | running) & (basin == side)
        # the cell is wholly in its basin when the exact boundary, within reference_error of
        # the one measured, cannot cut it
        clean = agree & (dist > self.half_diagonal + self.reference_error)
        side_well = side != RUNNING_SIDE
        # the wells this tile can touch: its labels, its sides and their neighbours
        k_lo, k_hi, worst, may_run = self._doubt(rows, k, has_label, side, clean,
                                                 *np.broadcast_arrays(theta, theta_dot),
                                                 n_near)
        ks = np.concatenate([k[has_label], side[side_well].ravel(), k_lo, k_hi])
        k0 = int(ks.min()) if ks.size else 0
        size = int(ks.max()) - k0 + 1 if ks.size else 1
        count = np.bincount(k[has_label] - k0, minlength=size)
        weight = self._row_weight[rows][:, None] * self._col_weight[None, :]  # a/A
        gap = np.abs(1.0 / self.n_points - weight)
        # clean cells are wholly in their basin, off only by their weight; every other cell
        # counts at most max(1/N, a/A) in each basin it may meet
        clean_well = clean & has_label
        bound = np.bincount(k[clean_well] - k0, weights=gap[clean_well],
                            minlength=size).astype(float)
        change = np.bincount(k_lo - k0, weights=worst, minlength=size + 1) \
            - np.bincount(k_hi + 1 - k0, weights=worst, minlength=size + 1)
        bound += np.cumsum(change)[:size]
        running_bound = float(gap[clean & running].sum() + worst[may_run].sum())
        tally = {"k0": np.int64(k0), "count": count, "bound": bound,
                 "running_bound": np.float64(running_bound),
                 "certified": np.int64(np.count_nonzero((new_status == TRAPPED)
                                                        | (new_status == RUNNING))),
                 "mismatched": np.int64(np.count_nonzero((has_label | running) & ~agree
                                                         & (dist > self.d_cert))),
                 **_unlabelled(status)}
        return new_status, dist.astype(np.float32), tally

    def _doubt(self, rows, k, has_label, side, clean, theta, theta_dot, n_near):
        """For the cells that are not clean: the range of wells [k_lo, k_hi] each may meet
        (its label, its exact side, and both sides of every boundary within its
        half-diagonal), its weight max(1/N, a/A), and whether it may meet the running basin
        (its label or side is running, or a boundary of a running basin is near)."""
        doubt = ~clean
        lo_n, hi_n = self.exact.saddles_within(theta[doubt], theta_dot[doubt],
                                               self.half_diagonal)
        near = n_near[doubt]
        lo_n = np.where(lo_n == 0, near, np.minimum(lo_n, near))
        hi_n = np.where(hi_n == 0, near, np.maximum(hi_n, near))
        own_side = side[doubt]
        side_well = own_side != RUNNING_SIDE
        bottom = (lo_n - 1) // 2 + self.exact.lower_well
        top = (hi_n - 1) // 2 + self.exact.upper_well
        k_lo = np.where(side_well, np.minimum(bottom, own_side), bottom)
        k_hi = np.where(side_well, np.maximum(top, own_side), top)
        own = has_label[doubt]
        k_lo = np.where(own, np.minimum(k_lo, k[doubt]), k_lo)
        k_hi = np.where(own, np.maximum(k_hi, k[doubt]), k_hi)
        weight = self._row_weight[rows][:, None] * self._col_weight[None, :]
        may_run = np.full(k_lo.shape, self.exact.running_possible)
        return k_lo, k_hi, np.maximum(1.0 / self.n_points, weight[doubt]), may_run

    def summary(self, tally: dict) -> dict[str, np.ndarray]:
        """The parameter point's summary from the sum of its tiles' tallies: per basin k
        (every k the window meets or a label names) the exact fraction and its error, the grid
        fraction, its error bound and its measured error; the running basin's; and the
        point's certificate figures (the variables of :data:`atlas.store.atlasfile.BASIN_VARIABLES` and
        :data:`atlas.store.atlasfile.POINT_VARIABLES` but ``trap_margin``)."""
        k0 = int(tally["k0"])
        grid_k = np.arange(k0, k0 + tally["count"].size)
        a = self.exact
        ks = np.union1d(a.k, grid_k)
        exact = np.zeros(ks.size)
        error = np.zeros(ks.size)
        exact[np.searchsorted(ks, a.k)] = a.fraction
        error[np.searchsorted(ks, a.k)] = a.error
        grid = np.zeros(ks.size)
        bound = np.zeros(ks.size)
        grid[np.searchsorted(ks, grid_k)] = tally["count"] / self.n_points
        bound[np.searchsorted(ks, grid_k)] = tally["bound"]
        n = self.n_points
        running = int(tally["running"]) / n
        return {"k": ks, "basin_fraction_exact": exact, "basin_fraction_exact_error": error,
                "basin_fraction": grid, "basin_fraction_grid_error_bound": bound,
                "basin_fraction_grid_error": np.abs(grid - exact),
                "unresolved_fraction": int(tally["unlabelled"]) / n,
                "running_fraction": running,
                "running_fraction_exact": float(a.running),
                "running_fraction_exact_error": float(a.running_error),
                "running_fraction_grid_error_bound": float(tally["running_bound"]),
                "certified_fraction": int(tally["certified"]) / n, "d_cert": self.d_cert,
                "boundary_shift": self.shift, "boundary_reference_error": self.reference_error,
                "side_mismatches": int(tally["mismatched"])}


def _basin(attractor, status) -> np.ndarray:
    """The basin a label names: well k, or RUNNING_SIDE for a running orbit."""
    return np.where(np.asarray(status) == RUNNING, RUNNING_SIDE,
                    np.asarray(attractor, np.int64))


def add_tallies(tallies) -> dict:
    """The sum of tile tallies (:meth:`Certifier.tile`), aligned on their wells k."""
    tallies = list(tallies)
    k0 = min(int(t["k0"]) for t in tallies)
    size = max(int(t["k0"]) + t["count"].size for t in tallies) - k0
    total = {"k0": np.int64(k0), "count": np.zeros(size, np.int64), "bound": np.zeros(size)}
    for t in tallies:
        at = slice(int(t["k0"]) - k0, int(t["k0"]) - k0 + t["count"].size)
        total["count"][at] += t["count"]
        total["bound"][at] += t["bound"]
    for name in ("certified", "mismatched", "unlabelled", "running"):
        total[name] = np.int64(sum(int(t[name]) for t in tallies))
    total["running_bound"] = np.float64(sum(float(t["running_bound"]) for t in tallies))
    return total


def _unlabelled(status) -> dict:
    """The tally's counts of orbits without a well label: certified running, or neither
    (unresolved, nonfinite)."""
    status = np.asarray(status)
    running = np.count_nonzero(status == RUNNING)
    return {"running": np.int64(running),
            "unlabelled": np.int64(np.count_nonzero(~labelled(status)) - running)}


class NoBoundaries:
    """The certifier of a pendulum without rest states (|τ| > ω0²): the running limit cycle
    is its only attractor, so its basin is the whole plane, there is no basin boundary
    (``boundary_distance`` is +inf, d_cert 0) and every running label is certified for the
    exact equation; an orbit not yet in the running barrier stays unresolved. Same
    interface as :class:`Certifier`."""

    def __init__(self, pendulum: Pendulum, theta0, theta_dot0):
        self.pendulum = pendulum
        self.theta0, self.theta_dot0 = np.asarray(theta0, float), np.asarray(theta_dot0, float)
        self.n_points = self.theta0.size * self.theta_dot0.size
        self.d_cert = 0.0

    def tile(self, rows: slice, attractor, status):
        tally = {"k0": np.int64(0), "count": np.zeros(1, np.int64), "bound": np.zeros(1),
                 "running_bound": np.float64(0.0),
                 "certified": np.int64(np.count_nonzero(np.asarray(status) == RUNNING)),
                 "mismatched": np.int64(0), **_unlabelled(status)}
        return status, np.full(np.shape(status), np.inf, np.float32), tally

    def summary(self, tally: dict) -> dict:
        n = self.n_points
        running = int(tally["running"]) / n
        return {"k": np.zeros(0, np.int64), "basin_fraction_exact": np.zeros(0),
                "basin_fraction_exact_error": np.zeros(0), "basin_fraction": np.zeros(0),
                "basin_fraction_grid_error_bound": np.zeros(0),
                "basin_fraction_grid_error": np.zeros(0),
                "unresolved_fraction": int(tally["unlabelled"]) / n,
                "running_fraction": running, "running_fraction_exact": 1.0,
                "running_fraction_exact_error": 0.0,
                "running_fraction_grid_error_bound": 1.0 - running,
                "certified_fraction": int(tally["certified"]) / n,
                "d_cert": 0.0, "boundary_shift": 0.0, "boundary_reference_error": 0.0,
                "side_mismatches": 0}


def certifier_for(pendulum: Pendulum, theta0, theta_dot0, shift: float, tol: float,
                  tilted=None):
    """The certifier of one parameter point: :class:`Certifier` (exact boundaries) where the
    pendulum has rest states, :class:`NoBoundaries` where it has none (|τ| > ω0²). At the
    saddle-node |τ| = ω0² neither argument holds: ValueError (configs refuse it)."""
    if pendulum.torque == 0.0 or pendulum.has_rest_states:
        return Certifier(pendulum, theta0, theta_dot0, shift, tol, tilted)
    if abs(pendulum.torque) > pendulum.omega0**2:
        return NoBoundaries(pendulum, theta0, theta_dot0)
    raise ValueError("|torque| = omega0^2: the saddle-node, whose basin atlas does not certify")


def _edge_weights(num: int) -> np.ndarray:
    """1 for interior grid points, ½ for the two end points (their cells are half cells)."""
    w = np.ones(num)
    w[[0, -1]] = 0.5
    return w
