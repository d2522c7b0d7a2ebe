"""The pendulum's parameter points, prepared (what its planner,
:mod:`atlas.models.pendulum.plan`, hands the sweep): per point the pendulum, its running
cycle and barrier, its exact boundaries, its traced separatrices, its certifier, and the
per-point groups of the file (``/critical_points``, ``/separatrices``, ``/limit_cycle``),
gathered into one picklable :class:`PendulumPoint` per point that labels a tile
(:func:`atlas.label`, the RK4 map and its energy trap) and certifies it for the exact
equation (:mod:`atlas.boundaries.certificate`).

Nothing here depends on the grid's resolution, only on its window; every function takes the
points in the layout's order (:mod:`atlas.layout`) and returns one entry per point (None
where the point has none: no torque, no rest state, separatrices disabled). The slow ones
take ``track(items, total, desc)``, which yields ``items`` and may show their progress
(:func:`atlas.pipeline.progress.tracked`; by default nothing is shown).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.boundaries import exact
from atlas.boundaries.certificate import Certifier, add_tallies, certifier_for
from atlas.errors import AtlasError
from atlas.kernels.threads import concurrent_points, use_threads
from atlas.labels.trap import energy_cap, trap_margin
from atlas.layout import Layout, per_point, point_label
from atlas.physics import running
from atlas.physics.barrier import RunningBarrier
from atlas.physics.pendulum import Pendulum, critical_points
from atlas.pipeline.config import Config
from atlas.store.schema import summary_dataset, with_barrier
from atlas.store.separatrices import inexact_line

log = logging.getLogger(__name__)


__all__ = ["begin", "plan", "PendulumLabeller", "PendulumPoint", "PendulumPlan", "pendulums",
           "window", "running_certificates", "exact_boundaries", "trace_separatrices",
           "certifiers", "groups", "critical_points_dataset",
           "limit_cycle_dataset"]


def _untracked(items, total: int, desc: str):
    """The default ``track``: the items, no progress shown."""
    return items


def pendulums(layout: Layout) -> list[Pendulum]:
    """The pendulum of every parameter point, in the layout's order."""
    return [Pendulum(**layout.point(p)) for p in range(layout.n_params)]


def critical_points_dataset(p: Pendulum, lo: float, hi: float) -> xr.Dataset:
    """One parameter point's node of ``/critical_points``: θ, n, kind and both eigenvalues
    of every critical point with θ in [``lo``, ``hi``] [rad]."""
    found = critical_points(p, lo, hi)
    eig = np.array([c.eigenvalues for c in found], np.complex128).reshape(len(found), 2)
    dims = ("point", "eigen")
    return xr.Dataset(
        {
            "eigenvalue_real": (dims, eig.real, {"units": "s-1",
                                                 "long_name": "real part of the eigenvalue"}),
            "eigenvalue_imag": (dims, eig.imag, {"units": "s-1",
                                                 "long_name": "imaginary part of the eigenvalue"}),
            "kind": ("point", np.array([c.kind for c in found], dtype=str),
                     {"long_name": "attractor focus/node/critical node, or saddle"}),
        },
        coords={
            "theta": ("point", np.array([c.theta for c in found], np.float64),
                      {"units": "rad", "long_name": "angle of the critical point (theta, 0)"}),
            "n": ("point", np.array([c.n for c in found], np.int32),
                  {"units": "1", "long_name": "index n: the critical point near n*pi (even: "
                                              "rest state, odd: saddle)"}),
        },
        attrs={"description": "critical points of the pendulum in the theta0 window and "
                              "their linearisation eigenvalues (essay section 3, eqs. 22-24)"},
    )


def window(cfg: Config) -> tuple[tuple[float, float], tuple[float, float]]:
    """The grid's window: (θ0 first, last) [rad], (θ̇0 first, last) [rad s⁻¹]."""
    g = cfg.grid
    return (g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop)


def exact_boundaries(cfg: Config, pendulums: list[Pendulum], cycles: list,
                     track=_untracked) -> list:
    """The exact basin boundaries of every parameter point over the window
    (:func:`atlas.boundaries.exact.exact_boundaries`, given its running limit cycle), built
    once for both the separatrices and the certifier."""
    from atlas.pipeline.schedule import each_in_background

    def one(point):  # independent points, two at a time (compiled DOP853, polygons: nogil)
        p, cycle = point
        return exact.exact_boundaries(p, window(cfg), cycle=cycle)

    return list(track(each_in_background(one, zip(pendulums, cycles),
                                         concurrent_points(len(pendulums))),
                      len(pendulums), "exact boundaries"))


