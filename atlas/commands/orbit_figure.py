"""``atlas orbit``'s figure: one orbit's phase curve and θ(t), side by side, as a PNG.

The phase curve is drawn over the atlas's basin map when there is one (essay Figure 9, with
the running basin and the limit cycle for a torque atlas: :func:`atlas.views.maps.basin_map`),
else over the (tilted) critical points and the limit cycle; θ(t) with the wells and saddles
marked (essay Figure 6). It draws what :func:`atlas.commands.orbit_integrate.integrate`
returned and computes nothing but the critical points' positions.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from atlas.commands.orbit_integrate import Orbit
from atlas.errors import AtlasError
from atlas.physics.pendulum import Pendulum, critical_points
from atlas.status import RUNNING, TRAPPED
from atlas.views.style import STYLE, critical_point_markers, pi_ticks, point_title

__all__ = ["plot_orbit", "MAX_TURNS_MARKED"]

TWO_PI = 2.0 * math.pi


#: The θ(t) panel marks wells and saddles only while it spans at most this many turns.
MAX_TURNS_MARKED = 24


def plot_orbit(orbit: Orbit, output: str | Path, tree=None, index=None) -> Path:
    """Write the orbit's phase curve (over the basin map when ``tree`` is given: essay Figure
    9, with the running basin and the limit cycle for a torque atlas) and θ(t) (essay
    Figure 6) side by side to ``output`` (PNG). Without a file the (tilted) critical points
    and the limit cycle (when known) are drawn under the curve."""
    import matplotlib
    from matplotlib.figure import Figure  # no pyplot: a file, never a window or a backend

    from atlas.views.maps import basin_map, draw_limit_cycle

    output = Path(output)
    pendulum = Pendulum(orbit.alpha, orbit.omega0, orbit.torque)
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(13, 4.8))
        ax, ax_t = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.35, 1]})
        if tree is not None:
            basin_map(tree, ax=ax, **(index or {}))
        else:
            lo = min(-math.pi, orbit.theta.min()) - 0.5
            hi = max(math.pi, orbit.theta.max()) + 0.5
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
            ax.legend(loc="upper right")
        ax.plot(orbit.theta, orbit.theta_dot, color="white", lw=3.0, zorder=6)
        ax.plot(orbit.theta, orbit.theta_dot, color="black", lw=1.2, zorder=7, label="orbit")
        ax.plot(orbit.theta0, orbit.theta_dot0, "o", mfc="white", mec="black", ms=7, zorder=8)
        if orbit.trap_index is not None:
            i = orbit.trap_index
            ax.plot(orbit.theta[i], orbit.theta_dot[i], "x", color="black", ms=8, mew=2,
                    zorder=8)
        ax_t.plot(orbit.t, orbit.theta, color="black", lw=1.2)
        lo, hi = float(orbit.theta.min()), float(orbit.theta.max())
        if hi - lo <= MAX_TURNS_MARKED * TWO_PI:
            for p in critical_points(pendulum, lo - math.pi, hi + math.pi):
                ax_t.axhline(p.theta, color="red" if p.is_saddle else "0.5",
                             ls=":" if p.is_saddle else "--", lw=0.8)
            pi_ticks(ax_t, lo - 0.5, hi + 0.5, axis="y")
        if orbit.status == TRAPPED:
            rest = ("" if orbit.torque == 0.0 else
                    f" (rest at θ = {orbit.rest_angle + TWO_PI * orbit.k:.4g})")
            ax_t.axvline(orbit.t_trap, color="tab:blue", lw=1,
                         label=f"trapped in well {orbit.k:+d} at t = {orbit.t_trap:.2f} s{rest}")
            ax_t.legend(loc="best")
        elif orbit.status == RUNNING:
            ax_t.axvline(orbit.t_trap, color="tab:blue", lw=1,
                         label=f"certified running ({orbit.direction:+d}) at t = "
                         f"{orbit.t_trap:.2f} s")
            ax_t.legend(loc="best")
        ax_t.set_ylim(lo - 0.5, hi + 0.5)
        ax_t.set_xlabel("t [s]")
        ax_t.set_ylabel("θ [rad]")
        ax_t.set_title(f"θ(t) from θ0 = {orbit.theta0:.4g}, θ̇0 = {orbit.theta_dot0:.4g} "
                       "(wells dashed, saddles dotted)")
        fig.tight_layout()
        try:
            fig.savefig(output)
        except OSError as exc:
            raise AtlasError(f"{output}: cannot write the figure ({exc.strerror or exc})"
                             ) from None
    return output
