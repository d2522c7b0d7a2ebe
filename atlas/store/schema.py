"""The atlas file's schema, written once: variables, dtypes, fills, chunks, CF attributes.

Every format (:mod:`atlas.store.hdf5`, :mod:`atlas.store.zarrformat`) writes, and
:mod:`atlas.store.validate` checks, what is declared here: the basin map
(:data:`MAP_VARIABLES`: ``attractor`` int16 with ``_FillValue``, ``status`` int8 with CF
flags from :mod:`atlas.status`, ``t_trap`` float32 [s], ``boundary_distance`` float32; dims
``theta_dot0``, ``theta0`` after the swept parameters, one chunk per tile), the summary
(:data:`BASIN_VARIABLES` over ``k``, :data:`POINT_VARIABLES` per parameter point,
:func:`summary_dataset`), and format 4's certificate (:data:`BARRIER_G`,
:data:`BARRIER_ATTRS` in each ``/limit_cycle`` node, ``trap_energy_cap`` per point: the
running barrier and the trap level the labels were certified with). Conventions: CF-1.10
(units as UDUNITS strings, "1" for counts and fractions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.layout import Layout
from atlas.status import ATTRACTOR_FILL, IN_FILE, STATUS_MEANINGS

__all__ = ["FORMAT_VERSION", "OLDEST_FORMAT", "CERTIFICATE_FORMAT", "SCHEMA", "STUDY_SCHEMA",
           "not_an_atlas",
           "MapVariable",
           "LABEL_VARIABLES",
           "MAP_VARIABLES", "FILLS", "STATUS_FLAGS", "chunks_of", "BASIN_VARIABLES",
           "POINT_VARIABLES", "CERTIFICATE_POINT_VARIABLES", "summary_dataset",
           "summary_tree", "BARRIER_DIM", "BARRIER_G", "BARRIER_ATTRS", "with_barrier"]

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

#: ``status``'s CF flags and comment, from :data:`atlas.status.STATUS_MEANINGS` and
#: :data:`atlas.status.IN_FILE`.
STATUS_FLAGS = {"flag_values": np.array(list(STATUS_MEANINGS), np.int8),
                "flag_meanings": " ".join(STATUS_MEANINGS.values()),
                "comment": "; ".join(f"{STATUS_MEANINGS[code]}: {text}"
                                     for code, text in IN_FILE.items())}


@dataclass(frozen=True)
class MapVariable:
    """One variable of the basin map: its stored dtype, its ``_FillValue`` (None: none),
    the value that pads a tile's edge chunk, and its CF attributes."""

    dtype: type
    fill: object
    padding: object
    attrs: dict


#: The basin map's variables, in file order.
MAP_VARIABLES = {
    "attractor": MapVariable(np.int16, ATTRACTOR_FILL, ATTRACTOR_FILL, {
        "long_name": "index k of the attractor (theta* + 2*pi*k, 0) reached, "
                     "theta* = asin(torque/omega0^2)",
        "units": "1", "comment": "fill value where no well label applies (status unresolved, "
                                 "nonfinite, running or running_near_boundary)"}),
    "status": MapVariable(np.int8, None, np.int8(0), {
        "long_name": "labelling status", "units": "1", **STATUS_FLAGS}),
    "t_trap": MapVariable(np.float32, np.float32(np.nan), np.float32(np.nan), {
        "long_name": "time at which the orbit's label was certified", "units": "s",
        "comment": "status trapped or near_boundary: trapped in its well; running or "
                   "running_near_boundary: in the running barrier; NaN where no label"}),
    "boundary_distance": MapVariable(np.float32, np.float32(np.nan), np.float32(np.nan), {
        "long_name": "Euclidean distance in the (theta, theta_dot) plane to the nearest basin "
                     "boundary",
        "units": "1", "comment": "rad (theta) and rad s-1 (theta_dot) as one Euclidean unit; "
        "boundaries are the stable manifolds of the saddles integrated by DOP853 (rtol 1e-13)"}),
}
#: The map variables every atlas file has (files before boundary_distance lack only it).
LABEL_VARIABLES = ("attractor", "status", "t_trap")
#: The padding of each map variable (a tile's edge chunk; the label arrays' fill values).
FILLS = {name: var.padding for name, var in MAP_VARIABLES.items()}


def chunks_of(layout: Layout) -> tuple[int, ...]:
    """The map variables' chunks: one per tile (one parameter point, a band of whole rows)."""
    return (*(1 for _ in layout.swept), layout.chunk_rows, layout.theta0.size)


