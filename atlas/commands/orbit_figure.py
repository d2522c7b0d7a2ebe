"""``atlas orbit``'s figure: one orbit's phase curve, θ(t) and θ̇(t), as a PNG.

The phase curve is drawn over the atlas's basin map when there is one (essay Figure 9, with
the running basin and the limit cycle for a torque atlas: :func:`atlas.views.maps.basin_map`),
else over the (tilted) critical points and the limit cycle, modulo the window's whole turns
(:func:`atlas.commands.orbit_integrate.wrapped`: a piece that leaves the window is drawn a
whole number of turns away, inside it, so that every orbit is seen to settle, in a well or on
the running cycle); θ(t) with the wells and saddles marked (essay Figure 6) and θ̇(t) beside
it. It draws what :func:`atlas.commands.orbit_integrate.integrate` returned and computes
nothing but the critical points' positions.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from atlas.commands.orbit_integrate import Orbit, window_period, wrapped
from atlas.errors import AtlasError
from atlas.physics.pendulum import Pendulum, critical_points
from atlas.status import RUNNING, TRAPPED
from atlas.views.style import (
    ORBIT_START_MARKER,
    SADDLE_MARKER,
    STYLE,
    basin_colours,
    critical_point_markers,
    pi_ticks,
    point_title,
)

__all__ = ["plot_orbit", "MAX_TURNS_MARKED"]

TWO_PI = 2.0 * math.pi


#: The θ(t) panel marks wells and saddles only while it spans at most this many turns.
MAX_TURNS_MARKED = 24


def _certified_colour(orbit: Orbit) -> str:
    """The colour of the orbit's certified end (its well k, or the running basin) in the
    basin palette (:func:`atlas.views.style.basin_colours`, its darker variant for lines)."""
    trapped = orbit.status == TRAPPED
    colours = basin_colours([orbit.k] if trapped else [], running=not trapped, lines=True)
    return colours[orbit.k if trapped else "running"]


def plot_orbit(orbit: Orbit, output: str | Path, tree=None, index=None) -> Path:
    """Write the orbit's phase curve (over the basin map when ``tree`` is given: essay Figure
    9, with the running basin and the limit cycle for a torque atlas), θ(t) (essay Figure 6)
    and θ̇(t) to ``output`` (PNG). Without a file the (tilted) critical points and the limit
    cycle (when known) are drawn under the curve, in a window that holds the orbit up to its
    certificate. The phase curve is drawn modulo the window's whole turns (module
    docstring); the legend names every marker."""
    import matplotlib
    from matplotlib.figure import Figure  # no pyplot: a file, never a window or a backend

    from atlas.store.outputs import figure_metadata
    from atlas.views.maps import basin_map, draw_limit_cycle

    output = Path(output)
    pendulum = Pendulum(orbit.alpha, orbit.omega0, orbit.torque)
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(14, 6.4))
        grid = fig.add_gridspec(2, 2, width_ratios=[1.35, 1])
        ax = fig.add_subplot(grid[:, 0])
        ax_t = fig.add_subplot(grid[0, 1])
        ax_v = fig.add_subplot(grid[1, 1], sharex=ax_t)
        if tree is not None:
            basin_map(tree, ax=ax, **(index or {}))
            lo, hi = ax.get_xlim()
        else:
            lo, hi = _window(orbit)
            pts = critical_points(pendulum, lo, hi)
            critical_point_markers(ax, [p.theta for p in pts], [p.is_saddle for p in pts],
                                   tilted=orbit.torque != 0.0)
            if orbit.cycle is not None:
                draw_limit_cycle(ax, lo, hi, np.asarray(orbit.cycle.theta),
                                 np.asarray(orbit.cycle.theta_dot), orbit.cycle.period)
            ax.set_xlim(lo, hi)
            pi_ticks(ax, lo, hi)
            ax.set_xlabel("θ [rad]")
            ax.set_ylabel("θ̇ [rad/s]")
            ax.set_title("Phase curve, " + point_title(
                {"alpha": orbit.alpha, "omega0": orbit.omega0, "torque": orbit.torque}))
        _draw_phase_curve(ax, orbit, lo, hi)
        ax.set_xlim(lo, hi)
        # above the map, within its width (the right-hand panels keep their place)
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=2, borderaxespad=0)
        ax_t.plot(orbit.t, orbit.theta, color="black", lw=1.2)
        _draw_speed(ax_v, orbit)
        lo, hi = float(orbit.theta.min()), float(orbit.theta.max())
        if hi - lo <= MAX_TURNS_MARKED * TWO_PI:
            for p in critical_points(pendulum, lo - math.pi, hi + math.pi):
                ax_t.axhline(p.theta, color=SADDLE_MARKER["mec"] if p.is_saddle else "0.5",
                             ls=":" if p.is_saddle else "--", lw=0.8)
            pi_ticks(ax_t, lo - 0.5, hi + 0.5, axis="y")
        if orbit.status in (TRAPPED, RUNNING):
            for panel in (ax_t, ax_v):
                panel.axvline(orbit.t_trap, color=_certified_colour(orbit), lw=1,
                              label=_certificate_text(orbit) if panel is ax_t else None)
            ax_t.legend(loc="best")
        ax_t.set_ylim(lo - 0.5, hi + 0.5)
        ax_t.set_ylabel("θ [rad]")
        ax_t.tick_params(labelbottom=False)
        ax_t.set_title(f"θ(t), θ̇(t) from θ0 = {orbit.theta0:.4g} rad, θ̇0 = "
                       f"{orbit.theta_dot0:.4g} rad/s\n(wells dashed, saddles dotted)")
        fig.tight_layout()
        try:
            fig.savefig(output, metadata=figure_metadata(Path(output).suffix, "atlas orbit"))
        except OSError as exc:
            raise AtlasError(f"{output}: cannot write the figure ({exc.strerror or exc})"
                             ) from None
    return output


def _window(orbit: Orbit) -> tuple[float, float]:
    """The θ window [rad] of the phase curve without an atlas: [−π, π], grown to hold the
    whole orbit (0.5 rad to spare); for a running orbit, to hold it up to its certificate,
    then to whole turns, so that the rest, wrapped, fills it."""
    if orbit.status != RUNNING:
        return (min(-math.pi, orbit.theta.min()) - 0.5, max(math.pi, orbit.theta.max()) + 0.5)
    shown = orbit.theta[:orbit.trap_index + 1]
    lo, hi = min(-math.pi, shown.min()), max(math.pi, shown.max())
    return lo, lo + TWO_PI * math.ceil((hi - lo) / TWO_PI - 1e-9)


def _certificate_text(orbit: Orbit) -> str:
    """What the cross marks: the certificate and its time [s]."""
    if orbit.status == TRAPPED:
        rest = ("" if orbit.torque == 0.0 else
                f" (rest at θ = {orbit.rest_angle + TWO_PI * orbit.k:.4g})")
        return (f"trapped in well {orbit.k:+d} at t = {orbit.t_trap:.2f} s{rest}"
                .replace("-", "−"))
    return f"certified running ({orbit.direction:+d}) at t = {orbit.t_trap:.2f} s"


def _wrap_point(theta: float, lo: float, hi: float) -> float:
    """One θ [rad] as :func:`wrapped` draws it in [lo, hi]."""
    return float(wrapped(np.array([theta]), np.array([0.0]), lo, hi)[0][0])


def _draw_phase_curve(ax, orbit: Orbit, lo: float, hi: float) -> None:
    """The orbit in the phase plane over [lo, hi] [rad], wrapped (:func:`wrapped`), its start
    and its certificate marked, each named in the legend."""
    theta, theta_dot = wrapped(orbit.theta, orbit.theta_dot, lo, hi)
    period = window_period(lo, hi)
    shifted = bool(np.isnan(theta).any()) or not np.array_equal(theta, orbit.theta)
    turns = f"{round(period / TWO_PI)} × 2π" if period > TWO_PI else "2π"
    ax.plot(theta, theta_dot, color="white", lw=3.0, zorder=6)
    ax.plot(theta, theta_dot, color="black", lw=1.2, zorder=7,
            label=f"orbit (drawn modulo {turns} into the window)" if shifted else "orbit")
    ax.plot(_wrap_point(orbit.theta0, lo, hi), orbit.theta_dot0, **ORBIT_START_MARKER,
            zorder=8, label="initial condition (θ0, θ̇0)")
    if orbit.trap_index is not None:
        i = orbit.trap_index
        ax.plot(_wrap_point(orbit.theta[i], lo, hi), orbit.theta_dot[i], "x", color="black",
                ms=8, mew=2, zorder=8, label=_certificate_text(orbit))
    end = _wrap_point(orbit.theta[-1], lo, hi)
    if orbit.status == TRAPPED and end != orbit.theta[-1]:  # settles whole turns away
        import matplotlib.patheffects as pe

        turns = round((orbit.theta[-1] - end) / TWO_PI)
        ax.annotate(f"well {orbit.k:+d}, drawn {abs(turns)} turn{'s' * (abs(turns) > 1)} "
                    "away".replace("-", "−"), (end, orbit.theta_dot[-1]),
                    xytext=(10, -14), textcoords="offset points", fontsize=8, zorder=9,
                    path_effects=[pe.withStroke(linewidth=2.5, foreground="white")])


def _draw_speed(ax, orbit: Orbit) -> None:
    """θ̇(t) [rad/s], with the running cycle's mean speed where the orbit runs."""
    ax.plot(orbit.t, orbit.theta_dot, color="black", lw=1.0)
    ax.axhline(0.0, color="0.5", lw=0.8, ls="--")
    if orbit.status == RUNNING and orbit.cycle is not None:
        mean = TWO_PI / orbit.cycle.period * orbit.direction
        ax.axhline(mean, color="0.3", lw=0.8, ls=":",
                   label=f"the cycle's mean speed 2π/T = {abs(mean):.4g} rad/s")
        ax.legend(loc="best")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("θ̇ [rad/s]")
