"""The pendulum's description: θ̈ + 2αθ̇ + ω0² sin θ = τ, its parameters (α, ω0, τ), its grid
(θ0, θ̇0), the codes of ``status`` (:mod:`atlas.status`) and the variables it stores: the
basin map and the summary from the exact basin boundaries (essay sections 3–4)."""

from __future__ import annotations

import numpy as np

from atlas.models.base import Axis, MapVariable, Model, status_flags
from atlas.status import (
    ATTRACTOR_FILL,
    IN_FILE,
    NEAR_BOUNDARY,
    RUNNING,
    RUNNING_NEAR_BOUNDARY,
    STATUS_MEANINGS,
    TRAPPED,
)

__all__ = ["PARAMETERS", "AXES", "MAP_VARIABLES", "BASIN_VARIABLES", "POINT_VARIABLES",
           "PENDULUM"]

#: The physical parameters: name → (units, long_name). Their order is the order of the
#: leading dims of a parameter atlas.
PARAMETERS = {
    "alpha": ("s-1", "damping constant"),
    "omega0": ("rad s-1", "natural angular frequency"),
    "torque": ("rad s-2", "constant torque per unit moment of inertia"),
}

#: The grid of initial states: θ0 along columns, θ̇0 along rows.
AXES = (Axis("theta0", "rad", "initial angle", "θ0"),
        Axis("theta_dot0", "rad s-1", "initial angular velocity", "θ̇0"))

#: ``status``'s CF flags and comment, from :data:`atlas.status.STATUS_MEANINGS` and
#: :data:`atlas.status.IN_FILE`.
STATUS_FLAGS = status_flags(STATUS_MEANINGS, IN_FILE)

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

PENDULUM = Model(
    name="pendulum",
    title="damped pendulum with constant torque",
    parameters=PARAMETERS,
    axes=AXES,
    section="pendulum",
    statuses=STATUS_MEANINGS,
    in_file=IN_FILE,
    map_variables=MAP_VARIABLES,
    label_variables=("attractor", "status", "t_trap"),
    basin_variables=BASIN_VARIABLES,
    point_variables=POINT_VARIABLES,
    attractor="the rest state (theta* + 2*pi*k, 0), theta* = asin(torque/omega0^2)",
    planner="atlas.models.pendulum.plan",
    labelled=(TRAPPED, NEAR_BOUNDARY),
    running=(RUNNING, RUNNING_NEAR_BOUNDARY),
    positive=("alpha", "omega0"),
    since={"trap_energy_cap": 4},
)
