"""The driven pendulum's description: θ̈ + 2αθ̇ + ω0² sin θ = τ + A cos(Ω t + φ), its
parameters (α, ω0, τ, then the drive's A, Ω, φ), its grid (θ0, θ̇0 at t = 0, as the
pendulum's), the codes of ``status`` and the variables it stores.

Labels are attractors of the stroboscopic map P (one drive period T = 2π/Ω of RK4 with
dt = T/N): ``attractor`` = i indexes the ``/attractors`` group of the point (its period p in
drive periods, winding, kind, points on P, Floquet multipliers). What each status claims is
what its test shows, no more: see :data:`IN_FILE`.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.models.base import MapVariable, Model, status_flags
from atlas.models.pendulum.description import AXES
from atlas.models.pendulum.description import PARAMETERS as PENDULUM_PARAMETERS

__all__ = ["PARAMETERS", "CONVERGED", "UNRESOLVED", "NONFINITE", "NEAR", "CHAOTIC",
           "STATUSES", "IN_FILE", "ATTRACTOR_FILL", "MAX_PERIOD", "LONGEST_PERIOD", "WHOLE",
           "steps_per_period", "DRIVEN_PENDULUM", "CONFIRM", "confirm_returns",
           "stored_confirm"]

#: The parameters: the pendulum's, then the drive's (dims in this order).
PARAMETERS = {
    **PENDULUM_PARAMETERS,
    "amplitude": ("rad s-2", "amplitude A of the periodic torque A cos(frequency t + phase)"),
    "frequency": ("rad s-1", "angular frequency of the periodic torque"),
    "phase": ("rad", "phase of the periodic torque at t = 0"),
}

#: A return of the orbit to P came within the capture radius of a stable periodic orbit of P,
#: one whose capture ball was seen to map into itself (every sampled state of its circle
#: mapped inside by P^(p·m), some m ≤ 8): its returns every p·m periods stay in the ball, which
#: holds the orbit's point (``confirm`` = 1).
CONVERGED = 0
#: No label by t_max.
UNRESOLVED = 1
#: A NaN or inf state was met.
NONFINITE = 2
#: Within the capture radius of a periodic orbit of P for ``confirm`` returns in a row, where
#: no contraction was seen (the radius is the orbit's spacing only).
NEAR = 3
#: On a chaotic attractor: its returns stayed inside the attractor's recorded cloud of
#: points on P for ``confirm`` returns in a row.
CHAOTIC = 4

STATUSES = {CONVERGED: "converged", UNRESOLVED: "unresolved", NONFINITE: "nonfinite",
            NEAR: "near", CHAOTIC: "chaotic"}
IN_FILE = {
    CONVERGED: "a return came within the capture radius of a stable periodic orbit of the "
               "RK4 stroboscopic map, whose capture ball was seen to map into itself under "
               "P^(p m), m <= 8, on sampled states of its circle, so that the orbit's "
               "returns every p m periods stay in it (shown for the RK4 map by sampling, "
               "not proven; not certified for the exact equation)",
    UNRESOLVED: "no label decided before t_max",
    NONFINITE: "a NaN or inf state was met",
    NEAR: "within the capture radius of a periodic orbit of the RK4 stroboscopic map for "
          "confirm returns in a row, whose capture ball was not seen to map into itself",
    CHAOTIC: "on a chaotic attractor of the RK4 stroboscopic map: within its recorded cloud "
             "of points for confirm returns in a row (a recurrent, non-periodic attractor)",
}

#: Returns of P in a row within an attractor's capture radius that decide a label, where
#: its capture ball was not seen to map into itself (a ``near`` or ``chaotic`` label). One
#: return decides a ``converged`` label: its ball was seen to map into itself under P^(p·m)
#: (sampled, :func:`atlas.models.driven.attractors.contracts`), so the orbit's returns every
#: p·m periods stay in the ball with the orbit's point; eight returns in a row would add no
#: evidence the test has not (tests/models/test_driven_pendulum.py: the same labels).
CONFIRM = 8


def confirm_returns(statuses: np.ndarray) -> np.ndarray:
    """The returns in a row within its capture radius that decide each attractor's label
    (int64 per attractor, from the status its labels get): 1 for a ``converged`` one,
    :data:`CONFIRM` otherwise."""
    return np.where(np.asarray(statuses) == CONVERGED, 1, CONFIRM).astype(np.int64)


def stored_confirm(group) -> np.ndarray:
    """The returns in a row that decided each attractor's labels in a file (int64 per
    attractor): its ``/attractors`` node's ``confirm``, or (a file written before that
    variable, with one rule for all) the node's ``confirm`` attribute."""
    n = group.sizes.get("attractor", 0)
    if "confirm" in group.data_vars:
        stored = np.asarray(group["confirm"].values)
    else:
        stored = np.full(n, group.attrs.get("confirm", CONFIRM))
    if not (stored.shape == (n,) and np.all(np.isfinite(stored.astype(float)))
            and np.all(stored >= 1) and np.all(stored == np.round(stored))):
        from atlas.errors import InputFileError

        raise InputFileError(f"/attractors confirm holds {stored.tolist()}: the returns in a "
                             "row that decide a label are whole numbers >= 1 (a damaged file?)")
    return stored.astype(np.int64)


