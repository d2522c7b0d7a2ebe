"""Files are checked before they are believed: the schema check every reader shares.

:func:`atlas.open` (and with it ``atlas info``, ``plot``, ``view`` and ``orbit``) opens an
atlas file and runs :func:`check_tree` before any view uses it; a file that fails is refused
with one :class:`~atlas.errors.InputFileError` line naming it and what is wrong (exit status
2). Checked against :mod:`atlas.store.schema`, from the metadata and the small groups (the
maps are not read): ``format_version`` (3 or 4; older layouts are refused naming their
version); the basin map's variables, dtypes and dims; the coordinates (``theta0``,
``theta_dot0`` finite and increasing; every parameter a finite float64, scalar or swept);
``status``'s CF flags against :data:`atlas.status.STATUS_MEANINGS`; the summary; the
attributes the readers use (``dt``, ``t_max``, ``check_every``, ``method``, ``config`` a
JSON object); the per-point groups' vectors and attributes. In format 4 also the stored
certificate: ``trap_energy_cap`` per point, and in each ``/limit_cycle`` node the running
barrier (finite ``barrier_g``, g[-1] ≥ g[0], ``barrier_top`` above every g, direction ±1).
"""

from __future__ import annotations

import json
import math
import numbers

import numpy as np

from atlas import defaults
from atlas.errors import InputFileError
from atlas.layout import point_nodes
from atlas.models.base import Model
from atlas.models.registry import of_attrs
from atlas.store.schema import (
    BARRIER_ATTRS,
    BARRIER_DIM,
    CERTIFICATE_FORMAT,
    FORMAT_VERSION,
    OLDEST_FORMAT,
)

__all__ = ["check_tree", "check_dataset", "model_of", "parse_config", "format_version",
           "file_method"]


def _refuse(path, what: str):
    raise InputFileError(f"{path}: {what}")


def format_version(attrs: dict, path) -> int:
    """The file's layout version (1 when absent): :data:`~atlas.store.schema.OLDEST_FORMAT`
    to :data:`~atlas.store.schema.FORMAT_VERSION`; an older or newer one, or a value that is
    not an integer, is refused."""
    value = attrs.get("format_version", 1)
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(()).item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        _refuse(path, f"format_version {value!r} is not an integer; not an atlas file this "
                "atlas can read")
    value = int(value)
    if value > FORMAT_VERSION:
        _refuse(path, f"format_version {value} is newer than this atlas reads (up to "
                f"{FORMAT_VERSION}); upgrade atlas to read it")
    if value < 1:
        _refuse(path, f"format_version {value} is not a version atlas ever wrote")
    if value < OLDEST_FORMAT:
        _refuse(path, f"format_version {value}, an older layout than this atlas reads "
                f"({OLDEST_FORMAT} to {FORMAT_VERSION}); run its config again to rewrite it")
    return value


def file_method(attrs: dict, path) -> str:
    """The discretisation the file's labels come from: its ``method`` attribute (bytes
    decoded; "rk4" where absent), or one InputFileError line if it is not one of
    :data:`atlas.defaults.METHODS` as text."""
    method = attrs.get("method", defaults.METHOD)
    if isinstance(method, bytes):
        method = method.decode("utf-8", "replace")
    if not isinstance(method, str) or method not in defaults.METHODS:
        _refuse(path, f"attribute method = {str(method)[:40]!r} is not one of "
                f"{', '.join(defaults.METHODS)}")
    return method


def parse_config(attrs: dict, path):
    """The stored ``config`` attribute as a dict (None if the file has none), or one
    InputFileError line: it must be a JSON object."""
    if "config" not in attrs:
        return None
    text = attrs["config"]
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    if not isinstance(text, str):
        _refuse(path, f"the config attribute is not text (a {type(text).__name__})")
    try:
        config = json.loads(text)
    except ValueError as exc:
        _refuse(path, f"the config attribute is not valid JSON ({getattr(exc, 'msg', exc)} "
                f"at character {getattr(exc, 'pos', '?')})")
    except RecursionError:
        _refuse(path, "the config attribute is not valid JSON (nested too deeply)")
    if not isinstance(config, dict):
        _refuse(path, f"the config attribute is not a JSON object (a {type(config).__name__})")
    return config


def _number(attrs: dict, name: str, path, *, positive=False, nonnegative=False, finite=True,
            where="") -> float:
    if name not in attrs:
        _refuse(path, f"no {where}attribute {name}")
    value = attrs[name]
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(()).item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        _refuse(path, f"{where}attribute {name} is not a number ({str(value)[:40]!r})")
    value = float(value)
    if ((finite and not math.isfinite(value)) or (positive and not value > 0)
            or (nonnegative and not value >= 0)):
        _refuse(path, f"{where}attribute {name} = {value!r} is out of range")
    return value


