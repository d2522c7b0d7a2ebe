"""``atlas orbit``'s figure of a driven pendulum's orbit, as a PNG, in three panels:

* the phase curve (θ wrapped to [−π, π), θ̇), thin, over the file's basin map
  (:func:`atlas.views.maps.basin_map`: the atlas key's colours, the attractors' points on P),
  its start marked;
* θ(t), unwrapped (a rotation then reads as a slope, its winding as turns per period), its
  returns to P (every drive period T) as dots and the decision t_trap marked;
* the returns to P themselves (θ wrapped, θ̇), in their order, on the attractors' points on
  P, the one reached ringed by its capture radius (the label's test: its last ``confirm``
  returns lie inside).

It draws what :func:`atlas.commands.orbit_driven.follow` returned and the file's
``/attractors`` node; it computes nothing.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from atlas.commands.orbit_driven import DrivenOrbit
from atlas.errors import AtlasError
from atlas.models.driven.description import stored_confirm
from atlas.views.info_driven import attractor_names
from atlas.views.style import ATTRACTOR_MARKER, ORBIT_START_MARKER, STYLE, pi_ticks

__all__ = ["plot_driven_orbit", "driven_figure", "wrap_with_breaks"]

TWO_PI = 2.0 * math.pi
#: The phase panel beyond the atlas's window (white is the map's "no label").
OUTSIDE = "0.84"
#: A chaotic attractor's cloud of points on P.
CLOUD = {"marker": ".", "ms": 1.5, "color": "black", "ls": "none"}
#: θ(t) gets ticks at multiples of π while it spans at most this many turns.
MAX_TURNS_TICKED = 8


def wrap_with_breaks(theta: np.ndarray, theta_dot: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(θ wrapped to [−π, π), θ̇) with NaN between two states where θ wraps, so that a line
    drawn through them is not drawn across the window."""
    wrapped = (theta + math.pi) % TWO_PI - math.pi
    jumps = np.flatnonzero(np.abs(np.diff(wrapped)) > math.pi) + 1
    return np.insert(wrapped, jumps, np.nan), np.insert(theta_dot, jumps, np.nan)


def _name(group, k: int) -> str:
    """Attractor k as every key names it (:func:`atlas.views.info_driven.attractor_names`)."""
    return attractor_names(group)[k].replace("-", "−")


def _decision(orbit: DrivenOrbit, group) -> str:
    """What t_trap marks, for legends."""
    if orbit.attractor is None:
        return "no label"
    return f"label decided: {_name(group, orbit.attractor)}, t_trap = {orbit.t_trap:.1f} s"


