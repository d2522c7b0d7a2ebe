"""``atlas orbit FILE`` of a driven pendulum's atlas: one orbit of the atlas's own RK4 map,
labelled by the atlas's own rule.

:func:`open_driven_point` opens the file and selects a parameter point; it rebuilds the point
as the run labelled it (:func:`atlas.models.driven.points.stored_point`: the drive α, ω0, τ,
A, Ω, φ, its N steps per period, the attractors' points on P, their capture radius and status
from ``/attractors``, t_max from the file). :func:`follow` labels the orbit with that point's
:meth:`~atlas.models.driven.points.DrivenPoint.label` (the lane kernel of the run, so the
label is the atlas's for that point) and again at dt/2 (:meth:`~atlas.models.driven.points.
DrivenPoint.halved`), then keeps its trajectory step by step up to the decision (or t_max)
with :func:`atlas.kernels.driven.trajectory`, whose returns to P are the kernel's, bit for
bit. :func:`atlas.commands.orbit.report` adds the text (:mod:`atlas.commands.
orbit_driven_text`); the figure is :mod:`atlas.commands.orbit_driven_figure`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from atlas.errors import AtlasError
from atlas.kernels import driven as kernels
from atlas.layout import at_point, point_group, point_label, points
from atlas.models.driven.attractors import Drive
from atlas.models.driven.description import DRIVEN_PENDULUM, NONFINITE
from atlas.models.driven.points import DrivenPoint, stored_point
from atlas.store.reader import open_atlas

__all__ = ["DrivenFilePoint", "DrivenOrbit", "open_driven_point", "follow", "nearest_stored",
           "DRIVE_OPTIONS", "MAX_KEPT"]

#: The parameters that select a point of a driven atlas, as ``atlas orbit`` options.
DRIVE_OPTIONS = tuple(DRIVEN_PENDULUM.parameters)
#: The most states of the trajectory kept (a long orbit keeps every s-th step, s dividing N).
MAX_KEPT = 400_000


@dataclass(frozen=True)
class DrivenFilePoint:
    """One parameter point of an opened driven atlas: the opened ``tree`` (the caller closes
    it) and its ``path``; ``params`` and ``index`` (the indices along the swept dims, for
    :func:`atlas.views.maps.basin_map`); ``point`` the root dataset at the point (its basin
    map); ``group`` its ``/attractors`` node; ``labeller`` the point as the run labelled it;
    ``t_max`` [s]."""

    tree: xr.DataTree
    path: Path
    params: dict
    index: dict
    point: xr.Dataset
    group: xr.Dataset
    labeller: DrivenPoint
    t_max: float


@dataclass(frozen=True)
class DrivenOrbit:
    """One orbit of the driven pendulum from (θ0 [rad], θ̇0 [rad s⁻¹]) at t = 0, on the RK4
    map of ``drive``: its trajectory ``t`` [s], ``theta`` (unwrapped) [rad], ``theta_dot``
    [rad s⁻¹] (every ``stride``-th step) up to the decision or t_max; ``returns`` (n + 1, 2):
    the start and its n returns to P (θ unwrapped, θ̇), the kernel's; and its label as the
    atlas gives it: ``attractor`` (None: no label), ``status``, ``t_trap`` [s] (NaN: none),
    ``periods`` (the returns followed), and at dt/2 ``half_attractor`` (None: no label) and
    ``half_status``."""

    theta0: float
    theta_dot0: float
    drive: Drive
    t_max: float
    attractor: int | None
    status: int
    t_trap: float
    periods: int
    half_attractor: int | None
    half_status: int
    stride: int
    t: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    theta_dot: np.ndarray = field(repr=False)
    returns: np.ndarray = field(repr=False)

    @property
    def changes_at_half_dt(self) -> bool:
        """Whether the label at dt/2 differs (another attractor, or none), as the file's
        ``changes_at_half_dt`` says of its grid points."""
        return self.half_attractor != self.attractor


def _select(ds: xr.Dataset, path: Path, asked: dict) -> tuple[dict, dict]:
    """The parameter point asked for (the only one when none is asked) and its indices along
    the swept dims; AtlasError naming the points where none or several fit."""
    every = points(ds)
    swept = [name for name in DRIVE_OPTIONS if name in ds.dims]
    shown = swept or [name for name in DRIVE_OPTIONS if asked.get(name) is not None]
    listed = "; ".join(point_label({n: p.get(n, 0.0) for n in shown}) for p in every[:12]) + (
        "; …" if len(every) > 12 else "")
    if all(value is None for value in asked.values()):
        if len(every) > 1:
            options = ", ".join(f"--{name}" for name in swept)
            raise AtlasError(f"{path}: a parameter atlas of {len(every)} points; choose one "
                             f"with {options} ({listed})")
        fits = every
    else:
        fits = [p for p in every
                if all(value is None or math.isclose(p.get(name, 0.0), value, rel_tol=1e-9,
                                                     abs_tol=1e-300)
                       for name, value in asked.items())]
        if len(fits) != 1:
            wanted = ", ".join(f"{name} = {value:g}" for name, value in asked.items()
                               if value is not None)
            raise AtlasError(f"{path}: no single parameter point with {wanted} (its points: "
                             f"{listed})")
    chosen = fits[0]
    index = {name: int(np.flatnonzero(ds[name].values == chosen[name])[0]) for name in swept}
    return chosen, index


def open_driven_point(file: str | Path, dt: float | None = None, t_max: float | None = None,
                      **asked: float | None) -> DrivenFilePoint:
    """The parameter point of the driven atlas ``file`` selected by ``asked`` (any of
    :data:`DRIVE_OPTIONS`; the only point when none is given), rebuilt as its run labelled
    it. ``dt``, ``t_max``: refused (AtlasError) unless they are the file's (dt: the RK4 step
    T/N of the point, or the config's dt it was derived from)."""
    unknown = set(asked) - set(DRIVE_OPTIONS)
    if unknown:
        raise AtlasError(f"not a parameter of the driven pendulum: {', '.join(sorted(unknown))}")
    path = Path(file)
    tree = open_atlas(path)
    try:
        ds = tree.to_dataset(inherit=False)
        params, index = _select(ds, path, asked)
        group = point_group(tree, "attractors", params)
        if group is None:
            raise AtlasError(f"{path}: no /attractors for {point_label(params)}: the file "
                             "is not a complete driven atlas")
        stored_t_max = float(ds.attrs["t_max"])
        labeller = stored_point(group, params, stored_t_max)
        drive = labeller.drive
        for name, given, stored in (("dt", dt, (drive.dt, float(ds.attrs["dt"]))),
                                    ("t_max", t_max, (stored_t_max,))):
            if given is not None and not any(math.isclose(given, s, rel_tol=1e-12)
                                             for s in stored):
                raise AtlasError(f"--{name.replace('_', '-')} {given:g}: {path} was computed "
                                 f"with {name} = {stored[0]:g}; drop the option")
        return DrivenFilePoint(tree=tree, path=path, params=params, index=index,
                               point=at_point(ds, params), group=group,
                               labeller=labeller,
                               t_max=stored_t_max)
    except BaseException:
        tree.close()
        raise


