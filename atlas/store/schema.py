"""The atlas file's schema, written once: versions, chunks, the summary, CF attributes.

Every format (:mod:`atlas.store.hdf5`, :mod:`atlas.store.zarrformat`) writes, and
:mod:`atlas.store.validate` checks, what is declared here and by the file's model
(:mod:`atlas.models`): the basin map (the model's ``map_variables``; for the pendulum
``attractor`` int16 with ``_FillValue``, ``status`` int8 with CF flags from
:mod:`atlas.status`, ``t_trap`` float32 [s], ``boundary_distance`` float32; dims: the swept
parameters, then the model's two axes, one chunk per tile), the summary (the model's
``basin_variables`` over ``k`` and ``point_variables`` per parameter point,
:func:`summary_dataset`), and the pendulum's format 4 certificate (:data:`BARRIER_G`,
:data:`BARRIER_ATTRS` in each ``/limit_cycle`` node, ``trap_energy_cap`` per point: the
running barrier and the trap level the labels were certified with). Conventions: CF-1.10
(units as UDUNITS strings, "1" for counts and fractions).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.layout import Layout
from atlas.models.base import MapVariable

__all__ = ["FORMAT_VERSION", "OLDEST_FORMAT", "CERTIFICATE_FORMAT", "SCHEMA", "STUDY_SCHEMA",
           "not_an_atlas",
           "MapVariable", "map_variables", "chunks_of", "summary_dataset",
           "summary_tree", "table_attrs", "BARRIER_DIM", "BARRIER_G", "BARRIER_ATTRS",
           "with_barrier"]

#: Version of the layout this atlas writes (root attribute ``format_version``). 1: files
#: without the attribute; 2: the attribute is written; 3: every parameter (α, ω0, τ) is a
#: coordinate, and the per-point groups hold one node per parameter point; 4: the
#: certificate the labels used is stored (``trap_energy_cap``, the running barrier).
FORMAT_VERSION = 4
#: The oldest layout this atlas reads (format 3: without the stored certificate).
OLDEST_FORMAT = 3
#: The first layout that stores the certificate.
CERTIFICATE_FORMAT = 4
#: Root attribute ``atlas_schema`` of every atlas file, complete or not.
SCHEMA = "atlas-basin-map/1"
#: Root attribute ``atlas_schema`` of a stability study file (:mod:`atlas.store.study`).
STUDY_SCHEMA = "atlas-stability-study/1"

def map_variables(layout: Layout) -> dict[str, MapVariable]:
    """The basin map's variables of ``layout``'s model, in file order."""
    return layout.model.map_variables


def chunks_of(layout: Layout) -> tuple[int, ...]:
    """The map variables' chunks: one per tile (one parameter point, a band of whole rows)."""
    return (*(1 for _ in layout.swept), layout.chunk_rows, layout.x0.size)


def table_attrs(table: dict, name: str, flags: dict | None = None) -> dict:
    """The CF attributes of variable ``name`` from a table whose rows end (long_name, units,
    comment): long_name, units, the comment where there is one, and for a flag variable
    ``flags`` (code → meaning) its flag_values and flag_meanings."""
    long_name, units, comment = table[name][-3:]
    attrs = {"long_name": long_name, "units": units}
    if comment:
        attrs["comment"] = comment
    if flags:
        attrs["flag_values"] = np.array(list(flags), np.int8)
        attrs["flag_meanings"] = " ".join(flags.values())
    return attrs