def trace_separatrices(cfg: Config, pendulums: list[Pendulum], boundaries: list,
                        barriers: list, track=_untracked) -> list[xr.Dataset | None]:
    """The traced separatrices of every parameter point (:func:`atlas.boundaries.trace.trace`
    on its exact boundaries and running barrier; None where it has no boundary, and each
    when disabled)."""
    if not cfg.separatrices.enabled:
        return [None] * len(pendulums)
    from atlas.boundaries.trace import trace

    settings = {"tol": cfg.separatrices.tol, "max_spacing": cfg.separatrices.max_spacing,
                "dt": cfg.integrator.dt, "t_max": cfg.integrator.t_max,
                "method": cfg.integrator.method}
    from atlas.pipeline.schedule import each_in_background

    def one(point):  # the points are independent: two at a time overlap their serial parts
        p, b, barrier = point
        return trace(p, *window(cfg), exact=b, barrier=barrier, **settings)

    return list(track(each_in_background(one, zip(pendulums, boundaries, barriers),
                                         concurrent_points(len(pendulums))),
                      len(pendulums), "separatrices"))


def certifiers(layout: Layout, pendulums: list[Pendulum], traced: list, boundaries: list,
                barriers: list, track=_untracked) -> list[tuple]:
    """(certifier, running barrier) of every parameter point: the certifier with the boundary
    shift its separatrices measured (NaN without them: then no label is certified for the
    exact equation; :func:`atlas.boundaries.certificate.certifier_for`), on the exact
    boundaries of :func:`exact_boundaries`, and the barrier of :func:`running_certificates`."""
    out = []
    for p, sep, b, barrier in track(zip(pendulums, traced, boundaries, barriers),
                                    len(pendulums), "certificates"):
        shift, tol = ((float(sep.attrs["discrepancy"]), float(sep.attrs["tol"]))
                      if sep is not None else (np.nan, np.nan))
        out.append((certifier_for(p, layout.x0, layout.v0, shift, tol, b),
                    barrier))
    return out


def running_certificates(pendulums: list[Pendulum], dt: float) -> tuple[list, list]:
    """The running limit cycle of every parameter point and the barrier around it, with the
    margins RK4 at step ``dt`` needs (None each where there is no cycle). Built before
    anything is written: a dt too coarse for the running speeds is bad input (AtlasError,
    one line naming integrator.dt)."""
    cycles, barriers = [], []
    for p in pendulums:
        try:
            cycle, barrier = running.running_certificate(p, dt)
        except ValueError as exc:
            raise AtlasError(f"integrator.dt: {exc} (torque = {p.torque:g})") from None
        cycles.append(cycle)
        barriers.append(barrier)
    return cycles, barriers


def limit_cycle_dataset(cycle, barrier) -> xr.Dataset:
    """One parameter point's node of ``/limit_cycle``: the running periodic orbit sampled
    uniformly in θ over one turn, with its period and mean angular velocity, and (format 4,
    :func:`atlas.store.schema.with_barrier`) the running barrier its labels were certified
    with, so that views read that certificate instead of rebuilding it."""
    return with_barrier(xr.Dataset(
        {"theta_dot": ("sample", cycle.theta_dot, {"units": "rad s-1",
                                                   "long_name": "angular velocity"}),
         "time": ("sample", cycle.time, {"units": "s", "long_name": "time from the first "
                                                                    "sample"})},
        coords={"theta": ("sample", cycle.theta, {"units": "rad", "long_name": "angle"})},
        attrs={"description": "the running limit cycle (steady rotation) of the pendulum with "
                              "torque: fixed point of the Poincare map over one turn (DOP853)",
               "period": cycle.period, "period_units": "s",
               "mean_theta_dot": cycle.mean_theta_dot, "direction": np.int8(cycle.direction),
               "relative_error": cycle.error}), barrier)


def groups(layout: Layout, pendulums: list[Pendulum], traced: list, cycles: list,
           barriers: list) -> dict[str, xr.Dataset]:
    """The per-point groups (path → dataset): ``/critical_points``, ``/separatrices`` and
    ``/limit_cycle`` (points with a running cycle only)."""
    lo, hi = float(layout.x0[0]), float(layout.x0[-1])
    return {**per_point(layout, "critical_points",
                         [critical_points_dataset(p, lo, hi) for p in pendulums]),
            **per_point(layout, "separatrices", traced),
            **per_point(layout, "limit_cycle",
                         [None if c is None else limit_cycle_dataset(c, b)
                           for c, b in zip(cycles, barriers)])}


# ----------------------------------------------------------------- the planner's contract