def _axis(ds, name: str, path, increasing: bool) -> None:
    if name not in ds.coords:
        _refuse(path, f"no {name} coordinate")
    var = ds.coords[name]
    if var.dims != (name,):
        _refuse(path, f"coordinate {name} has dims {var.dims}, not ({name!r},)")
    if var.dtype != np.float64:
        _refuse(path, f"coordinate {name} is {var.dtype}, not float64")
    values = var.values
    if values.size < 1 or not np.all(np.isfinite(values)):
        _refuse(path, f"coordinate {name} is empty or not finite")
    if increasing and (values.size < 2 or not np.all(np.diff(values) > 0)):
        _refuse(path, f"coordinate {name} is not strictly increasing")


def _parameter(ds, name: str, path, positive: bool) -> None:
    """A physical parameter: a finite float64 coordinate, scalar or its own 1-D dim; > 0
    where its model says so (``positive``)."""
    if name not in ds.coords:
        _refuse(path, f"no {name} coordinate")
    if name in ds.dims:
        _axis(ds, name, path, increasing=False)
    elif ds.coords[name].dims != () or ds.coords[name].dtype != np.float64:
        _refuse(path, f"coordinate {name} is not a float64 scalar or a dim of its own")
    values = ds.coords[name].values
    if not np.all(np.isfinite(values)) or (positive and not np.all(values > 0)):
        _refuse(path, f"coordinate {name} is out of range")


def model_of(attrs: dict, path) -> Model:
    """The model of the file at ``path`` (its ``model`` attribute: the pendulum where
    absent); one InputFileError line for a model this atlas does not know."""
    try:
        return of_attrs(attrs)
    except ValueError as exc:
        _refuse(path, f"an atlas whose {exc}, so it cannot be read here")


def _flags(attrs: dict, path, model: Model) -> None:
    values, meanings = attrs.get("flag_values"), attrs.get("flag_meanings")
    if values is None or not isinstance(meanings, str):
        _refuse(path, "status has no flag_values/flag_meanings attributes")
    values = np.atleast_1d(np.asarray(values))
    words = meanings.split()
    if values.dtype.kind not in "iu" or values.ndim != 1 or values.size != len(words):
        _refuse(path, "status's flag_values and flag_meanings do not pair up")
    for value, word in zip(values.tolist(), words):
        if model.statuses.get(value) != word:
            _refuse(path, f"status flag {value} means {word!r} in this file, not "
                    f"{model.statuses.get(value, 'anything atlas writes')!r}")


def check_dataset(ds, path) -> int:
    """Check the root group ``ds`` (an :class:`xarray.Dataset` opened with
    ``mask_and_scale=False``) of the atlas file at ``path``; InputFileError if it fails.
    Returns the file's format version."""
    attrs = ds.attrs
    version = format_version(attrs, path)
    model = model_of(attrs, path)
    lead = tuple(name for name in model.parameters if name in ds.dims)
    columns, rows = model.axes
    dims = (*lead, rows.name, columns.name)
    for axis in (columns, rows):
        _axis(ds, axis.name, path, increasing=True)
    for name in model.parameters:
        _parameter(ds, name, path, positive=name in model.positive)
    for name, spec in model.map_variables.items():
        if name not in ds.data_vars:
            _refuse(path, f"no {name} variable")
        var = ds[name]
        if var.dtype != spec.dtype:
            _refuse(path, f"variable {name} is {var.dtype}, not {np.dtype(spec.dtype)}")
        if var.dims != dims:
            _refuse(path, f"variable {name} has dims {var.dims}, not {dims}")
    _flags(ds["status"].attrs, path, model)
    if "k" not in ds.coords or ds["k"].dims != ("k",) or ds["k"].dtype.kind not in "iu":
        _refuse(path, "no integer k coordinate (the basins' summary)")
    point_names = [name for name in model.point_variables
                   if version >= model.since.get(name, OLDEST_FORMAT)]
    for names, want in ((model.basin_variables, (*lead, "k")), (point_names, lead)):
        for name in names:
            if name not in ds.data_vars:
                _refuse(path, f"no {name} variable (the summary)")
            if ds[name].dims != want or ds[name].dtype.kind not in "fiu":
                _refuse(path, f"variable {name} has dims {ds[name].dims} and dtype "
                        f"{ds[name].dtype}, not numbers on {want}")
    _number(attrs, "dt", path, positive=True)
    _number(attrs, "t_max", path, positive=True)
    if "check_every" in attrs:
        every = _number(attrs, "check_every", path, positive=True)
        if every != int(every):
            _refuse(path, f"attribute check_every = {every!r} is not an integer")
    if "trap_energy_cap" in point_names:
        cap = np.asarray(ds["trap_energy_cap"].values)
        if np.isnan(cap).any() or (cap == np.inf).any():
            _refuse(path, "variable trap_energy_cap holds NaN or +inf (a cap is finite, or "
                    "-inf where no well can trap)")
    file_method(attrs, path)
    parse_config(attrs, path)
    return version


