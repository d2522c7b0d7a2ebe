"""Per parameter point, what a sweep prepares before any tile: the pendulum, its running
cycle and barrier, its exact boundaries, its traced separatrices, its certifier, and the
per-point groups of the file (``/critical_points``, ``/separatrices``, ``/limit_cycle``).

Nothing here depends on the grid's resolution, only on its window; every function takes the
points in the layout's order (:mod:`atlas.layout`) and returns one entry per point (None
where the point has none: no torque, no rest state, separatrices disabled). The slow ones
take ``track(items, total, desc)``, which yields ``items`` and may show their progress
(:func:`atlas.pipeline.progress.tracked`; by default nothing is shown).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.boundaries import exact
from atlas.boundaries.certificate import certifier_for
from atlas.errors import AtlasError
from atlas.kernels.threads import concurrent_points
from atlas.layout import Layout, node_name
from atlas.physics import running
from atlas.physics.pendulum import Pendulum, critical_points
from atlas.pipeline.config import Config
from atlas.store.schema import with_barrier


def _untracked(items, total: int, desc: str):
    return items

__all__ = ["pendulums", "window", "running_certificates", "exact_boundaries",
           "trace_separatrices", "certifiers", "groups", "per_point",
           "critical_points_dataset", "limit_cycle_dataset"]


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


def per_point(layout: Layout, group: str, datasets: list[xr.Dataset | None]
               ) -> dict[str, xr.Dataset]:
    """The nodes of a per-point group: one per parameter point, each with the point's
    parameters as attributes (the group itself for an atlas of one point; see
    :mod:`atlas.layout`)."""
    out = {}
    for p, ds in enumerate(datasets):
        if ds is None:
            continue
        path = "/".join(filter(None, (group, node_name(layout, p))))
        out[path] = ds.assign_attrs(layout.point(p))
    return out


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
        out.append((certifier_for(p, layout.theta0, layout.theta_dot0, shift, tol, b),
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
    lo, hi = float(layout.theta0[0]), float(layout.theta0[-1])
    return {**per_point(layout, "critical_points",
                         [critical_points_dataset(p, lo, hi) for p in pendulums]),
            **per_point(layout, "separatrices", traced),
            **per_point(layout, "limit_cycle",
                         [None if c is None else limit_cycle_dataset(c, b)
                           for c, b in zip(cycles, barriers)])}
