"""The driven pendulum's planner (:class:`atlas.models.base.Planner`): its config section
(``pendulum:`` with ``drive``), its checks, and the entry points that prepare its parameter
points (:mod:`atlas.models.driven.points`, imported when a run needs it).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from atlas.models.driven.description import steps_per_period
from atlas.pipeline.config_sections import PendulumConfig

if TYPE_CHECKING:
    from atlas.pipeline.config import Config

__all__ = ["Section", "check", "check_study", "begin", "sample", "plan", "MIN_STEPS",
           "MIN_PERIODS", "MAX_STEPS", "MAX_PERIODS", "SEARCH_SPAN"]

#: The config section of its parameters: the pendulum's, with ``drive``.
Section = PendulumConfig
#: The fewest RK4 steps per drive period (dt = T/N is the config's dt or finer).
MIN_STEPS = 16
#: The fewest drive periods t_max must hold (a label needs the orbit's returns to settle).
MIN_PERIODS = 50
#: The most RK4 steps per drive period (a finer dt adds nothing RK4's fourth order does not
#: give at a thousandth of the cost, and the attractors' search costs N per period).
MAX_STEPS = 4096
#: The most drive periods t_max may hold: each undecided orbit (and each sample of the
#: pre-flight estimate, which has no attractor to stop it) runs that long.
MAX_PERIODS = 20_000
#: The widest ``drive.search_window`` a config may give, in widths of its grid's window
#: (a zoom 1e-6 wide searches its atlas's window: 1e6 times as wide, and more).
SEARCH_SPAN = 1e12
def _not_whole(dt: float, frequency: float) -> str:
    """The error for a ``dt`` [s] that is not T/N: the two nearest that are."""
    period = 2.0 * math.pi / frequency
    n = max(1, math.floor(period / dt))
    return (f"integrator.dt: {dt:g} s is not the drive period T = 2π/Ω = {period:.6g} s "
            f"(Ω = {frequency:g} rad/s) over a whole number N of steps (a return to the "
            f"stroboscopic map must fall on a step): "
            f"N = {n + 1} gives dt = {period / (n + 1):.9g} s, N = {n} gives "
            f"{period / n:.9g} s")


def check(cfg: Config, study: bool) -> None:
    """The driven pendulum's checks across the config's sections (ValueError "key:
    problem")."""
    if study:
        check_study(cfg)
    if cfg.integrator.method != "rk4":
        raise ValueError("integrator.method: the driven pendulum is integrated by rk4")
    given, g = cfg.pendulum.drive.search_window, cfg.grid
    if given is not None:
        for name, (lo, hi), axis in (("theta0", given.theta0, g.theta0),
                                     ("theta_dot0", given.theta_dot0, g.theta_dot0)):
            if lo > axis.start or hi < axis.stop:
                raise ValueError(f"pendulum.drive.search_window.{name}: [{lo:g}, {hi:g}] "
                                 f"must contain the grid's [{axis.start:g}, {axis.stop:g}]")
            if hi - lo > SEARCH_SPAN * (axis.stop - axis.start):
                raise ValueError(f"pendulum.drive.search_window.{name}: [{lo:g}, {hi:g}] is "
                                 f"more than {SEARCH_SPAN:g} times as wide as the grid's "
                                 "window: its seeds would be too sparse to find anything")
    for point in cfg.pendulum.points:
        period = 2 * math.pi / point["frequency"]
        if steps_per_period(point["frequency"], cfg.integrator.dt) is None:
            raise ValueError(_not_whole(cfg.integrator.dt, point["frequency"]))
        if cfg.integrator.dt > period / MIN_STEPS:
            raise ValueError(f"integrator.dt: {cfg.integrator.dt:g} s is more than a "
                             f"{MIN_STEPS}th of the drive period {period:.4g} s")
        if cfg.integrator.dt < period / MAX_STEPS:
            raise ValueError(f"integrator.dt: {cfg.integrator.dt:g} s is less than a "
                             f"{MAX_STEPS}th of the drive period {period:.4g} s")
        if cfg.integrator.t_max < MIN_PERIODS * period:
            raise ValueError(f"integrator.t_max: {cfg.integrator.t_max:g} s holds fewer than "
                             f"{MIN_PERIODS} drive periods of {period:.4g} s")
        if cfg.integrator.t_max > MAX_PERIODS * period:
            raise ValueError(f"integrator.t_max: {cfg.integrator.t_max:g} s holds more than "
                             f"{MAX_PERIODS:,} drive periods of {period:.4g} s (an orbit "
                             "undecided by then would run that long)")


def check_study(cfg: Config) -> None:
    """A driven pendulum's study (:mod:`atlas.stability.driven`) follows its attractors
    along one swept parameter, increasing: two swept parameters, a sweep over Ω (whose
    bisections would need a dt = T/N at every frequency between), a search window of its own,
    the Gaussian perturbation and the tipping probabilities (the undriven study's) are
    refused (ValueError "key: problem")."""
    swept = cfg.pendulum.swept
    if len(swept) > 1:
        raise ValueError(f"pendulum: a driven pendulum's study follows its attractors along "
                         f"one swept parameter; this config sweeps {' and '.join(swept)}")
    if "frequency" in swept:
        raise ValueError("pendulum.drive.frequency: a driven study's bisections take "
                         "frequencies between the listed ones, at which dt is no whole "
                         "fraction of the drive period; sweep amplitude, alpha, omega0 or "
                         "torque")
    for name in swept:
        values = cfg.pendulum.values(name)
        if any(b <= a for a, b in zip(values, values[1:])):
            key = f"pendulum.{'drive.' if name in cfg.pendulum.DRIVE_NAMES else ''}{name}"
            raise ValueError(f"{key}: a driven study follows its attractors along increasing "
                             "values; list them in increasing order")
    if cfg.pendulum.drive.search_window is not None:
        raise ValueError("pendulum.drive.search_window: a driven study searches its "
                         "attractors in the grid's window; drop the key")
    stab = cfg.stability
    if stab is not None and stab.sigma_theta is not None:
        raise ValueError("stability.sigma_theta: the Gaussian perturbation is the undriven "
                         "pendulum's study; a driven one samples basin fractions only")
    if stab is not None and stab.tipping:
        raise ValueError("stability.tipping: tipping probabilities are the undriven "
                         "pendulum's study; a driven one samples basin fractions only")


def begin(cfg, layout) -> list:
    """Every point's drive and its steps per period
    (:func:`atlas.models.driven.points.begin`)."""
    from atlas.models.driven import points

    return points.begin(cfg, layout)


def sample(cfg, begun: list, p: int):
    """The ``p``-th point's map, to label sample orbits with (the pre-flight estimate): its
    drive with no attractor to reach (every sample runs to its t_max)."""
    from atlas.models.driven import points

    return points.DrivenPoint.searching(begun[p], cfg.integrator.t_max)


def plan(cfg, layout, begun: list, track=None):
    """Every point prepared (:func:`atlas.models.driven.points.plan`): its attractors found,
    their capture radius and contraction tested."""
    from atlas.models.driven import points

    return points.plan(cfg, layout, begun, track)
