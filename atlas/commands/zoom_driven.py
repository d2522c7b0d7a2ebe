"""``atlas zoom`` of a driven pendulum's atlas: the config lines of its parameter point.

:func:`driven_lines` reads the point that ``amplitude``, ``frequency``, ``phase`` (and α, ω0,
τ) select, as ``atlas orbit`` does (:func:`atlas.commands.orbit_driven.open_driven_point`),
and writes the ``pendulum`` section with its drive and the ``integrator`` section: the file's
dt (= T/N), t_max, period bound, and the window its attractors were searched in
(``drive.search_window``), so that the zoomed atlas finds the same attractors, numbered
alike, however small its own window: a tiny window alone would seed only the basins that
cross it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from atlas.models.driven.description import MAX_PERIOD

__all__ = ["driven_lines"]


def driven_lines(path: Path, number: Callable[[float], str], **asked: float | None
                 ) -> list[str]:
    """The ``pendulum:`` lines, an empty line and the ``integrator:`` lines of the zoom
    config of the driven atlas ``path`` at the point ``asked`` selects (``number``: how a
    float is written)."""
    from atlas.commands.orbit_driven import open_driven_point
    from atlas.store.reader import describe

    point = open_driven_point(path, **asked)
    try:
        params, group, t_max = point.params, point.group, point.t_max
        dt = float(point.tree.attrs.get("dt", point.labeller.drive.dt))
        stored = describe(path)["config"] or {}
        grid = stored.get("grid") or {}
        window = group.attrs.get("search_window")
        if window is None:  # a file from before the window was stored: its grid's
            window = [grid["theta0"]["start"], grid["theta0"]["stop"],
                      grid["theta_dot0"]["start"], grid["theta_dot0"]["stop"]]
        window = np.asarray(window, np.float64).ravel()
        max_period = int(group.attrs.get("max_period", MAX_PERIOD))
    finally:
        point.tree.close()
    n = number
    return [
        "pendulum:",
        f"  alpha: {n(params['alpha'])}    # damping α [1/s]",
        f"  omega0: {n(params['omega0'])}    # natural frequency ω0 [rad/s]",
        f"  torque: {n(params.get('torque', 0.0))}    # constant torque τ [rad/s²]",
        "  drive:    # A cos(Ω t + φ), and where the file's attractors were searched for",
        f"    amplitude: {n(params['amplitude'])}    # A [rad/s²]",
        f"    frequency: {n(params['frequency'])}    # Ω [rad/s]",
        f"    phase: {n(params.get('phase', 0.0))}    # φ [rad]",
        f"    max_period: {max_period}",
        f"    search_window: {{theta0: [{n(window[0])}, {n(window[1])}], "
        f"theta_dot0: [{n(window[2])}, {n(window[3])}]}}",
        "",
        "integrator:",
        f"  dt: {n(dt)}    # RK4 step [s]: the drive period over N steps",
        f"  t_max: {n(t_max)}    # [s]",
    ]
