"""``atlas info`` of a study file (and ``atlas stability``'s summary): what a study holds, in
a few lines: its parameters, the bifurcations inside their ranges, the basin stability at
the ends of each range, the minimal fatal shock, and every point that is not exact."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.store.study import BIFURCATIONS

__all__ = ["study_lines", "study_info_lines"]


def _range(ds: xr.Dataset, name: str) -> str:
    values = np.atleast_1d(ds[name].values)
    if values.size == 1:
        return f"{name} = {values[0]:g}"
    return f"{name} from {values[0]:g} to {values[-1]:g} ({values.size} points)"


def _inside(ds: xr.Dataset, name: str, value: float) -> bool:
    values = np.atleast_1d(ds[name].values)
    return values.size > 1 and values[0] <= value <= values[-1]


#: What each bifurcation variable marks (:data:`atlas.store.study.BIFURCATIONS`).
_WHAT = {"homoclinic_torque": "the running cycle appears",
         "homoclinic_damping": "below it the running cycle exists",
         "homoclinic_omega0": "below it the running cycle exists",
         "saddle_node_torque": "the rest states vanish",
         "saddle_node_omega0": "below it there is no rest state",
         "focus_node_damping": "the rest state turns node",
         "focus_node_torque": "above it the rest state is a node",
         "focus_node_omega0": "below it the rest state is a node"}


def _bifurcation_lines(ds: xr.Dataset) -> list[str]:
    lines = []
    for var, (axis, _) in BIFURCATIONS.items():
        if var not in ds:
            continue
        values = np.atleast_1d(ds[var].values).ravel()
        shown = [v for v in values if np.isfinite(v) and _inside(ds, axis, v)]
        if not shown:
            continue
        where = f"{axis} = {shown[0]:.12g}" if len(shown) == 1 else \
            f"{len(shown)} values of {axis} in {min(shown):.6g} … {max(shown):.6g}"
        lines.append(f"bifurcation {var}: {where} ({_WHAT[var]})")
    return lines


def study_lines(ds: xr.Dataset) -> list[str]:
    """The summary of a study (module docstring); a driven pendulum's:
    :func:`atlas.views.driven_study.driven_study_lines`."""
    from atlas.store.driven_study import is_driven_study

    if is_driven_study(ds):
        from atlas.views.driven_study import driven_study_lines

        return driven_study_lines(ds)
    swept = [d for d in ("alpha", "omega0", "torque") if d in ds.dims]
    (a, b), (lo, hi) = ds.attrs["window_theta"], ds.attrs["window_theta_dot"]
    names = ("alpha", "omega0", "torque")
    lines = [f"stability study: {', '.join(_range(ds, n) for n in names)}",
             f"window    theta in [{a:.6g}, {b:.6g}] rad, theta_dot in [{lo:g}, {hi:g}] "
             f"rad/s (the region of perturbations); {ds.sizes['k']} rest states k meet it"]
    lines += _bifurcation_lines(ds)
    fp = ds["basin_stability"].sum("k", skipna=False)
    err = ds["basin_stability_error"].sum("k", skipna=False)
    if len(swept) <= 1:
        values = np.atleast_1d(fp.values)
        errors = np.atleast_1d(err.values)
        coord = np.atleast_1d(ds[swept[0]].values) if swept else [None]
        exact = np.flatnonzero(np.atleast_1d(ds["point_status"].values) == 0)
        for i in sorted({int(exact[0]), int(exact[-1])} if exact.size else ()):
            at = f"at {swept[0]} = {coord[i]:g}" if swept else "at the point"
            lines.append(f"basin stability {at}: rest states {values[i]:.10f} "
                         f"± {errors[i]:.1e}, running cycle "
                         f"{np.atleast_1d(ds['running_stability'].values)[i]:.10f} "
                         "(exact area fractions)")
    elif (ds["point_status"].values == 0).any():  # a map: its extremes, and where
        exact = np.where(ds["point_status"].transpose(*fp.dims).values == 0, fp.values, np.nan)
        for word, pick in (("lowest", np.nanargmin), ("highest", np.nanargmax)):
            index = np.unravel_index(pick(exact), fp.shape)
            where = ", ".join(f"{d} = {float(ds[d][i]):g}" for d, i in zip(fp.dims, index))
            lines.append(f"basin stability of the rest states, {word}: "
                         f"{float(fp.values[index]):.10f} ± {float(err.values[index]):.1e} "
                         f"at {where} (exact area fraction)")
    shock = ds["minimal_fatal_shock"].isel(k=0) if ds.sizes["k"] else None
    if shock is not None and np.isfinite(shock.values).any():
        v = shock.values[np.isfinite(shock.values)]
        error = np.nanmax(ds["minimal_fatal_shock_error"].values)
        lines.append(f"minimal fatal shock of the rest states: {v.min():.10g} to "
                     f"{v.max():.10g} (Euclidean "
                     f"(theta, theta_dot) distance, ± {error:.0e})")
    cycle = ds["running_fatal_shock"].values if "running_fatal_shock" in ds else None
    if cycle is not None and np.isfinite(cycle).any():
        v = cycle[np.isfinite(cycle)]
        error = np.nanmax(ds["running_fatal_shock_error"].values)
        lines.append(f"minimal fatal shock of the running cycle: {v.min():.10g} to "
                     f"{v.max():.10g} (the same distance, ± {error:.0e})")
    if "gaussian_stability" in ds:
        g = ds["gaussian_stability"].values
        lines.append(f"gaussian stability (sigma_theta = {ds.attrs['sigma_theta']:g}, "
                     f"sigma_theta_dot = {ds.attrs['sigma_theta_dot']:g}): {np.nanmin(g):.8f}"
                     f" to {np.nanmax(g):.8f}")
    if "tipping_probability" in ds:
        lines.append(f"tipping probabilities: {ds.sizes['step']} steps between consecutive "
                     "points (tipping_probability[step, source, target])")
    status = ds["point_status"]
    meanings = dict(zip(status.attrs["flag_values"].tolist(),
                        status.attrs["flag_meanings"].split()))
    for code, meaning in meanings.items():
        count = int((status.values == code).sum())
        if code and count:
            where = [f"{d} = {float(ds[d][i]):g}" for i, d in
                     zip(np.argwhere(status.values == code)[0], swept)]
            lines.append(f"{count} point(s) {meaning}, values NaN (first at "
                         f"{', '.join(where)})")
    for failure in json.loads(ds.attrs.get("failures", "[]"))[:3]:
        lines.append(f"  failed: {failure}")
    return lines


def study_info_lines(path: str | Path) -> list[str]:
    """``atlas info`` of the study file at ``path`` (checked by
    :func:`atlas.store.study.open_study`)."""
    from atlas.store.study import open_study

    ds = open_study(path)
    lines = [f"{path}: stability study (format {int(ds.attrs['format_version'])})"]
    lines += ["  " + line for line in study_lines(ds)]
    lines.append(f"  created   {ds.attrs.get('created', '?')} by atlas "
                 f"{ds.attrs.get('atlas_version', '?')}")
    return lines