def _stride(steps: int, periods: int) -> int:
    """The least divisor s of ``steps`` (N) that keeps periods·N/s + 1 within MAX_KEPT."""
    for s in range(1, steps + 1):
        if steps % s == 0 and periods * (steps // s) < MAX_KEPT:
            return s
    return steps


def _label(labeller: DrivenPoint, theta0: float, theta_dot0: float):
    attractor, status, t_trap, _ = labeller.label(np.array([theta0]), np.array([theta_dot0]))
    k = int(attractor[0])
    return (k if int(status[0]) in DRIVEN_PENDULUM.labelled else None, int(status[0]),
            float(t_trap[0]))


def follow(labeller: DrivenPoint, theta0: float, theta_dot0: float,
           t_max: float) -> DrivenOrbit:
    """The orbit from (θ0, θ̇0), labelled by ``labeller`` (the atlas's rule: its label is
    the run's for that point) and again at dt/2, and kept step by step up to the period of
    its decision (all ``t_max`` [s] where none)."""
    if not (math.isfinite(theta0) and math.isfinite(theta_dot0)):
        raise AtlasError("theta0 and theta_dot0 must be finite numbers")
    attractor, status, t_trap = _label(labeller, theta0, theta_dot0)
    half_attractor, half_status, _ = _label(labeller.halved(), theta0, theta_dot0)
    drive = labeller.drive
    periods = (int(round(t_trap / drive.period)) if math.isfinite(t_trap)
               else labeller.max_periods)
    stride = _stride(drive.steps_per_period, periods)
    path = kernels.trajectory(theta0, theta_dot0, drive.alpha, drive.omega0, drive.torque,
                              drive.table, drive.dt, periods, stride)
    if status == NONFINITE:  # keep the orbit up to the first state that is not finite
        bad = np.flatnonzero(~np.isfinite(path).all(axis=1))
        path = path[:bad[0] + 1] if bad.size else path
    per = drive.steps_per_period // stride
    return DrivenOrbit(theta0=theta0, theta_dot0=theta_dot0, drive=drive, t_max=t_max,
                       attractor=attractor, status=status, t_trap=t_trap, periods=periods,
                       half_attractor=half_attractor, half_status=half_status, stride=stride,
                       t=np.arange(path.shape[0]) * (stride * drive.dt), theta=path[:, 0],
                       theta_dot=path[:, 1], returns=path[::per])


def nearest_stored(point: xr.Dataset, theta0: float, theta_dot0: float) -> dict:
    """The file's labels at the grid point nearest (θ0, θ̇0): its θ0, θ̇0, ``attractor``
    (None where no label), ``status``, ``t_trap`` [s], ``changes_at_half_dt``, and whether
    (θ0, θ̇0) lies ``inside`` the grid's window."""
    th, v = point["theta0"].values, point["theta_dot0"].values
    i, j = int(np.abs(th - theta0).argmin()), int(np.abs(v - theta_dot0).argmin())
    status = int(point["status"].values[j, i])
    return {"theta0": float(th[i]), "theta_dot0": float(v[j]), "status": status,
            "attractor": (int(point["attractor"].values[j, i])
                          if status in DRIVEN_PENDULUM.labelled else None),
            "t_trap": float(point["t_trap"].values[j, i]),
            "changes_at_half_dt": int(point["changes_at_half_dt"].values[j, i]),
            "inside": bool(th[0] <= theta0 <= th[-1] and v[0] <= theta_dot0 <= v[-1])}
