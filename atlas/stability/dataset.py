"""A stability study as an xarray Dataset: the points' numbers (:class:`PointResult`) and
the bifurcations of the parameter ranges, laid out as the study file's schema
(:mod:`atlas.store.study`) says.

The bifurcations are computed here, once per line of the study: the homoclinic torque per
(α, ω0), the saddle-node torque per ω0, the focus–node damping per (ω0, τ); in a study over
α at fixed τ, the homoclinic damping inside the α range; in a study over τ, the focus–node
torque per (α, ω0); in a study over ω0, the saddle-node and focus–node frequencies and, at
fixed τ, the homoclinic frequency inside the ω0 range (:mod:`atlas.stability.bifurcations`;
which parameter each is a value of: :data:`atlas.store.study.BIFURCATIONS`).
"""

from __future__ import annotations

import json
from datetime import datetime, timezone

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.models.pendulum.description import PARAMETERS
from atlas.stability import bifurcations as bif
from atlas.stability.study import POINT_STATUS, PointResult, StudySettings
from atlas.store.study import (
    RUNNING_BASIN,
    STUDY_FORMAT,
    STUDY_SCHEMA,
    STUDY_VARIABLES,
    variable_attrs,
)

__all__ = ["study_dataset", "bifurcation_values"]


def bifurcation_values(alphas, omega0s, torques, swept) -> dict:
    """{name: array over the parameters of its schema dims (full lists, in their order)} of
    every bifurcation the schema stores for a study over ``swept`` (module docstring)."""
    out = {"homoclinic_torque": np.array([[bif.homoclinic_torque(a, w) for w in omega0s]
                                          for a in alphas]),
           "saddle_node_torque": np.array([bif.saddle_node_torque(w) for w in omega0s]),
           "focus_node_damping": np.array([[bif.focus_node_damping(w, t) for t in torques]
                                           for w in omega0s])}
    if "alpha" in swept and "torque" not in swept:  # over torque: homoclinic_torque's curve
        lo, hi = min(alphas), max(alphas)
        out["homoclinic_damping"] = np.array(
            [[_nan(bif.homoclinic_damping(t, w, lo, hi)) for t in torques] for w in omega0s])
    if "torque" in swept:
        out["focus_node_torque"] = np.array([[bif.focus_node_torque(a, w) for w in omega0s]
                                             for a in alphas])
    if "omega0" in swept:
        out["saddle_node_omega0"] = np.array([bif.saddle_node_omega0(t) for t in torques])
        out["focus_node_omega0"] = np.array([[bif.focus_node_omega0(a, t) for t in torques]
                                             for a in alphas])
        if "torque" not in swept:
            lo, hi = min(omega0s), max(omega0s)
            out["homoclinic_omega0"] = np.array(
                [[_nan(bif.homoclinic_omega0(a, t, lo, hi)) for t in torques]
                 for a in alphas])
    return out


def _nan(value):
    return np.nan if value is None else value


#: The running cycle's fatal shock: variable → field of
#: :class:`atlas.stability.shocks.RunningShock`.
_RUNNING_SHOCK = {"running_fatal_shock": "distance", "running_fatal_shock_error": "error",
                  "running_shock_theta": "theta", "running_shock_theta_dot": "theta_dot",
                  "running_shock_target_theta": "target_theta",
                  "running_shock_target_theta_dot": "target_theta_dot"}