def _phase_panel(ax, orbit: DrivenOrbit, tree, index: dict, group) -> None:
    from matplotlib.patches import Patch

    from atlas.views.maps import basin_map

    basin_map(tree, ax=ax, **index)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    # the last confirm periods (the label's test: on the attractor) drawn heavier
    settled = orbit.attractor is not None and orbit.periods > 0
    confirm = min(int(stored_confirm(group)[orbit.attractor]), orbit.periods) if settled else 0
    cut = orbit.theta.size - confirm * (orbit.drive.steps_per_period // orbit.stride)
    last = "its last period" if confirm == 1 else f"its last {confirm} periods"
    for piece, width, label in (
            (slice(0, cut + 1), 0.6, "orbit (θ wrapped to [−π, π))"),
            (slice(cut, None), 1.5, f"{last}, on the attractor")):
        theta, theta_dot = wrap_with_breaks(orbit.theta[piece], orbit.theta_dot[piece])
        if theta.size < 2:
            continue
        ax.plot(theta, theta_dot, color="white", lw=width + 1.2, alpha=0.7, zorder=6)
        ax.plot(theta, theta_dot, color="black", lw=width, zorder=7, label=label)
    ax.plot((orbit.theta0 + math.pi) % TWO_PI - math.pi, orbit.theta_dot0,
            **ORBIT_START_MARKER, zorder=8, label="initial condition (θ0, θ̇0)")
    finite = orbit.theta_dot[np.isfinite(orbit.theta_dot)]
    outside = False
    if finite.size:  # the whole orbit in view: the map's window, grown where it leaves it
        span = y1 - y0
        low, high = finite.min() - 0.03 * span, finite.max() + 0.03 * span
        outside = low < y0 or high > y1
        ax.set_ylim(min(y0, low), max(y1, high))
    ax.set_xlim(min(x0, -math.pi), max(x1, math.pi))
    ax.set_xlabel("θ, θ0 [rad] (orbit: θ wrapped to [−π, π))")
    ax.set_ylabel("θ̇, θ̇0 [rad/s]")
    handles, labels = ax.get_legend_handles_labels()
    if finite.size and outside:  # beyond the map: grey, not the white of "no label"
        ax.set_facecolor(OUTSIDE)
        handles.append(Patch(fc=OUTSIDE, ec="0.5", lw=0.5))
        labels.append("outside the atlas window (not mapped)")
    ax.legend(handles, labels, loc="lower left", bbox_to_anchor=(0.0, 1.08), ncol=2,
              borderaxespad=0, fontsize=8)


def _time_panel(ax, orbit: DrivenOrbit, group) -> None:
    period = orbit.drive.period
    ax.plot(orbit.t, orbit.theta, color="black", lw=0.9, label="θ(t)")
    n = orbit.returns.shape[0]
    ax.plot(np.arange(n) * period, orbit.returns[:, 0], ls="none", marker="o", ms=3.5,
            mfc="tab:orange", mec="black", mew=0.5, zorder=5, label="returns to P (t = nT)")
    if orbit.attractor is not None:
        ax.axvline(orbit.t_trap, color="tab:blue", lw=1.0, ls="--",
                   label=_decision(orbit, group))
    finite = orbit.theta[np.isfinite(orbit.theta)]
    if finite.size and finite.max() - finite.min() <= MAX_TURNS_TICKED * TWO_PI:
        pi_ticks(ax, finite.min() - 0.3, finite.max() + 0.3, axis="y")
    ax.set_xlim(0.0, 1.02 * max(orbit.t[-1], period))
    ax.set_xlabel("t [s]")
    ax.set_ylabel("θ(t), unwrapped [rad]")
    top = ax.secondary_xaxis("top", functions=(lambda t: t / period, lambda n: n * period))
    top.set_xlabel(f"t / T (drive periods, T = {period:.4g} s)")
    ax.legend(loc="best", fontsize=8)


def _attractor_points(group, k: int) -> np.ndarray:
    theta, theta_dot = group["theta"].values[k], group["theta_dot"].values[k]
    keep = np.isfinite(theta)
    return np.column_stack([theta[keep], theta_dot[keep]])


def _draw_returns(ax, orbit: DrivenOrbit, group, norm, label: bool):
    """The attractors' points on P (the reached one as the attractor marker, ringed by its
    capture radius; the others as open diamonds) and the orbit's returns, coloured by n."""
    from matplotlib.patches import Circle

    others = [k for k in range(group.sizes.get("attractor", 0)) if k != orbit.attractor]
    for k in others:
        pts = _attractor_points(group, k)
        style = CLOUD if str(group["kind"].values[k]) == "chaotic" else {
            "marker": "D", "ms": 5.0, "mfc": "white", "mec": "0.4", "mew": 1.0, "ls": "none"}
        ax.plot(pts[:, 0], pts[:, 1], **style, zorder=3,
                label="other attractors' points on P" if label and k == others[0] else None)
    if orbit.attractor is not None:
        pts = _attractor_points(group, orbit.attractor)
        radius = float(group["capture_radius"].values[orbit.attractor])
        chaotic = str(group["kind"].values[orbit.attractor]) == "chaotic"
        ax.plot(pts[:, 0], pts[:, 1], **(CLOUD if chaotic else ATTRACTOR_MARKER), zorder=6,
                label=f"{_name(group, orbit.attractor)} (reached): its points on P"
                if label else None)
        for i, (x, y) in enumerate([] if chaotic else pts):  # a cloud: no ring per point
            ax.add_patch(Circle((x, y), radius, fill=False, ec="tab:red", lw=1.2, zorder=4,
                                label=f"capture radius {radius:.3g}" if label and i == 0
                                else None))
    returns = orbit.returns[np.isfinite(orbit.returns).all(axis=1)]
    wrapped = (returns[:, 0] + math.pi) % TWO_PI - math.pi
    n = np.arange(returns.shape[0])
    ax.plot(wrapped, returns[:, 1], color="0.6", lw=0.5, zorder=2)
    return ax.scatter(wrapped, returns[:, 1], c=n, cmap="viridis", norm=norm, s=22,
                      edgecolors="black", linewidths=0.4, zorder=5,
                      label=f"returns to P, n = 0 … {int(n[-1]) if n.size else 0}"
                      if label else None)


def _zoom(ax, orbit: DrivenOrbit, group, norm) -> None:
    """The reached attractor's point on P nearest the last return, ±3 capture radii, at
    equal scales: the capture circle and the last returns inside it, which decided the
    label."""
    pts = _attractor_points(group, orbit.attractor)
    last = orbit.returns[-1]
    d = np.hypot((last[0] - pts[:, 0] + math.pi) % TWO_PI - math.pi, last[1] - pts[:, 1])
    x, y = pts[int(d.argmin())]
    half = 3.0 * float(group["capture_radius"].values[orbit.attractor])
    _draw_returns(ax, orbit, group, norm, label=False)
    ax.set_xlim(x - half, x + half)
    ax.set_ylim(y - half, y + half)
    ax.set_aspect("equal", adjustable="box")
    ax.locator_params(nbins=3)
    ax.tick_params(labelsize=8)
    ax.set_xlabel("θ(nT) [rad]")
    ax.set_ylabel("θ̇(nT) [rad/s]")
    ax.set_title("zoom: ±3 capture radii", fontsize=9)


def _returns_panel(ax, ax_zoom, fig, orbit: DrivenOrbit, group) -> None:
    from matplotlib.colors import Normalize

    norm = Normalize(0, max(orbit.returns.shape[0] - 1, 1))
    dots = _draw_returns(ax, orbit, group, norm, label=True)
    ax.set_xlim(-math.pi, math.pi)
    pi_ticks(ax, -math.pi, math.pi)
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.6 * (hi - lo))  # room for the legend above the returns
    zoomed = orbit.attractor is not None and orbit.periods > 0
    if zoomed:
        _zoom(ax_zoom, orbit, group, norm)
    else:  # no label: nothing to zoom on
        ax_zoom.set_axis_off()
    bar = fig.colorbar(dots, ax=ax_zoom if zoomed else ax, pad=0.03, fraction=0.08)
    bar.set_label("return n (t = nT)")
    ax.set_xlabel("θ(nT) wrapped to [−π, π) [rad]")
    ax.set_ylabel("θ̇(nT) [rad/s]")
    ax.set_title("Stroboscopic returns to P, every T", fontsize=10)
    ax.legend(loc="upper left", fontsize=7)


