"""``atlas orbit``'s text: one orbit's label and the certificate that proves it, in lines.

Each line starts with a fixed-width key (``orbit``, ``label``, ``t_trap``, ``certificate``,
``exact``, ``file``) and says, with the numbers, what was tested: the (tilted) energy trap
E_k < cap between the well's saddles, or the running barrier ĝ(σθ) ≤ σθ̇ ≤ top; whether
:func:`atlas.label` agrees; the distance to the exact basin boundaries against d_cert; and
the atlas file's stored label at the nearest grid point. Numbers in, text out: nothing here
computes a label.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.boundaries.basins import RUNNING_SIDE
from atlas.commands.orbit_integrate import Orbit
from atlas.physics.pendulum import Pendulum
from atlas.status import NONFINITE, RUNNING, STATUS_MEANINGS, TRAPPED

__all__ = ["header_line", "label_lines", "exact_line", "file_line", "outside_line"]

TWO_PI = 2.0 * math.pi
#: The name of each status code (as the file's CF flag_meanings say).


def header_line(orbit: Orbit) -> str:
    """What was integrated: the initial condition, the parameters, dt, t_max, the method."""
    tilt = f", torque = {orbit.torque:g} rad/s^2" if orbit.torque else ""
    return (f"orbit        from theta0 = {orbit.theta0:.10g} rad, theta_dot0 = "
            f"{orbit.theta_dot0:.10g} rad/s; alpha = {orbit.alpha:g} 1/s, omega0 = "
            f"{orbit.omega0:g} rad/s{tilt}, dt = {orbit.dt:g} s, t_max = {orbit.t_max:g} s, "
            f"method {orbit.method}")


def label_lines(orbit: Orbit, kernel_status: int, kernel_k: int) -> list[str]:
    """The label, t_trap and the certificate of ``orbit``, and whether :func:`atlas.label`
    (status ``kernel_status``, well ``kernel_k``) says the same."""
    same = kernel_status == orbit.status and (orbit.k is None or kernel_k == orbit.k)
    said_k = "" if kernel_status != TRAPPED else f", k = {kernel_k}"
    agree = "the same as atlas.label" if same else (
        f"atlas.label says status {STATUS_MEANINGS[kernel_status]}{said_k}: a point on a "
        "knife edge, decided by rounding")
    if orbit.status == TRAPPED:
        return _trapped_lines(orbit, agree)
    if orbit.status == RUNNING:
        return _running_lines(orbit, agree)
    why = ("NaN or inf met" if orbit.status == NONFINITE else
           "neither trapped nor certified running by t_max" if orbit.barrier is not None else
           "not trapped by t_max")
    return [f"label        none: {STATUS_MEANINGS[orbit.status]} ({why}) ({agree})"]


def _rest(k: int) -> str:
    """"theta*", "theta* + 2pi", "theta* - 4pi": the rest state of well k with a torque."""
    return "theta*" if k == 0 else f"theta* {'-' if k < 0 else '+'} {_pi(abs(2 * k))}"


def _trapped_lines(orbit: Orbit, agree: str) -> list[str]:
    k = orbit.k
    if orbit.torque == 0.0:
        phi = orbit.theta[orbit.trap_index] - TWO_PI * k
        return [
            f"label        k = {k:+d}: settles at ({_pi(2 * k)}, 0) ({agree})",
            f"t_trap       {orbit.t_trap:.2f} s",
            f"certificate  energy trap at t_trap: |theta - 2pi k| = {abs(phi):.4f} <= pi and "
            f"E_k = {orbit.energy:.10g} < 2 omega0^2 (1 - m) = {orbit.cap:.10g} "
            f"(m = {orbit.margin:.2g}): the RK4 map's orbit never leaves well {k:+d}",
        ]
    s = orbit.rest_angle
    phi = orbit.theta[orbit.trap_index] - TWO_PI * k
    lower = Pendulum(orbit.alpha, orbit.omega0, orbit.torque).saddle_energy
    return [
        f"label        k = {k:+d}: settles at ({_rest(k)}, 0) = ({s + TWO_PI * k:.10g}, 0), "
        f"theta* = asin(torque/omega0^2) = {s:.10g} ({agree})",
        f"t_trap       {orbit.t_trap:.2f} s",
        f"certificate  tilted energy trap at t_trap: theta - 2pi k = {phi:.4f} in "
        f"[-pi - theta*, pi - theta*) (between the well's two saddles) and E_k = "
        f"{orbit.energy:.10g} < dE (1 - m) - rounding = {orbit.cap:.10g} (dE = {lower:.10g}, "
        f"the lower saddle's energy above the rest state; m = {orbit.margin:.2g}): the RK4 "
        f"map's orbit never leaves well {k:+d}",
    ]


def _running_lines(orbit: Orbit, agree: str) -> list[str]:
    b, d = orbit.barrier, orbit.direction
    i = orbit.trap_index
    th, v = float(orbit.theta[i]), float(orbit.theta_dot[i])
    m = b.g.size - 1  # ĝ(σθ) (for the text: the test itself is the kernels')
    lower = float(np.interp((d * th - b.theta0) % TWO_PI, np.linspace(0.0, TWO_PI, m + 1), b.g))
    cycle = ""
    if orbit.cycle is not None:
        cycle = (f", period {orbit.cycle.period:.6g} s, mean theta_dot "
                 f"{orbit.cycle.mean_theta_dot:.6g} rad/s")
    verified = ", the run's, as its file stores it"  # a file's barrier (format 4)
    if getattr(b, "verified_margin", None) is not None:  # built here: the record of its check
        step = "" if getattr(b, "dt", None) is None else f" for the RK4 step dt = {b.dt:g} s"
        verified = (f", flow across the lower curve verified >= {b.verified_margin:.3g} "
                    f"rad/s^2{step}")
    frame = "theta_dot" if d > 0 else "-theta_dot"
    where = "g(theta)" if d > 0 else "g(-theta)"
    return [
        f"label        running: converges to the running limit cycle (direction {d:+d}"
        f"{cycle}) ({agree})",
        f"t_trap       {orbit.t_trap:.2f} s (certified running)",
        f"certificate  running barrier at t_trap: (theta, theta_dot) = ({th:.4f}, {v:.4f}) "
        f"with {where} = {lower:.6g} <= {frame} = {d * v:.6g} <= top = {b.top:.6g} rad/s "
        f"(lower curve of {b.g.size - 1} segments{verified}): the RK4 map's orbit stays in "
        f"the band around the limit cycle (direction {d:+d})",
    ]


def _pi(n: int) -> str:
    return "0" if n == 0 else f"{'-' if n < 0 else ''}{'' if abs(n) == 1 else abs(n)}pi"


def _basin_name(side: int) -> str:
    return "the running basin" if side == RUNNING_SIDE else f"k = {side:+d}"


def exact_line(orbit: Orbit, distance: float, side: int, d_cert: float) -> str:
    """The certificate for the exact equation: the orbit's ``distance`` to the exact basin
    boundaries, the exact ``side`` (a well k, or RUNNING_SIDE) against the RK4 label, and
    ``d_cert`` (NaN: not known without a file)."""
    where = ("no basin boundary: without rest states (|torque| > omega0^2) the running "
             "cycle attracts every orbit" if math.isinf(distance) else
             "Certifier: distance to the exact basin boundaries, the DOP853 stable "
             "manifolds" + (" of the tilted saddles" if orbit.torque else ""))
    own = RUNNING_SIDE if orbit.status == RUNNING else orbit.k
    if side != own:
        verdict = (f"the exact equation's side of the boundaries is "
                   f"{_basin_name(side)}, not the RK4 label's: certified for the RK4 map only")
    elif d_cert == d_cert:
        verdict = (f"{'>' if distance > d_cert else '<='} d_cert = {d_cert:.2g}: "
                   + ("certified for the exact equation" if distance > d_cert else
                      "certified for the RK4 map only"))
    else:
        verdict = ("on the exact side; d_cert needs the RK4 map's boundary shift, which "
                   "`atlas run` measures (give an atlas file with separatrices) — "
                   "certified for the RK4 map only until then")
    return f"exact        boundary distance {distance:.4g} ({where}); {verdict}"


def file_line(nearest: dict) -> str:
    """The atlas file's stored label at the grid point nearest the initial condition
    (:func:`atlas.commands.orbit_file.nearest_grid_point`)."""
    grid_k = "none" if nearest["k"] is None else f"{nearest['k']:+d}"
    return (f"file         nearest grid point theta0 = {nearest['theta0']:.6g}, theta_dot0 = "
            f"{nearest['theta_dot0']:.6g}: stored k = {grid_k}, status "
            f"{STATUS_MEANINGS.get(nearest['status'], nearest['status'])}, t_trap "
            f"{nearest['t_trap']:.2f} s, boundary distance {nearest['distance']:.4g}"
            + ("" if nearest["inside"] else " (the orbit starts outside the atlas window)"))


def outside_line(point) -> str:
    """The warning printed first when the initial condition lies outside the atlas window
    (``point``: the parameter point's map, with coordinates theta0 and theta_dot0): the
    stored label shown is that of the nearest edge point, not of the orbit."""
    th, v = point["theta0"].values, point["theta_dot0"].values
    return (f"warning      the initial condition lies outside the atlas window theta0 in "
            f"[{th[0]:.6g}, {th[-1]:.6g}] rad, theta_dot0 in [{v[0]:.6g}, {v[-1]:.6g}] "
            f"rad/s: the file's label below is the nearest edge point's, not the orbit's")