@dataclass(frozen=True)
class PendulumLabeller:
    """One parameter point's RK4 map (:func:`atlas.label`): the pendulum, its running
    barrier (None where it has no running cycle), the step ``dt`` [s], ``t_max`` [s] and the
    discretisation ``method``; and the running ``cycle`` (kept for the point's groups)."""

    pendulum: Pendulum
    barrier: RunningBarrier | None
    dt: float
    t_max: float
    method: str
    #: The running limit cycle the barrier surrounds (None where there is none).
    cycle: object = None

    def label(self, x0, v0, rows=None, backend: str = "cpu", numba_threads=None,
              t_max: float | None = None):
        """The labels of the orbits from θ0 = ``x0`` [rad], θ̇0 = ``v0`` [rad s⁻¹] (arrays
        that broadcast), by :func:`atlas.label` with ``numba_threads`` threads where given
        (``t_max`` overrides the point's; ``rows`` is not needed)."""
        from atlas.labels.labelling import label  # looked up at each call: tests replace it

        use_threads(numba_threads)
        p = self.pendulum
        return label(x0, v0, alpha=p.alpha, omega0=p.omega0, torque=p.torque, dt=self.dt,
                     t_max=self.t_max if t_max is None else t_max, backend=backend,
                     method=self.method, running=self.barrier)


@dataclass(frozen=True)
class PendulumPoint(PendulumLabeller):
    """One parameter point, prepared (:class:`atlas.models.base.PointPlan`): its RK4 map and
    the certifier of its labels for the exact equation."""

    certifier: Certifier | None = None

    def certify(self, rows: slice, res, numba_threads=None) -> tuple[dict, dict]:
        """The labels ``res`` of :meth:`label` for the grid rows ``rows`` certified for the
        exact equation (status, boundary distance), as the tile's arrays and tally."""
        use_threads(numba_threads)
        status, distance, tally = self.certifier.tile(rows, res.attractor, res.status)
        return {"attractor": res.attractor, "status": status, "t_trap": res.t_trap,
                "boundary_distance": distance}, tally


@dataclass
class PendulumPlan:
    """Every parameter point of a pendulum config, prepared (:class:`atlas.models.base.Plan`):
    ``points`` (:class:`PendulumPoint`), the per-point ``groups``, and the ``warnings`` of
    separatrices whose check exceeds its bound (one line each)."""

    layout: Layout
    points: list[PendulumPoint]
    groups: dict[str, xr.Dataset]
    warnings: list[str]

    def summary(self, tallies: list[list[dict]]) -> xr.Dataset:
        """The summary variables of every point from its tiles' tallies (O(tiles) numbers,
        no label re-read): the certifier's exact areas, grid counts and bounds, the trap's
        margin and energy cap."""
        out = []
        for p, (point, tally) in enumerate(zip(self.points, tallies)):
            summary = point.certifier.summary(add_tallies(tally))
            pend = point.pendulum
            summary["trap_margin"] = trap_margin(point.dt, pend.alpha, pend.omega0)
            summary["trap_energy_cap"] = energy_cap(point.dt, pend.alpha, pend.omega0,
                                                    pend.torque)
            if summary["side_mismatches"]:
                log.warning("%s: %d labels farther than d_cert from every boundary disagree "
                            "with the exact side; they are flagged near_boundary",
                            point_label(self.layout.point(p)), summary["side_mismatches"])
            out.append(summary)
        return summary_dataset(self.layout, out)


def begin(cfg: Config, layout: Layout) -> list[PendulumLabeller]:
    """Before anything is written: every point's pendulum and running certificate, with the
    margins RK4 at ``integrator.dt`` needs (:func:`running_certificates`: a dt too coarse
    for the running speeds is bad input, AtlasError naming integrator.dt)."""
    pends = pendulums(layout)
    cycles, barriers = running_certificates(pends, cfg.integrator.dt)
    integrator = cfg.integrator
    return [PendulumLabeller(p, b, integrator.dt, integrator.t_max, integrator.method, c)
            for p, b, c in zip(pends, barriers, cycles)]


def plan(cfg: Config, layout: Layout, begun: list[PendulumLabeller], track=_untracked
         ) -> PendulumPlan:
    """Every point prepared: its exact boundaries, its traced separatrices (they measure
    d_cert, which certifying a tile needs), its certifier and its groups."""
    pends = [b.pendulum for b in begun]
    cycles, barriers = [b.cycle for b in begun], [b.barrier for b in begun]
    boundaries = exact_boundaries(cfg, pends, cycles, track)
    traced = trace_separatrices(cfg, pends, boundaries, barriers, track)
    certs = certifiers(layout, pends, traced, boundaries, barriers, track)
    warnings = [line for p, sep in enumerate(traced) if sep is not None
                for line in [inexact_line(point_label(layout.point(p)), sep)] if line]
    points = [PendulumPoint(b.pendulum, b.barrier, b.dt, b.t_max, b.method,  # no cycle: a
                            certifier=cert) for b, (cert, _) in zip(begun, certs)]  # tile
    # never needs it, and each point travels to a Dask worker with its tiles
    return PendulumPlan(layout, points, groups(layout, pends, traced, cycles, barriers),
                        warnings)
