"""The pendulum's planner (:class:`atlas.models.base.Planner`): its config section
(``pendulum:``), the checks across the config's sections, and the entry points that prepare
its parameter points (:mod:`atlas.models.pendulum.points`, imported when a run needs it: a
config is validated without the physics).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from atlas.pipeline.config_sections import PendulumConfig

if TYPE_CHECKING:
    from atlas.pipeline.config import Config

__all__ = ["Section", "check", "begin", "sample", "plan"]

#: The config section of the pendulum's parameters (``pendulum:``).
Section = PendulumConfig


def check(cfg: Config, study: bool) -> None:
    """The pendulum's checks across the config's sections (ValueError "key: problem"), so
    that a valid config never fails after work began. A study (``study``) integrates no
    grid: it skips the grid run's checks of the integrator and the window's reach, and takes
    the saddle-node."""
    from atlas.labels.labelling import check_integration, check_torque_reach
    from atlas.labels.methods import lookup as lookup_method
    from atlas.labels.trap import CHECK_EVERY
    from atlas.limits import check_reach, check_separatrix_settings, check_study_window

    dt, t_max = cfg.integrator.dt, cfg.integrator.t_max
    g, pend = cfg.grid, cfg.pendulum
    if not lookup_method(cfg.integrator.method).running and any(pend.torques):
        raise ValueError(f"integrator.method: {cfg.integrator.method!r} is for the "
                         "pendulum without torque (the running certificate is established "
                         "for 'rk4' only); use method: rk4 with a torque")
    if study:
        stab = cfg.stability
        for key in ("samples", "seed"):
            if stab is not None and getattr(stab, key) is not None:
                raise ValueError(f"stability.{key}: the undriven pendulum's study is exact, "
                                 "from the stable manifolds (no samples); samples and seed "
                                 "are for a driven pendulum's study")
        try:
            check_study_window((g.theta0.start, g.theta0.stop),
                               (g.theta_dot0.start, g.theta_dot0.stop))
        except ValueError as exc:
            raise ValueError(f"grid.{exc}") from None
        swept = pend.swept
        if cfg.stability is not None and cfg.stability.tipping and (
                len(swept) != 1 or len(pend.values(swept[0])) < 2):
            over = (" and ".join(swept) if len(swept) != 1 else
                    f"one value of {swept[0]}") if swept else "no parameter"
            raise ValueError("stability.tipping: tipping probabilities are between "
                             "consecutive points of a 1-D study (one swept parameter); "
                             f"this study sweeps {over}")
        return
    theta_abs = max(abs(g.theta0.start), abs(g.theta0.stop))
    speed_abs = max(abs(g.theta_dot0.start), abs(g.theta_dot0.stop))
    for point in pend.points:
        a, w, t = point["alpha"], point["omega0"], point["torque"]
        if abs(t) == w * w:
            raise ValueError(
                f"pendulum.torque: |torque| = omega0^2 = {w * w:g} is the saddle-node "
                "bifurcation, where the rest state (pi/2, 0) is degenerate and atlas "
                "certifies no basin; take |torque| below or above omega0^2")
        try:
            check_integration(a, w, dt, t_max, torque=t)
        except ValueError as exc:
            raise ValueError(f"integrator.{exc}") from None
        if t:
            try:
                check_torque_reach(theta_abs, speed_abs, a, w, t, t_max + CHECK_EVERY * dt)
            except ValueError as exc:
                raise ValueError(f"grid: {exc}") from None
    try:
        check_reach(theta_abs, speed_abs, min(pend.alphas))
    except ValueError as exc:
        raise ValueError(f"grid: {exc}") from None
    if cfg.separatrices.enabled:
        cfg.resolve_tol()
        try:
            check_separatrix_settings((g.theta0.start, g.theta0.stop),
                                      (g.theta_dot0.start, g.theta_dot0.stop),
                                      cfg.separatrices.tol, cfg.separatrices.max_spacing)
        except ValueError as exc:
            raise ValueError(f"separatrices.{exc}") from None


def begin(cfg, layout) -> list:
    """Before anything is written: every point's RK4 map with its running certificate
    (:func:`atlas.models.pendulum.points.begin`; a dt too coarse for the running speeds is
    bad input, AtlasError naming integrator.dt)."""
    from atlas.models.pendulum import points

    return points.begin(cfg, layout)


def sample(cfg, begun: list, p: int):
    """The ``p``-th point's RK4 map, to label sample orbits with (the pre-flight estimate)."""
    return begun[p]


def plan(cfg, layout, begun: list, track=None):
    """Every point prepared (:func:`atlas.models.pendulum.points.plan`): its exact boundaries,
    traced separatrices, certifier and groups; ``track`` shows the progress."""
    from atlas.models.pendulum import points

    return points.plan(cfg, layout, begun) if track is None else \
        points.plan(cfg, layout, begun, track)
