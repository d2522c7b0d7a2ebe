"""Labels certified for the exact equation, and the honest error of grid-counted fractions.

A label of the RK4 map (certified by the energy trap, :mod:`atlas.labels.labelling`, or the
running barrier) is certified for the exact equation when it names the basin on whose side of
the exact boundaries (:mod:`atlas.boundaries.exact`) the point lies and the point is farther
than d_cert = SAFETY · (shift + tol + reference_error) from every boundary, ``shift`` being
the RK4 map's measured boundary shift (the trace's ``discrepancy``,
:func:`atlas.boundaries.trace.trace`); other labels become ``near_boundary`` or
``running_near_boundary``. Per tile, :class:`Certifier` also tallies the grid count of every
basin and a bound on its difference from the exact area fraction, of first order in the cell
size. Without rest states (|τ| > ω0²) there is no boundary (:class:`NoBoundaries`).
Derivation (why SAFETY = 10, the cell bound): docs/design/certificate.md.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.boundaries.exact import (
    RUNNING_SIDE,
    ExactBoundaries,
    exact_boundaries,
)
from atlas.physics.pendulum import Pendulum
from atlas.status import NEAR_BOUNDARY, RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED

__all__ = ["SAFETY", "cert_distance", "Certifier", "NoBoundaries", "certifier_for",
           "labelled", "add_tallies"]

#: Safety factor of d_cert over the measured RK4-vs-exact boundary shift
#: (docs/design/certificate.md).
SAFETY = 10.0


def cert_distance(shift: float, tol: float, reference_error: float) -> float:
    """d_cert [rad-ish]: the distance from the exact boundaries beyond which RK4 labels are
    labels of the exact equation (docs/design/certificate.md). NaN when ``shift`` was not
    measured."""
    return SAFETY * (shift + tol + reference_error)


def labelled(status):
    """Where an orbit has a well label: certified for the ODE (trapped) or for the RK4 map
    only (near_boundary)."""
    status = np.asarray(status)
    return (status == TRAPPED) | (status == NEAR_BOUNDARY)


class Certifier:
    """Boundary distances, certificates and grid-error tallies of one parameter point's
    basin map, tile by tile: grid axes ``theta0`` [rad] (columns) and ``theta_dot0``
    [rad s⁻¹] (rows), the window being their ranges; ``shift`` [rad-ish], the measured
    distance of the RK4 map's boundaries from the exact ones, located to ``tol`` (NaN when
    not measured: then no label is certified for the exact equation). With torque the
    running basin is one more basin: a running label is certified for the exact equation
    (status ``running``) on the same terms as a well's, else it becomes
    ``running_near_boundary``. ``exact``: the window's exact boundaries
    (:func:`atlas.boundaries.exact.exact_boundaries`) if the caller built them.

    A certifier is sent to where tiles are computed (a Dask worker): it pickles without its
    boundary indices, which are rebuilt on first use."""

    def __init__(self, pendulum: Pendulum, theta0, theta_dot0, shift: float, tol: float,
                 exact: ExactBoundaries | None = None):
        self.pendulum = pendulum
        self.theta0, self.theta_dot0 = np.asarray(theta0, float), np.asarray(theta_dot0, float)
        self.window = ((self.theta0[0], self.theta0[-1]), (self.theta_dot0[0],
                                                           self.theta_dot0[-1]))
        self.exact = exact_boundaries(pendulum, self.window) if exact is None else exact
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
        # (a grid's row and column as given: the untilted sides are found a column at a time)
        side, dist, n_near = (np.broadcast_to(a, full) for a in
                              self.exact.side_and_distance(theta, theta_dot))
        status = np.asarray(status)
        has_label, running = labelled(status), status == RUNNING
        agree = (has_label | running) & (_basin(attractor, status) == side)
        # d_cert NaN (no boundary shift measured: separatrices disabled or none traced)
        # certifies nothing: every label stays near_boundary, as IN_FILE says
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
        point's certificate figures (the variables of
        :data:`atlas.store.schema.BASIN_VARIABLES` and :data:`atlas.store.schema.POINT_VARIABLES`
        but ``trap_margin``; and not
        :data:`atlas.store.schema.CERTIFICATE_POINT_VARIABLES`)."""
        k0 = int(tally["k0"])
        grid_k = np.arange(k0, k0 + tally["count"].size)
        a = self.exact.areas
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

    def certify(self, theta, theta_dot, attractor, status):
        """As :meth:`Certifier.certify`: every label keeps its status (a running label is
        certified, nothing else can be), the distance is +inf, the exact side the running
        basin, and there is no nearest saddle (−1)."""
        full = np.broadcast_shapes(np.shape(theta), np.shape(theta_dot), np.shape(status))
        return (np.broadcast_to(np.asarray(status), full).copy(), np.full(full, np.inf),
                np.full(full, RUNNING_SIDE, np.int64), np.full(full, -1, np.int64))

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
                  exact: ExactBoundaries | None = None):
    """The certifier of one parameter point over the grid axes ``theta0``, ``theta_dot0``:
    :class:`Certifier` on its exact boundaries (``exact``, built here if None), or
    :class:`NoBoundaries` where there are none (|τ| > ω0²). At the saddle-node |τ| = ω0²
    neither argument holds: ValueError (configs refuse it)."""
    if exact is None:
        exact = exact_boundaries(pendulum, ((theta0[0], theta0[-1]),
                                            (theta_dot0[0], theta_dot0[-1])))
    if not exact.has_boundary:
        return NoBoundaries(pendulum, theta0, theta_dot0)
    return Certifier(pendulum, theta0, theta_dot0, shift, tol, exact)


def _edge_weights(num: int) -> np.ndarray:
    """1 for interior grid points, ½ for the two end points (their cells are half cells)."""
    w = np.ones(num)
    w[[0, -1]] = 0.5
    return w