def study_dataset(cfg, settings: StudySettings, results: list[PointResult]) -> xr.Dataset:
    """The study of ``cfg`` (a validated :class:`atlas.pipeline.config.Config`) from the
    results of its points (``cfg.pendulum.points`` order)."""
    from atlas.pipeline.identity import library_versions

    pend = cfg.pendulum
    values = {name: pend.values(name) for name in PARAMETERS}
    swept = pend.swept
    shape = tuple(len(values[d]) for d in swept)
    ks = np.unique(np.concatenate([r.k for r in results] + [np.zeros(0, np.int64)])) \
        .astype(np.int64)
    n = len(results)
    frac = np.zeros((ks.size, n))
    frac_err = np.zeros((ks.size, n))
    shock = np.full((ks.size, n), np.nan)
    foot_t, foot_v = shock.copy(), shock.copy()
    point = {name: np.full(n, np.nan) for name in
             ("running_stability", "running_stability_error", "minimal_fatal_shock_error",
              "gaussian_stability", "gaussian_stability_error", *_RUNNING_SHOCK)}
    status = np.zeros(n, np.int8)
    for i, r in enumerate(results):
        status[i] = r.status
        if r.status != POINT_STATUS["exact"]:
            frac[:, i] = frac_err[:, i] = np.nan
            continue
        where = np.searchsorted(ks, r.k)
        frac[where, i], frac_err[where, i] = r.fraction, r.error
        point["running_stability"][i] = r.running
        point["running_stability_error"][i] = r.running_error
        point["minimal_fatal_shock_error"][i] = r.shock.error
        point["gaussian_stability"][i], point["gaussian_stability_error"][i] = r.gaussian
        for name, field in _RUNNING_SHOCK.items():
            point[name][i] = getattr(r.running_shock, field)
        shock[:, i] = r.shock.distance
        foot_t[:, i] = r.shock.theta + 2.0 * np.pi * ks
        foot_v[:, i] = r.shock.theta_dot
    data = {}

    def put(name, array, dims):
        data[name] = (dims, array, variable_attrs(name))

    for name, array in (("basin_stability", frac), ("basin_stability_error", frac_err),
                        ("minimal_fatal_shock", shock), ("fatal_shock_theta", foot_t),
                        ("fatal_shock_theta_dot", foot_v)):
        put(name, array.reshape((ks.size, *shape)), ("k", *swept))
    for name, array in point.items():
        if name.startswith("gaussian") and settings.sigma is None:
            continue
        put(name, array.reshape(shape), swept)
    put("point_status", status.reshape(shape), swept)
    lines = bifurcation_values(values["alpha"], values["omega0"], values["torque"], swept)
    for name, array in lines.items():
        full = STUDY_VARIABLES[name][0]  # the parameters it runs over
        keep = tuple(d for d in full if d in swept)
        index = tuple(slice(None) if d in swept else 0 for d in full)
        put(name, np.asarray(array, float)[index], keep)
    attrs = {"title": f"atlas stability study: {cfg.name}", "Conventions": "CF-1.10",
             "atlas_schema": STUDY_SCHEMA, "format_version": np.int64(STUDY_FORMAT),
             "config": cfg.to_json(),
             "window_theta": np.array(settings.window[0], float),
             "window_theta_dot": np.array(settings.window[1], float),
             "failures": json.dumps([f"{r.alpha:g}, {r.omega0:g}, {r.torque:g}: {r.message}"
                                     for r in results if r.status == POINT_STATUS["failed"]]),
             "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             **library_versions()}
    if settings.sigma is not None:
        attrs["sigma_theta"], attrs["sigma_theta_dot"] = map(float, settings.sigma)
    if settings.tipping and len(swept) == 1 and n >= 2:
        labels = np.append(ks, RUNNING_BASIN).astype(np.int64)
        from atlas.stability.tipping import tipping_matrix

        rows = np.stack([tipping_matrix(a.basins or {}, b.basins or {}, labels)
                         if a.status == b.status == POINT_STATUS["exact"]
                         else np.full((labels.size,) * 2, np.nan)
                         for a, b in zip(results[:-1], results[1:])])
        put("tipping_probability", rows, ("step", "source", "target"))
        coords_extra = {"step": np.arange(n - 1), "source": labels, "target": labels}
    else:
        coords_extra = {}
    coords = {name: (name, np.array(values[name], float)) if name in swept
              else ((), float(values[name][0])) for name in PARAMETERS}
    coords["k"] = ("k", ks)
    coords.update(coords_extra)
    ds = xr.Dataset(data, coords=coords, attrs=attrs)
    units = {"alpha": ("damping constant", "s-1"), "omega0": ("natural frequency", "rad s-1"),
             "torque": ("constant torque per unit moment of inertia", "rad s-2")}
    for name, (long_name, unit) in units.items():
        ds[name].attrs.update(long_name=long_name, units=unit)
    ds["k"].attrs.update(long_name="rest state (asin(torque/omega0^2) + 2 pi k, 0)", units="1")
    if coords_extra:
        ds["step"].attrs.update(long_name="from point step to point step + 1", units="1")
        for name in ("source", "target"):
            ds[name].attrs.update(long_name=f"{name} basin: well k, or {RUNNING_BASIN} for "
                                  "the running basin", units="1")
    return ds