def check_tree(tree, path) -> None:
    """Check an opened atlas (:class:`xarray.DataTree`): the root group
    (:func:`check_dataset`), then the groups the readers draw from (their small arrays are
    read: the separatrices' branch codes index a table)."""
    version = check_dataset(tree.to_dataset(inherit=False), path)
    for node in point_nodes(tree, "critical_points"):
        cp = node.to_dataset(inherit=False)
        _point_attrs(node, path)
        _vector(cp, node.path, "theta", "f", path, dim="point")
        _vector(cp, node.path, "n", "iu", path, dim="point")
    for node in point_nodes(tree, "separatrices"):
        _point_attrs(node, path)
        _check_separatrices(node.to_dataset(inherit=False), node.path, path)
    for node in point_nodes(tree, "limit_cycle"):
        _point_attrs(node, path)
        cycle = node.to_dataset(inherit=False)
        for name in ("theta", "theta_dot", "time"):
            _vector(cycle, node.path, name, "f", path, dim="sample")
        _number(node.attrs, "period", path, positive=True, where=f"{node.path} ")
        _number(node.attrs, "mean_theta_dot", path, where=f"{node.path} ")
        direction = _number(node.attrs, "direction", path, where=f"{node.path} ")
        if direction not in (1.0, -1.0):
            _refuse(path, f"{node.path} attribute direction = {direction:g} is not +1 or -1")
        if version >= CERTIFICATE_FORMAT:
            _check_barrier(cycle, node.path, path, direction)


def _check_barrier(cycle, group: str, path, direction: float) -> None:
    """Format 4's running barrier in a ``/limit_cycle`` node: the contract the kernels tested
    (:class:`atlas.physics.barrier.RunningBarrier`), so that a view may draw it as stored."""
    g = _vector(cycle, group, "barrier_g", "f", path, dim=BARRIER_DIM)
    if g.size < 2 or not np.all(np.isfinite(g)):
        _refuse(path, f"{group}/barrier_g is not finite or has fewer than 2 samples")
    if not g[-1] >= g[0]:
        _refuse(path, f"{group}/barrier_g ends below its start ({g[-1]:g} < {g[0]:g})")
    where = f"{group} "
    for name in BARRIER_ATTRS:
        _number(cycle.attrs, name, path, where=where)
    top = _number(cycle.attrs, "barrier_top", path, where=where)
    if not top > g.max():
        _refuse(path, f"{group} attribute barrier_top = {top:g} is not above every barrier_g "
                f"(max {g.max():g})")
    sign = _number(cycle.attrs, "barrier_direction", path, where=where)
    if sign not in (1.0, -1.0):
        _refuse(path, f"{group} attribute barrier_direction = {sign:g} is not +1 or -1")
    if sign != direction:
        _refuse(path, f"{group} attribute barrier_direction = {sign:g} is not the cycle's "
                f"direction {direction:g}")


def _point_attrs(node, path) -> None:
    for name in of_attrs(node.root.attrs).parameters:
        _number(node.attrs, name, path, where=f"{node.path} ")


def _vector(ds, group: str, name: str, kinds: str, path, dim: str):
    if name not in ds.variables:
        _refuse(path, f"the {group} group has no {name}")
    var = ds[name]
    if var.dims != (dim,) or var.dtype.kind not in kinds:
        _refuse(path, f"{group}/{name} has dims {var.dims} and dtype {var.dtype}, not a "
                f"{'float' if kinds == 'f' else 'integer'} vector over {dim}")
    return var.values


def _check_separatrices(sep, group: str, path) -> None:
    branch = _vector(sep, group, "branch", "iu", path, "point")
    for name in ("saddle_n", "vertex"):
        _vector(sep, group, name, "iu", path, "point")
    for name in ("theta", "theta_dot"):
        _vector(sep, group, name, "f", path, "point")
    if branch.size and not np.isin(branch, (0, 1)).all():
        _refuse(path, f"{group}/branch holds codes other than 0 (left) and 1 (right)")
    for name in ("tol", "max_spacing", "discrepancy_bound"):
        _number(sep.attrs, name, path, positive=True, where=f"{group} ")
    if "discrepancy" not in sep.attrs:
        _refuse(path, f"no {group} attribute discrepancy")
    _number(sep.attrs, "discrepancy", path, finite=False, where=f"{group} ")