#: Per-basin summary variables (dims: the parameter dims, then ``k``; units "1").
BASIN_VARIABLES = {
    "basin_fraction_exact": {
        "long_name": "area fraction of the window in the basin of k",
        "comment": "from the exact basin boundaries (stable manifolds integrated by DOP853, "
                   "rtol 1e-13): integral of the clipped boundary curves over theta"},
    "basin_fraction_exact_error": {
        "long_name": "error estimate of basin_fraction_exact",
        "comment": "change of the result from rtol 1e-12 to 1e-13 (about 10x the error)"},
    "basin_fraction": {
        "long_name": "fraction of the grid points labelled k (a count, not an area)"},
    "basin_fraction_grid_error_bound": {
        "long_name": "bound on |basin_fraction - basin_fraction_exact|",
        "comment": "from the grid cells: a certified cell farther than its half-diagonal "
                   "from every boundary counts |1/N - a/A|, every other cell max(1/N, a/A) "
                   "in each basin it may meet; first order in the cell size"},
    "basin_fraction_grid_error": {
        "long_name": "measured |basin_fraction - basin_fraction_exact|"},
}
#: Per-parameter-point summary variables (dims: the parameter dims; units "1" unless given).
POINT_VARIABLES = {
    "unresolved_fraction": {"long_name": "fraction of the grid without a well label "
                                         "(unresolved or nonfinite)"},
    "certified_fraction": {"long_name": "fraction of the grid whose label is certified for "
                                        "the exact equation (status trapped)"},
    "running_fraction": {"long_name": "fraction of the grid labelled running (a count, not "
                                      "an area)"},
    "running_fraction_exact": {"long_name": "area fraction of the window in the running "
                                            "basin, from the exact basin boundaries"},
    "running_fraction_exact_error": {"long_name": "error estimate of "
                                                  "running_fraction_exact"},
    "running_fraction_grid_error_bound": {"long_name": "bound on |running_fraction - "
                                                       "running_fraction_exact|"},
    "d_cert": {"long_name": "distance to the basin boundaries beyond which RK4 labels are "
                            "certified for the exact equation",
               "comment": "10 x (boundary shift + bisection tol + reference error); NaN: "
                          "not measured (separatrices disabled), no label certified"},
    "boundary_shift": {"long_name": "largest distance of the RK4 map's basin boundary "
                                    "(bisected) from the exact one"},
    "boundary_reference_error": {"long_name": "error estimate of the DOP853 basin "
                                              "boundaries (change from rtol 1e-12 to 1e-13)"},
    "trap_margin": {"long_name": "relative safety margin m of the energy trap"},
    "side_mismatches": {"long_name": "labels farther than d_cert from every boundary whose "
                                     "RK4 label differs from the exact side (expected 0)"},
    "trap_energy_cap": {"units": "rad2 s-2", "long_name": "energy cap of the energy trap",
                        "comment": "a state of well k is trapped when its energy above the "
                                   "rest state E_k < trap_energy_cap; -inf where no well can "
                                   "trap (|torque| >= omega0^2). From format 4"},
}
#: The summary variables that format 4 added (absent from files of format 3).
CERTIFICATE_POINT_VARIABLES = ("trap_energy_cap",)


def summary_dataset(layout: Layout, points: list[dict]) -> xr.Dataset:
    """The summary of every parameter point (``points`` in the order of ``layout``'s points,
    each a dict of :data:`BASIN_VARIABLES` over its own ``k`` and :data:`POINT_VARIABLES`):
    per-basin variables over ``k`` (the union of every point's basins, 0 where a basin is
    absent) and per-point scalars, both with the parameter dims leading."""
    ks = sorted({int(k) for p in points for k in p["k"]}) or [0]
    lead, lead_dims = layout.parameter_shape, layout.swept
    data = {}
    for name, attrs in BASIN_VARIABLES.items():
        table = np.zeros((len(points), len(ks)))
        for row, p in zip(table, points):
            values = np.asarray(p[name], float)
            if values.size and np.isnan(values).all():
                row[:] = np.nan  # not computed for this point (no exact boundaries)
            row[np.searchsorted(ks, p["k"])] = values
        data[name] = ((*lead_dims, "k"), table.reshape(*lead, len(ks)), {"units": "1", **attrs})
    for name, attrs in POINT_VARIABLES.items():
        values = np.array([p[name] for p in points], np.float64).reshape(lead)
        data[name] = (lead_dims, values, {"units": "1", **attrs})
    return xr.Dataset(data, coords={"k": ("k", np.array(ks, np.int16), {
        "long_name": "attractor index: the rest state (theta* + 2*pi*k, 0), "
                     "theta* = asin(torque/omega0^2)", "units": "1"})})


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
