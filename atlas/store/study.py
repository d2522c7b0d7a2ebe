"""The study file of ``atlas stability``: its schema, written once, its writer and its
checked reader.

An xarray Dataset in HDF5 (netCDF-4 layout, engine ``h5netcdf``) or, for an output named
``NAME.zarr``, a Zarr store, with the atlas file's conventions: CF-1.10 attributes on every
variable, ``format_version`` (:data:`STUDY_FORMAT`), ``atlas_schema``
(:data:`STUDY_SCHEMA`, which tells a study from a basin atlas), the validated ``config`` as
JSON, provenance (``created``, library versions). Dims: ``k`` (the rest states whose basins
meet the window at some point of the study) and the swept parameters, in the order alpha,
omega0, torque; every parameter is a coordinate (scalar when not swept). The variables are
:data:`STUDY_VARIABLES` (the SPEC's fixed names and the documented others); optional ones
are absent when not asked. :func:`open_study` checks a file before it is believed (one
:class:`~atlas.errors.InputFileError` line otherwise).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import InputFileError
from atlas.models.pendulum.description import PARAMETERS
from atlas.store.formats import format_for
from atlas.store.schema import STUDY_SCHEMA, table_attrs

__all__ = ["STUDY_SCHEMA", "STUDY_FORMAT", "STUDY_VARIABLES", "BIFURCATIONS",
           "POINT_STATUS_MEANINGS",
           "write_study", "open_study", "is_study_file", "check_study", "swept_dims",
           "variable_attrs", "RUNNING_BASIN"]

#: Version of the study file's layout (root attribute ``format_version``).
STUDY_FORMAT = 1
#: ``point_status``'s flags: what the numbers of a parameter point are.
POINT_STATUS_MEANINGS = {0: "exact", 1: "saddle_node", 2: "failed"}
#: The ``source`` and ``target`` coordinate of the running basin in ``tipping_probability``
#: (the atlas file's attractor fill value, which names no well).
RUNNING_BASIN = -32768

_K = "k"
_PARAMS = "params"  # the swept parameter dims
_F64 = np.float64

#: name: (dims: "k" = k + params, "params", "tipping", or a tuple of the parameters it runs
#: over when swept; required; long_name; units; comment).
STUDY_VARIABLES = {
    "basin_stability": (_K, True, "basin stability of rest state k", "1",
                        "exact area fraction of the window in the basin of (asin(torque/"
                        "omega0^2) + 2 pi k, 0), from the stable manifolds: a grid run's "
                        "basin_fraction_exact"),
    "basin_stability_error": (_K, True, "error estimate of basin_stability", "1",
                              "the reference's change from rtol 1e-12 to 1e-13 (with torque "
                              "both exact for the DOP853 dense output)"),
    "running_stability": (_PARAMS, True, "basin stability of the running limit cycle", "1",
                          "exact area fraction of the window in the running basin (0 where "
                          "there is no running cycle)"),
    "running_stability_error": (_PARAMS, True, "error estimate of running_stability", "1", ""),
    "minimal_fatal_shock": (_K, True, "minimal fatal shock of rest state k", "1",
                            "Euclidean (theta, theta_dot) distance, theta [rad] and theta_dot "
                            "[rad s-1] as one unit, from the rest state to the nearest point "
                            "of its basin boundary (Halekotte & Feudel 2020); the same for "
                            "every k; NaN without rest state"),
    "minimal_fatal_shock_error": (_PARAMS, True, "error estimate of minimal_fatal_shock", "1",
                                  "without torque the boundaries' reference error; with "
                                  "torque the distance's change with the boundaries at "
                                  "rtol 1e-12"),
    "fatal_shock_theta": (_K, True, "theta of the nearest boundary point of rest state k",
                          "rad", ""),
    "fatal_shock_theta_dot": (_K, True, "theta_dot of the nearest boundary point of rest "
                              "state k", "rad s-1", ""),
    "running_fatal_shock": (_PARAMS, False, "minimal fatal shock of the running limit cycle",
                            "1", "Euclidean (theta, theta_dot) distance, theta [rad] and "
                            "theta_dot [rad s-1] as one unit, from the nearest point of the "
                            "running cycle to the nearest point of a basin boundary "
                            "(Halekotte & Feudel 2020); NaN where there is no running cycle "
                            "or no rest state"),
    "running_fatal_shock_error": (_PARAMS, False, "error estimate of running_fatal_shock",
                                  "1", "the distance's change with the boundaries at rtol "
                                  "1e-12, plus the cycle's own error"),
    "running_shock_theta": (_PARAMS, False, "theta of the running cycle's point nearest a "
                            "boundary", "rad", ""),
    "running_shock_theta_dot": (_PARAMS, False, "theta_dot of the running cycle's point "
                                "nearest a boundary", "rad s-1", ""),
    "running_shock_target_theta": (_PARAMS, False, "theta of the boundary point nearest the "
                                   "running cycle", "rad", ""),
    "running_shock_target_theta_dot": (_PARAMS, False, "theta_dot of the boundary point "
                                       "nearest the running cycle", "rad s-1", ""),
    "point_status": (_PARAMS, True, "what the numbers of the parameter point are", "1",
                     "exact: from the stable manifolds; saddle_node: |torque| = omega0^2, no "
                     "certified boundaries, values NaN; failed: the boundaries failed, "
                     "values NaN (the reason is in the attribute failures)"),
    "homoclinic_torque": (("alpha", "omega0"), True, "homoclinic torque", "rad s-2",
                          "the running cycle exists for |torque| above it; Brent's method on "
                          "the saddle's unstable manifold (DOP853), about 1e-11 relative"),
    "saddle_node_torque": (("omega0",), True, "saddle-node torque omega0^2", "rad s-2",
                           "no rest state for |torque| >= omega0^2"),
    "focus_node_damping": (("omega0", "torque"), True, "focus-node damping", "s-1",
                           "(omega0^4 - torque^2)^(1/4): the rest state is a focus below it, "
                           "a node above it (closed form)"),
    "homoclinic_damping": (("omega0", "torque"), False, "homoclinic damping", "s-1",
                           "the damping below which the running cycle exists, inside the "
                           "study's alpha range (NaN where it is outside); only in studies "
                           "over alpha at fixed torque"),
    "homoclinic_omega0": (("alpha", "torque"), False, "homoclinic natural frequency",
                          "rad s-1", "the natural frequency below which the running cycle "
                          "exists, inside the study's omega0 range (NaN where it is "
                          "outside); Brent's method on omega0 on the homoclinic torque, about "
                          "1e-11 relative; sqrt(|torque|) where the damping is strong (the "
                          "cycle is born at the saddle-node); only in studies over omega0 at "
                          "fixed torque"),
    "saddle_node_omega0": (("torque",), False, "saddle-node natural frequency sqrt(|torque|)",
                           "rad s-1", "no rest state for omega0 <= sqrt(|torque|); only in "
                           "studies over omega0"),
    "focus_node_torque": (("alpha", "omega0"), False, "focus-node torque", "rad s-2",
                          "(omega0^4 - alpha^4)^(1/2): the rest state is a focus for |torque| "
                          "below it, a node above it (closed form; NaN for alpha >= omega0); "
                          "only in studies over torque"),
    "focus_node_omega0": (("alpha", "torque"), False, "focus-node natural frequency",
                          "rad s-1", "(alpha^4 + torque^2)^(1/4): the rest state is a node "
                          "for omega0 below it, a focus above it (closed form); only in "
                          "studies over omega0"),
    "gaussian_stability": (_PARAMS, False, "basin stability under a Gaussian perturbation",
                           "1", "probability that a rest state kicked by independent normal "
                           "perturbations (sigma_theta, sigma_theta_dot: attributes) stays in "
                           "its basin, Green's theorem over the exact basin; the same for "
                           "every k"),
    "gaussian_stability_error": (_PARAMS, False, "error estimate of gaussian_stability", "1",
                                 ""),
    "tipping_probability": ("tipping", False, "tipping probability between consecutive "
                            "points", "1",
                            "share of the window part of basin source at point step that lies "
                            "in basin target at point step + 1 (Kaszas, Feudel & Tel 2019); "
                            f"basin {RUNNING_BASIN}: the running basin; rows sum to 1"),
}

#: The bifurcation variables: name → (the parameter whose value it is, the bifurcation): a
#: study over that parameter marks it on its axis (1-D) or draws it as a curve (2-D); the
#: same bifurcation read along another parameter is another variable.
BIFURCATIONS = {"homoclinic_torque": ("torque", "homoclinic"),
                "homoclinic_damping": ("alpha", "homoclinic"),
                "homoclinic_omega0": ("omega0", "homoclinic"),
                "saddle_node_torque": ("torque", "saddle-node"),
                "saddle_node_omega0": ("omega0", "saddle-node"),
                "focus_node_damping": ("alpha", "focus-node"),
                "focus_node_torque": ("torque", "focus-node"),
                "focus_node_omega0": ("omega0", "focus-node")}


def _dims(kind, swept: tuple[str, ...]) -> tuple[str, ...]:
    if kind == _K:
        return (_K, *swept)
    if kind == _PARAMS:
        return swept
    if kind == "tipping":
        return ("step", "source", "target")
    return tuple(d for d in PARAMETERS if d in kind and d in swept)


def swept_dims(ds: xr.Dataset) -> tuple[str, ...]:
    """The swept parameters of a study (its parameter dims), in the order alpha, omega0,
    torque."""
    return tuple(d for d in PARAMETERS if d in ds.dims)


def variable_attrs(name: str) -> dict:
    """The CF attributes of study variable ``name``."""
    return table_attrs(STUDY_VARIABLES, name,
                       POINT_STATUS_MEANINGS if name == "point_status" else None)


def write_study(ds: xr.Dataset, path: str | Path) -> None:
    """Write ``ds`` (checked first, :func:`check_study`) at ``path`` in the format its name
    asks for (:func:`atlas.store.formats.format_for`): whole or not at all."""
    path = Path(path)
    check_study(ds, path)
    format_for(path).write_dataset(ds, path)


def is_study_file(path: str | Path) -> bool:
    """Whether ``path`` is a study file (by its ``atlas_schema`` attribute)."""
    path = Path(path)
    fmt = format_for(path)
    if not path.exists() or (path.is_dir() and not fmt.folder):
        return False
    try:
        value = fmt.root_attrs(path).get("atlas_schema")
    except Exception:  # not HDF5 / Zarr at all: the atlas reader says what it is
        return False
    if isinstance(value, bytes):
        value = value.decode()
    return str(value) == STUDY_SCHEMA


def open_study(path: str | Path) -> xr.Dataset:
    """The study at ``path``, loaded and checked (:func:`check_study`)."""
    path = Path(path)
    if not path.exists():
        raise InputFileError(f"{path}: no such file")
    try:
        ds = format_for(path).open_dataset(path)
    except Exception as exc:  # a damaged file fails in h5py, h5netcdf, zarr or xarray
        raise InputFileError(f"{path}: not a readable study file "
                             f"({exc.__class__.__name__})") from None
    check_study(ds, path)
    return ds


def _numbers(value) -> np.ndarray:
    """``value`` (an attribute) as a flat float array; empty if it holds no numbers."""
    try:
        return np.asarray(value, float).ravel()
    except (TypeError, ValueError):
        return np.zeros(0)


def check_study(ds: xr.Dataset, path) -> None:
    """Refuse (one InputFileError line naming ``path``) a study that breaks the schema: its
    schema and format version, the required variables with their dims and float64 (int8 for
    ``point_status``, with its flags), finite increasing parameter coordinates, fractions
    within [0, 1] and summing to 1 where exact, the window attributes, and ``config`` a JSON
    object."""
    def refuse(what: str):
        raise InputFileError(f"{path}: {what}")

    attrs = ds.attrs
    if str(attrs.get("atlas_schema")) != STUDY_SCHEMA:
        refuse(f"not a stability study (atlas_schema {attrs.get('atlas_schema')!r})")
    version = np.asarray(attrs.get("format_version", -1)).reshape(-1)
    if version.size != 1 or version.dtype.kind not in "iu" or int(version[0]) != STUDY_FORMAT:
        refuse(f"study format_version {attrs.get('format_version')!r}; this atlas reads "
               f"{STUDY_FORMAT}")
    try:
        if not isinstance(json.loads(str(attrs.get("config"))), dict):
            raise ValueError
    except ValueError:
        refuse("the attribute config is not a JSON object")
    for name in ("window_theta", "window_theta_dot"):
        edges = _numbers(attrs.get(name, []))
        if edges.size != 2 or not np.isfinite(edges).all() or not edges[0] < edges[1]:
            refuse(f"the attribute {name} is not a window (min, max)")
    from atlas.store.driven_study import check_driven_study, is_driven_study

    if is_driven_study(ds):  # a driven pendulum's: its own variables
        check_driven_study(ds, path)
        return
    sigmas = [_numbers(attrs.get(n, np.nan)) for n in ("sigma_theta", "sigma_theta_dot")]
    if "gaussian_stability" in ds and not all(s.size and np.isfinite(s).all() for s in sigmas):
        refuse("gaussian_stability without the attributes sigma_theta, sigma_theta_dot")
    for name in PARAMETERS:
        if name not in ds.coords:
            refuse(f"the parameter coordinate {name} is missing")
        values = np.asarray(ds[name].values)
        if values.dtype != np.float64 or not np.isfinite(values).all() or values.ndim > 1 \
                or (values.ndim == 1 and not (np.diff(values) > 0).all()):
            refuse(f"the coordinate {name} is not finite, increasing float64")
    swept = swept_dims(ds)
    for name, (kind, required, *_) in STUDY_VARIABLES.items():
        if name not in ds:
            if required:
                refuse(f"the variable {name} is missing")
            continue
        dims = _dims(kind, swept)
        if ds[name].dims != dims:
            refuse(f"{name} has dims {ds[name].dims}, expected {dims}")
        dtype = np.int8 if name == "point_status" else _F64
        if ds[name].dtype != dtype:
            refuse(f"{name} is {ds[name].dtype}, expected {np.dtype(dtype)}")
    status = ds["point_status"].values
    if not np.isin(status, list(POINT_STATUS_MEANINGS)).all():
        refuse("point_status holds a value outside its flags")
    exact = status == 0
    fractions = ds["basin_stability"].values
    running = ds["running_stability"].values
    if not (np.all((fractions[:, exact] >= -1e-12) & (fractions[:, exact] <= 1 + 1e-12))
            and np.all(np.abs(fractions.sum(axis=0)[exact] + running[exact] - 1.0) < 1e-6)):
        refuse("basin_stability and running_stability are not fractions summing to 1")
    if "k" in ds.coords and ds["k"].dtype.kind not in "iu":
        refuse("the coordinate k is not an integer")