def summary_dataset(layout: Layout, points: list[dict]) -> xr.Dataset:
    """The summary of every parameter point (``points`` in the order of ``layout``'s points,
    each a dict of its model's basin variables over its own ``k`` and point variables,
    :attr:`atlas.models.base.Model.basin_variables` and ``point_variables``): per-basin
    variables over ``k`` (the union of every point's basins, 0 where a basin is absent) and
    per-point scalars, both with the parameter dims leading."""
    model = layout.model
    ks = sorted({int(k) for p in points for k in p["k"]}) or [0]
    lead, lead_dims = layout.parameter_shape, layout.swept
    data = {}
    for name, attrs in model.basin_variables.items():
        table = np.zeros((len(points), len(ks)))
        for row, p in zip(table, points):
            values = np.asarray(p[name], float)
            if values.size and np.isnan(values).all():
                row[:] = np.nan  # not computed for this point (no exact boundaries)
            row[np.searchsorted(ks, p["k"])] = values
        data[name] = ((*lead_dims, "k"), table.reshape(*lead, len(ks)), {"units": "1", **attrs})
    for name, attrs in model.point_variables.items():
        values = np.array([p[name] for p in points], np.float64).reshape(lead)
        data[name] = (lead_dims, values, {"units": "1", **attrs})
    return xr.Dataset(data, coords={"k": ("k", np.array(ks, np.int16), {
        "long_name": f"attractor index: {model.attractor}", "units": "1"})})


def summary_tree(layout: Layout, root_vars: xr.Dataset, groups: dict[str, xr.Dataset],
                 attrs: dict) -> xr.DataTree:
    """What a format's ``finalize`` writes beyond the basin map, as an in-memory DataTree:
    the grid's and parameters' coordinates, the summary's root variables, the root attributes
    ``attrs`` and the ``groups`` (path → dataset). ``atlas run`` prints its summary from
    this instead of reading the file back (0.1 s of HDF5 metadata on the default grid)."""
    root = root_vars.assign_coords(layout.coords()).assign_attrs(
        {key: value for key, value in attrs.items() if value is not None})
    return xr.DataTree.from_dict({"/": root, **groups})


#: Format 4: the dim of the running barrier's samples in a ``/limit_cycle`` node.
BARRIER_DIM = "barrier_sample"
#: Format 4: the running barrier's lower curve, a variable over :data:`BARRIER_DIM`.
BARRIER_G = {
    "units": "rad s-1", "long_name": "lower curve of the running barrier",
    "comment": "in the frame of positive rotation (u = barrier_direction * theta, w = "
               "barrier_direction * theta_dot): a state is in the barrier, certified running, "
               "when g(u) <= w <= barrier_top, g the linear interpolation of barrier_g on the "
               "uniform grid of u over [barrier_theta0, barrier_theta0 + 2*pi], u reduced "
               "mod 2*pi"}
#: Format 4: the running barrier's attributes of a ``/limit_cycle`` node, with their units
#: (written as ``<name>_units`` attributes, like ``period_units``).
BARRIER_ATTRS = {"barrier_theta0": "rad", "barrier_top": "rad s-1", "barrier_direction": "1"}


def with_barrier(cycle: xr.Dataset, barrier) -> xr.Dataset:
    """A ``/limit_cycle`` node ``cycle`` with format 4's running barrier added: ``barrier``
    is any object with ``theta0`` [rad], ``g`` [rad s-1], ``top`` [rad s-1] and
    ``direction`` (+1/-1), e.g. :class:`atlas.physics.barrier.RunningBarrier`."""
    g = np.asarray(barrier.g, np.float64)
    attrs = {"barrier_theta0": float(barrier.theta0), "barrier_top": float(barrier.top),
             "barrier_direction": np.int8(barrier.direction)}
    attrs.update({f"{name}_units": units for name, units in BARRIER_ATTRS.items()})
    return cycle.assign(barrier_g=(BARRIER_DIM, g, BARRIER_G)).assign_attrs(attrs)


def not_an_atlas(path, attrs: dict, what: str, why: str = "", xarray: str = "") -> str:
    """The one line for a file of format ``what`` ("an HDF5 file") that is not an atlas file
    (``why``, appended): where it is a stability study (``atlas stability``'s file), how to
    read that instead (``xarray``: the xarray call that opens it, ``{path}`` for its path)."""
    if attrs.get("atlas_schema") == STUDY_SCHEMA:
        return (f"{path}: a stability study, not an atlas file; `atlas info {path}` and "
                f"`atlas plot {path}` read it, and in Python "
                f"atlas.store.study.open_study('{path}') or {xarray.format(path=path)}")
    return f"{path}: {what}, but not an atlas{why}"
