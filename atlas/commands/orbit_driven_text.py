"""``atlas orbit``'s text for a driven pendulum's orbit: the point, the drive, the label
with what its status claims, t_trap, the label at dt/2 and the file's stored label at the
nearest grid point, in lines.

Each line starts with a fixed-width key (``orbit``, ``drive``, ``label``, ``status``,
``t_trap``, ``dt/2``, ``file``), as the pendulum's (:mod:`atlas.commands.orbit_text`). Numbers
in, text out: nothing here computes a label.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from atlas.commands.orbit_text import outside_line
from atlas.models.driven.description import DRIVEN_PENDULUM, NONFINITE, stored_confirm
from atlas.views.info_driven import attractor_names

if TYPE_CHECKING:
    import xarray as xr

    from atlas.commands.orbit_driven import DrivenOrbit

__all__ = ["driven_lines", "attractor_text"]


def attractor_text(group: xr.Dataset, k: int | None) -> str:
    """"attractor #1 rotation, period 2, winding -2", "attractor #3 chaotic" or "no
    attractor", from the point's ``/attractors`` node, named as every key names it
    (:func:`atlas.views.info_driven.attractor_names`)."""
    if k is None:
        return "no attractor"
    return f"attractor {attractor_names(group)[k]}"


def _status(code: int) -> str:
    return DRIVEN_PENDULUM.statuses.get(code, str(code))


def _drive_line(orbit: DrivenOrbit, params: dict) -> str:
    d = orbit.drive
    tilt = f", torque = {d.torque:g} rad/s^2" if "torque" in params or d.torque else ""
    return (f"drive        alpha = {d.alpha:g} 1/s, omega0 = {d.omega0:g} rad/s{tilt}; "
            f"A cos(Omega t + phi) with A = {d.amplitude:g} rad/s^2, Omega = {d.frequency:g} "
            f"rad/s, phi = {d.phase:g} rad: T = 2pi/Omega = {d.period:.6g} s, RK4 with dt = "
            f"T/{d.steps_per_period} = {d.dt:.6g} s (the atlas's map), t_max = "
            f"{orbit.t_max:g} s ({int(orbit.t_max / d.period)} periods)")


def _label_lines(orbit: DrivenOrbit, group: xr.Dataset) -> list[str]:
    status = _status(orbit.status)
    meaning = DRIVEN_PENDULUM.in_file.get(orbit.status, "")
    if orbit.attractor is None:
        return [f"label        none ({status}; the atlas's rule, DrivenPoint.label)",
                f"status       {status}: {meaning}",
                "t_trap       none: " + (
                    "a state that is not finite was met" if orbit.status == NONFINITE else
                    f"no label after {orbit.periods} drive periods (t_max = "
                    f"{orbit.t_max:g} s)")]
    k = orbit.attractor
    floquet = ""
    if str(group["kind"].values[k]) == "periodic":
        moduli = group["floquet_modulus"].values[k]
        floquet = f", |Floquet multipliers| {moduli[0]:.3g}, {moduli[1]:.3g}"
    radius = float(group["capture_radius"].values[k])
    confirm = int(stored_confirm(group)[k])
    returns = (f"its return {orbit.periods} to P lies" if confirm == 1 else
               f"its returns to P {orbit.periods - confirm + 1} to {orbit.periods} lie")
    return [f"label        {attractor_text(group, k)}{floquet} (the atlas's rule, "
            "DrivenPoint.label)",
            f"status       {status}: {meaning}",
            f"t_trap       {orbit.t_trap:.2f} s = {orbit.periods} T: {returns} within the "
            f"capture radius {radius:.3g} of its points on P"]


def _half_line(orbit: DrivenOrbit, group: xr.Dataset) -> str:
    n = 2 * orbit.drive.steps_per_period
    at_half = f"{attractor_text(group, orbit.half_attractor)}, status {_status(orbit.half_status)}"
    if not orbit.changes_at_half_dt:
        return f"dt/2         the same label with dt = T/{n}: {at_half}"
    return (f"dt/2         changes: with dt = T/{n} the orbit reaches {at_half}: its label "
            "depends on the integrator")


def _file_line(nearest: dict, group: xr.Dataset) -> str:
    t_trap = nearest["t_trap"]
    return (f"file         nearest grid point theta0 = {nearest['theta0']:.6g}, theta_dot0 = "
            f"{nearest['theta_dot0']:.6g}: stored {attractor_text(group, nearest['attractor'])}"
            f", status {_status(nearest['status'])}, t_trap "
            + ("none" if math.isnan(t_trap) else f"{t_trap:.2f} s")
            + f", changes at dt/2: {'yes' if nearest['changes_at_half_dt'] else 'no'}"
            + ("" if nearest["inside"] else " (the orbit starts outside the atlas window)"))


def driven_lines(orbit: DrivenOrbit, params: dict, group: xr.Dataset, nearest: dict,
                 point: xr.Dataset) -> list[str]:
    """Every line of ``atlas orbit`` on a driven atlas: a warning first where the start lies
    outside the atlas window, then the orbit, the drive, its label, status and t_trap, the
    label at dt/2 and the file's at the nearest grid point."""
    lines = [] if nearest["inside"] else [outside_line(point)]
    return lines + [
        f"orbit        from theta0 = {orbit.theta0:.10g} rad, theta_dot0 = "
        f"{orbit.theta_dot0:.10g} rad/s at t = 0",
        _drive_line(orbit, params),
        *_label_lines(orbit, group),
        _half_line(orbit, group),
        _file_line(nearest, group),
    ]