def driven_figure(orbit: DrivenOrbit, tree, index: dict | None, group):
    """The figure of ``orbit`` (module docstring; a matplotlib Figure, no pyplot): ``tree``
    the opened atlas, ``index`` its point's indices along the swept dims, ``group`` the
    point's ``/attractors`` node. Its panels are named by their titles and axis labels."""
    from matplotlib.figure import Figure  # no pyplot: a file, never a window or a backend

    fig = Figure(figsize=(16, 8), layout="constrained")
    grid = fig.add_gridspec(2, 3, width_ratios=[1.45, 0.75, 0.55], height_ratios=[1, 1.15])
    ax = fig.add_subplot(grid[:, 0])
    ax_t = fig.add_subplot(grid[0, 1:])
    ax_p, ax_zoom = fig.add_subplot(grid[1, 1]), fig.add_subplot(grid[1, 2])
    _phase_panel(ax, orbit, tree, index or {}, group)
    _time_panel(ax_t, orbit, group)
    _returns_panel(ax_p, ax_zoom, fig, orbit, group)
    ax_t.set_title(f"θ(t) from θ0 = {orbit.theta0:.4g} rad, θ̇0 = {orbit.theta_dot0:.4g} rad/s",
                   fontsize=10)
    return fig


def plot_driven_orbit(orbit: DrivenOrbit, output: str | Path, tree, index: dict | None,
                      group) -> Path:
    """Write :func:`driven_figure` of ``orbit`` to ``output`` (PNG, SVG or PDF)."""
    import matplotlib

    from atlas.store.outputs import figure_metadata

    output = Path(output)
    with matplotlib.rc_context(STYLE):
        fig = driven_figure(orbit, tree, index, group)
        try:
            fig.savefig(output, metadata=figure_metadata(output.suffix, "atlas orbit"))
        except OSError as exc:
            raise AtlasError(f"{output}: cannot write the figure ({exc.strerror or exc})"
                             ) from None
    return output
