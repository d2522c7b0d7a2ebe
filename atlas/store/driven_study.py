"""The study file of ``atlas stability`` for a driven pendulum: its schema and its check.

The same container as the undriven study (:mod:`atlas.store.study`: HDF5 or Zarr,
``atlas_schema`` :data:`~atlas.store.schema.STUDY_SCHEMA`, ``format_version``, the config as
JSON, provenance), told apart by the root attribute ``model`` = ``"driven_pendulum"``
(:data:`DRIVEN_MODEL`). Its basin fractions are sampled, not exact: ``samples`` initial
conditions drawn uniformly in the window by NumPy's PCG64 seeded with ``seed`` (both
attributes; the same states at every point), each labelled with the attractor of the
stroboscopic map P it reaches.

Dims: the swept parameter (one of alpha, omega0, torque, amplitude, frequency; the
attribute ``swept_parameter``; a study of one point has a dim ``amplitude`` of length 1),
``attractor_id`` (the global ids of :mod:`atlas.models.driven.continuation`: one per
attractor followed along the sweep), ``orbit_point`` (the attractors' points on P, one row
each) and ``bifurcation`` (the located events). Every parameter is a coordinate (scalar when
not swept). The variables are :data:`DRIVEN_VARIABLES`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from atlas.errors import InputFileError
from atlas.store.schema import table_attrs

__all__ = ["DRIVEN_MODEL", "DRIVEN_PARAMETERS", "DRIVEN_VARIABLES", "KIND_MEANINGS",
           "EVENT_MEANINGS", "is_driven_study", "driven_attrs", "check_driven_study"]

#: The root attribute ``model`` of a driven pendulum's study.
DRIVEN_MODEL = "driven_pendulum"
#: The parameters, every one a coordinate (dims order: the swept one).
DRIVEN_PARAMETERS = ("alpha", "omega0", "torque", "amplitude", "frequency", "phase")
#: ``attractor_kind``'s flags.
KIND_MEANINGS = {0: "absent", 1: "periodic", 2: "chaotic"}
#: ``bifurcation_kind``'s flags (:data:`atlas.models.driven.continuation.EVENT_KINDS`).
EVENT_MEANINGS = {0: "birth", 1: "death", 2: "period_change"}

_P = "param"  # the swept parameter's dim, whichever it is
_F64, _I8, _I32, _I64 = np.float64, np.int8, np.int32, np.int64

#: name: (dims, with "param" for the swept parameter; dtype; long_name; units; comment).
DRIVEN_VARIABLES = {
    "basin_fraction": ((_P, "attractor_id"), _F64, "basin fraction of the attractor", "1",
                       "share of the sampled initial conditions (uniform in the window) "
                       "whose orbit reaches the attractor; NaN where the attractor is absent"),
    "basin_fraction_error": ((_P, "attractor_id"), _F64,
                             "standard error of basin_fraction", "1",
                             "binomial: sqrt(f (1 - f) / samples); NaN where absent"),
    "unresolved_fraction": ((_P,), _F64, "fraction of samples with no attractor", "1",
                            "share of the samples undecided by t_max or met with a NaN state"),
    "unresolved_fraction_error": ((_P,), _F64, "standard error of unresolved_fraction", "1",
                                  "binomial: sqrt(f (1 - f) / samples)"),
    "attractor_count": ((_P,), _I32, "number of attractors found", "1",
                        "found from seeds spread over the window (find_attractors)"),
    "attractor_kind": ((_P, "attractor_id"), _I8, "kind of the attractor", "1",
                       "absent: not found at this point"),
    "attractor_period": ((_P, "attractor_id"), _I32, "period of the attractor", "1",
                         "in drive periods; 0: chaotic; -1: absent"),
    "attractor_winding": ((_P, "attractor_id"), _I32, "winding of the attractor", "1",
                          "net turns of the orbit over its period (0: chaotic or absent)"),
    "attractor_status": ((_P, "attractor_id"), _I8, "status of the attractor's labels", "1",
                         "the driven atlas's status codes (0 converged, 3 near, 4 chaotic); "
                         "-1: absent"),
    "orbit_step": (("orbit_point",), _I32, "sweep point of the orbit point", "1",
                   "index along the swept parameter's dim"),
    "orbit_attractor": (("orbit_point",), _I64, "global id of the orbit point's attractor",
                        "1", ""),
    "orbit_theta": (("orbit_point",), _F64, "angle of the attractor's point on the "
                    "stroboscopic map", "rad", "wrapped to [-pi, pi); a periodic orbit's p "
                    "points, a chaotic attractor's recorded cloud (thinned to at most 500)"),
    "orbit_theta_dot": (("orbit_point",), _F64, "angular velocity of the attractor's point "
                        "on the stroboscopic map", "rad s-1", ""),
    "bifurcation_value": (("bifurcation",), _F64, "parameter value of the event",
                          "(the swept parameter's)",
                          "middle of the final bisection bracket"),
    "bifurcation_error": (("bifurcation",), _F64, "half width of the event's bracket",
                          "(the swept parameter's)",
                          "the event lies within value +- error, as find_attractors sees it"),
    "bifurcation_kind": (("bifurcation",), _I8, "kind of the event", "1",
                         "birth or death of an attractor, or a change of its period (or "
                         "kind) between consecutive points"),
    "bifurcation_attractor": (("bifurcation",), _I64, "global id of the attractor of the "
                              "event", "1", ""),
    "bifurcation_period_before": (("bifurcation",), _I32, "period below the event", "1",
                                  "-1: absent; 0: chaotic"),
    "bifurcation_period_after": (("bifurcation",), _I32, "period above the event", "1",
                                 "-1: absent; 0: chaotic"),
    "bifurcation_step": (("bifurcation",), _I32, "sweep point below the event", "1",
                         "the event lies between points step and step + 1"),
}


def is_driven_study(ds: xr.Dataset) -> bool:
    """Whether a study (opened) is a driven pendulum's (root attribute ``model``)."""
    model = ds.attrs.get("model")
    if isinstance(model, bytes):
        model = model.decode()
    return str(model) == DRIVEN_MODEL


