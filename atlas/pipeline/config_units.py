"""Units in a config: θ is in radians, and a θ0 window that looks like degrees (an end at
±90, ±180, …, or more than eight turns) gets a warning with the window in radians as a hint.
"""

from __future__ import annotations

import math
from fractions import Fraction

__all__ = ["radians_warning", "RADIANS_WARNING_TURNS", "DEGREE_LIKE_ENDS"]

#: A θ0 window [rad] wider than this many turns (2π rad each) gets a warning that θ0 is in
#: radians: the default window spans 3 turns, an essay figure at most 2.
RADIANS_WARNING_TURNS = 8
#: Window ends [rad] that look like degrees: a quarter, a half, three quarters, one and two
#: turns in degrees.
DEGREE_LIKE_ENDS = (90.0, 180.0, 270.0, 360.0, 720.0)


def _in_pi(degrees: float) -> str:
    """``degrees`` (a whole number) in radians as a π expression where it is a simple
    fraction of π (90 → "pi/2", -180 → "-pi", 360 → "2pi"), else as a number [rad]."""
    ratio = Fraction(round(degrees), 180)
    if ratio.denominator > 12:
        return f"{math.radians(degrees):.6g}"
    if ratio == 0:
        return "0"
    factor = {1: "", -1: "-"}.get(ratio.numerator, str(ratio.numerator))
    return f"{factor}pi" + (f"/{ratio.denominator}" if ratio.denominator > 1 else "")


def radians_warning(cfg) -> str | None:
    """The warning, if any, that the θ0 window of ``cfg`` (a
    :class:`~atlas.pipeline.config.Config`) may have been written in degrees: it
    spans more than :data:`RADIANS_WARNING_TURNS` turns, or an end is one of
    :data:`DEGREE_LIKE_ENDS` (±90, ±180, …); with the window in radians as a hint ("did you
    mean -pi/2 … pi/2?") where both ends are whole numbers. None where ``check_radians``
    is false, or where the model's position axis is not an angle. A warning, not an error:
    such a window is valid, only unlikely. (:attr:`Config.warnings` adds how to silence
    it.)"""
    if cfg.description.axes[0].units != "rad":
        return None
    start, stop = cfg.grid.theta0.start, cfg.grid.theta0.stop
    turns = (stop - start) / (2 * math.pi)
    looks_like_degrees = any(abs(end) in DEGREE_LIKE_ENDS for end in (start, stop))
    if not cfg.check_radians or (turns <= RADIANS_WARNING_TURNS and not looks_like_degrees):
        return None
    hint = ""
    if float(start).is_integer() and float(stop).is_integer():
        hint = f"; did you mean {_in_pi(start)} … {_in_pi(stop)}?"
    return (f"grid.theta0: θ0 is in radians: the window {start:g} … {stop:g} spans "
            f"{turns:.1f} turns (a turn is 2pi = 6.283 rad){hint}")