#: The largest period [drive periods] of the periodic attractors searched for, by default
#: (``pendulum.drive.max_period``), and the largest a config may ask for (the search reads
#: a period from the seeds' last returns, of which it records more than four times this).
MAX_PERIOD = 8
LONGEST_PERIOD = 48

#: How close T/dt must come to a whole number N (relative): dt = 2pi/200 written in a config
#: is T/200 of Ω = 1 to rounding, dt = 0.0314 is not.
WHOLE = 1e-9


def steps_per_period(frequency: float, dt: float) -> int | None:
    """N where ``dt`` [s] is the drive period T = 2π/Ω (``frequency`` [rad s⁻¹]) over N whole
    steps, so that every return to P falls on a step; None where it is not."""
    n = round(2.0 * math.pi / frequency / dt)
    return n if n >= 1 and abs(n * dt * frequency / (2.0 * math.pi) - 1.0) <= WHOLE else None


#: ``attractor`` where no label applies (int16; also the file's _FillValue).
ATTRACTOR_FILL = int(np.iinfo(np.int16).min)

DRIVEN_PENDULUM = Model(
    name="driven_pendulum",
    title="periodically driven damped pendulum",
    parameters=PARAMETERS,
    axes=AXES,
    section="pendulum",
    statuses=STATUSES,
    in_file=IN_FILE,
    map_variables={
        "attractor": MapVariable(np.int16, ATTRACTOR_FILL, ATTRACTOR_FILL, {
            "long_name": "index of the attractor of the stroboscopic map reached (the "
                         "attractor dim of /attractors)", "units": "1",
            "comment": "fill value where no label applies (status unresolved or "
                       "nonfinite)"}),
        "status": MapVariable(np.int8, None, np.int8(0), {
            "long_name": "labelling status", "units": "1",
            **status_flags(STATUSES, IN_FILE)}),
        "t_trap": MapVariable(np.float32, np.float32(np.nan), np.float32(np.nan), {
            "long_name": "time at which the orbit's label was decided", "units": "s",
            "comment": "whole drive periods; NaN where no label"}),
        "changes_at_half_dt": MapVariable(np.int8, None, np.int8(0), {
            "long_name": "1 where the orbit labelled again with dt/2 reaches another "
                         "attractor (or none): a label that depends on the integrator",
            "units": "1", "flag_values": np.array([0, 1], np.int8),
            "flag_meanings": "same changed"}),
    },
    label_variables=("attractor", "status", "t_trap"),
    basin_variables={
        "basin_fraction": {"long_name": "fraction of the grid points labelled k (a count, "
                                        "not an area)"},
        "basin_fraction_shifted_spread": {
            "long_name": "spread of basin_fraction over the grid's four interleaved "
                         "half-resolution grids (row and column parity), as an error of "
                         "the whole grid's fraction: their standard deviation over 2"},
        "basin_fraction_error": {
            "long_name": "uncertainty of basin_fraction as an estimate of the basin's share "
                         "of the window",
            "comment": "the larger of the binomial standard error sqrt(f (1 - f) / N) over "
                       "the grid's N points and basin_fraction_shifted_spread (what the "
                       "grid's own lattice does to the count), plus |f - f(dt/2)|, the "
                       "change of the share when every point is labelled again with half "
                       "the step"},
    },
    point_variables={
        "unresolved_fraction": {"long_name": "fraction of the grid without a label "
                                             "(unresolved or nonfinite)"},
        "changed_at_half_dt_fraction": {"long_name": "fraction of the grid whose label "
                                                     "changes when dt is halved"},
        "attractor_count": {"long_name": "number of attractors of the stroboscopic map "
                                         "found in the window"},
    },
    attractor="the attractor of the stroboscopic map with this index in /attractors",
    planner="atlas.models.driven.plan",
    labelled=(CONVERGED, NEAR, CHAOTIC),
    positive=("alpha", "omega0", "frequency"),
)