def driven_attrs(name: str) -> dict:
    """The CF attributes of driven-study variable ``name``; the swept parameter's units
    are the coordinate's (read them there)."""
    flags = {"attractor_kind": KIND_MEANINGS, "bifurcation_kind": EVENT_MEANINGS}
    return table_attrs(DRIVEN_VARIABLES, name, flags.get(name))


def check_driven_study(ds: xr.Dataset, path) -> None:
    """Refuse (one InputFileError line naming ``path``) a driven study that breaks the
    schema: its swept parameter, every variable with its dims and dtype, fractions within
    [0, 1] summing with the unresolved fraction to 1, ids within ``attractor_id``, and the
    samples and seed attributes. (The container's checks, schema, version and config, are
    :func:`atlas.store.study.check_study`'s.)"""
    def refuse(what: str):
        raise InputFileError(f"{path}: {what}")

    swept = str(ds.attrs.get("swept_parameter", ""))
    if swept not in DRIVEN_PARAMETERS or swept not in ds.dims:
        refuse(f"the swept parameter {swept!r} is not a dim of this driven study")
    for name in DRIVEN_PARAMETERS:
        if name not in ds.coords:
            refuse(f"the parameter coordinate {name} is missing")
        values = np.asarray(ds[name].values)
        if values.dtype != _F64 or not np.isfinite(values).all() or \
                (values.ndim == 1 and not (np.diff(values) > 0).all()):
            refuse(f"the coordinate {name} is not finite, increasing float64")
    for key in ("samples", "seed"):
        value = np.asarray(ds.attrs.get(key, -1)).reshape(-1)
        if value.size != 1 or value.dtype.kind not in "iu" or int(value[0]) < (key == "samples"):
            refuse(f"the attribute {key} is not a whole number")
    for name, (dims, dtype, *_) in DRIVEN_VARIABLES.items():
        if name not in ds:
            refuse(f"the variable {name} is missing")
        want = tuple(swept if d == _P else d for d in dims)
        if ds[name].dims != want:
            refuse(f"{name} has dims {ds[name].dims}, expected {want}")
        if ds[name].dtype != dtype:
            refuse(f"{name} is {ds[name].dtype}, expected {np.dtype(dtype)}")
    f = ds["basin_fraction"].values
    u = ds["unresolved_fraction"].values
    present = ds["attractor_kind"].values > 0
    if np.isnan(f[present]).any() or not np.isnan(f[~present]).all() or \
            not ((f[present] >= 0) & (f[present] <= 1)).all() or \
            not np.allclose(np.nansum(f, axis=1) + u, 1.0, atol=1e-9):
        refuse("basin_fraction and unresolved_fraction are not fractions summing to 1")
    ids = np.asarray(ds["attractor_id"].values)
    for name in ("orbit_attractor", "bifurcation_attractor"):
        if not np.isin(ds[name].values, ids).all():
            refuse(f"{name} names an attractor_id the study does not have")
