"""``atlas orbit FILE``: the parameter point of an atlas file and the certificate its run used.

:func:`open_point` opens the file (format 4 only: a file of format 3 does not store the
certificate, and is refused with one line saying how to recompute it), selects the parameter
point asked for, and reads what the run gave its kernels: dt, t_max, check_every, the method,
the trap's energy cap and margin, and the running barrier (:func:`atlas.store.reader.
stored_certificate`), nothing rebuilt; with the stored limit cycle (for the pictures), the
RK4 map's boundary shift and the separatrix tolerance (for d_cert), and the stored labels of
the grid point nearest an initial condition (:func:`nearest_grid_point`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import AtlasError, InputFileError
from atlas.layout import at_point, point_group, points
from atlas.models.registry import DEFAULT, of_attrs
from atlas.physics.barrier import RunningBarrier
from atlas.physics.running import LimitCycle
from atlas.status import NEAR_BOUNDARY, TRAPPED
from atlas.store.reader import open_atlas, require_certificate, stored_certificate
from atlas.store.validate import file_method

__all__ = ["FilePoint", "open_point", "nearest_grid_point", "cycle_from_group"]


@dataclass(frozen=True)
class FilePoint:
    """One parameter point of an opened atlas file and the certificate its labels used.

    tree, path:     the opened file (the caller closes ``tree``) and where it is.
    params, index:  the point's parameters {alpha, omega0, torque} and its indices along the
                    swept dims (for :func:`atlas.views.maps.basin_map`).
    point:          the root dataset at the point (the basin map and its summary).
    dt, t_max:      the RK4 step and the integration limit [s]; ``check_every`` the steps
                    between two certificate tests; ``method`` the discretisation.
    cap, margin:    the trap's energy cap [rad² s⁻²] (−inf: no well traps) and margin m.
    barrier:        the running barrier (None where the point has none); ``cycle`` the
                    running limit cycle (:class:`atlas.physics.running.LimitCycle`) or None.
    shift, tol:     the RK4 map's boundary shift and the separatrix tolerance (NaN: not
                    stored), from which d_cert follows.
    """

    tree: xr.DataTree
    path: Path
    params: dict
    index: dict
    point: xr.Dataset
    dt: float
    t_max: float
    check_every: int
    method: str
    cap: float
    margin: float
    barrier: RunningBarrier | None
    cycle: LimitCycle | None
    shift: float
    tol: float


def open_point(file: str | Path, alpha: float | None = None, omega0: float | None = None,
               torque: float | None = None, dt: float | None = None,
               t_max: float | None = None) -> FilePoint:
    """The parameter point (α, ω0, τ) of the atlas ``file`` (the only one when none is
    given) with the certificate stored for it. ``dt``, ``t_max``: refused (AtlasError) unless
    they are the file's. A file of format 3, or an atlas of another model than the pendulum
    (whose orbits these commands integrate), is refused with one InputFileError line."""
    path = Path(file)
    tree = open_atlas(path)
    try:
        model = of_attrs(tree.attrs)
        if model.name != DEFAULT:
            raise InputFileError(f"{path}: an atlas of the {model.title} (model "
                                 f"{model.name}); atlas orbit and atlas zoom integrate the "
                                 "pendulum's orbits, so they read the pendulum's atlases only")
        require_certificate(tree, path)
        ds = tree.to_dataset(inherit=False)
        params, index = _select(ds, path, alpha, omega0, torque)
        point = at_point(ds, params)
        for name, given in (("dt", dt), ("t_max", t_max)):
            stored = float(ds.attrs[name])
            if given is not None and not math.isclose(given, stored, rel_tol=1e-12):
                raise AtlasError(f"--{name.replace('_', '-')} {given:g}: {path} was computed "
                                 f"with {name} = {stored:g}; drop the option")
        certificate = stored_certificate(tree, params)
        stored = certificate.barrier
        cycle = point_group(tree, "limit_cycle", params)
        sep = point_group(tree, "separatrices", params)
        return FilePoint(
            tree=tree, path=path, params=params, index=index, point=point,
            dt=float(ds.attrs["dt"]), t_max=float(ds.attrs["t_max"]),
            check_every=int(ds.attrs["check_every"]), method=file_method(ds.attrs, path),
            cap=certificate.trap_energy_cap, margin=float(point["trap_margin"]),
            barrier=None if stored is None else RunningBarrier(
                theta0=stored.theta0, g=stored.g, top=stored.top, direction=stored.direction),
            cycle=None if cycle is None else cycle_from_group(cycle),
            shift=float(point["boundary_shift"]) if "boundary_shift" in point else math.nan,
            tol=math.nan if sep is None else float(sep.attrs.get("tol", math.nan)))
    except BaseException:
        tree.close()
        raise


def _listed(every: list[dict]) -> str:
    with_torque = any(p.get("torque", 0.0) for p in every)
    names = ("alpha", "omega0", "torque") if with_torque else ("alpha", "omega0")
    text = ", ".join("(" + ", ".join(f"{p.get(n, 0.0):g}" for n in names) + ")"
                     for p in every[:12]) + (", …" if len(every) > 12 else "")
    return f"{', '.join(names)} = {text}"


def _select(ds: xr.Dataset, path: Path, alpha: float | None, omega0: float | None,
            torque: float | None) -> tuple[dict, dict]:
    """The parameter point (α, ω0, τ) asked for (the only one when not asked) and its
    indices along the swept dims; AtlasError naming the points where none or several fit."""
    every = points(ds)
    listed = _listed(every)
    asked = {"alpha": alpha, "omega0": omega0, "torque": torque}
    if all(value is None for value in asked.values()):
        if len(every) > 1:
            options = ("--alpha, --omega0 and --torque" if "torque" in ds.dims
                       else "--alpha and --omega0")
            raise AtlasError(f"{path}: a parameter atlas of {len(every)} points; choose one "
                             f"with {options} ({listed})")
        fits = every
    else:
        fits = [p for p in every
                if all(value is None
                       or math.isclose(p.get(name, 0.0), value, rel_tol=1e-9, abs_tol=1e-300)
                       for name, value in asked.items())]
        if len(fits) != 1:
            wanted = "".join(f" {name} = {value:g}" for name, value in asked.items()
                             if value is not None)
            raise AtlasError(f"{path}: no single parameter point with{wanted} ({listed})")
    chosen = fits[0]
    index = {name: int(np.flatnonzero(ds[name].values == chosen[name])[0])
             for name in chosen if name in ds.dims}
    return chosen, index


def nearest_grid_point(point: xr.Dataset, theta0: float, theta_dot0: float) -> dict:
    """The stored labels of the grid point nearest (θ0, θ̇0): its θ0, θ̇0, status, k (None
    unless trapped), t_trap, boundary distance (NaN where not stored), and whether (θ0, θ̇0)
    lies inside the grid's window."""
    th, v = point["theta0"].values, point["theta_dot0"].values
    i, j = int(np.abs(th - theta0).argmin()), int(np.abs(v - theta_dot0).argmin())
    status = int(point["status"].values[j, i])
    out = {"theta0": float(th[i]), "theta_dot0": float(v[j]), "status": status,
           "k": (int(point["attractor"].values[j, i]) if status in (TRAPPED, NEAR_BOUNDARY)
                 else None),
           "t_trap": float(point["t_trap"].values[j, i]),
           "distance": (float(point["boundary_distance"].values[j, i])
                        if "boundary_distance" in point else math.nan)}
    out["inside"] = bool(th[0] <= theta0 <= th[-1] and v[0] <= theta_dot0 <= v[-1])
    return out


def cycle_from_group(ds: xr.Dataset) -> LimitCycle:
    """The :class:`atlas.physics.running.LimitCycle` stored in a parameter point's
    ``/limit_cycle`` node (the arrays and attributes the sweep wrote)."""
    theta = np.asarray(ds["theta"].values, np.float64)
    return LimitCycle(theta0=float(theta[0]), theta=theta,
                      theta_dot=np.asarray(ds["theta_dot"].values, np.float64),
                      time=np.asarray(ds["time"].values, np.float64),
                      period=float(ds.attrs["period"]), direction=int(ds.attrs["direction"]),
                      error=float(ds.attrs.get("relative_error", math.nan)))
