"""The essay's Figures 1–12, redrawn from this package's own mathematics.

A leaf layer: every curve comes from :mod:`atlas.physics.linear` (closed forms, essay eqs.
2–19 and 25–26, errata fixed), from RK4 integration of eq. (1) with the kernels' step
(:mod:`atlas.kernels.rk4`; only :func:`rk4_orbits`, which records the figure's trajectories,
is added here), from :mod:`atlas.boundaries.trace` (Figure 9's red curves) or from the vector
fields of eqs. (20)–(24).

Each ``figN_<what>(ax_or_fig=None, *, small=False, **parameters)`` returns a matplotlib
Figure; the keyword defaults are the parameters of the essay's caption (ω in Figures 1–4 is
the damped frequency, so ω0 = √(ω² + α²)). ``ax_or_fig`` may be an Axes (single-panel
figures; a 3-D Axes for Figure 6) or a Figure to draw into; ``small=True`` draws fewer curves
and points (for tests). :func:`write_all` writes all twelve as PNG files. Where the essay is
silent (parameters, windows, starting points) the choices are said in the titles and in
``docs/design/figures.md``.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from atlas import defaults  # noqa: E402
from atlas.kernels.rk4 import record_straightforward  # noqa: E402
from atlas.physics import linear
from atlas.physics.pendulum import Pendulum, critical_points  # noqa: E402
from atlas.views.style import (  # noqa: E402
    ATTRACTOR_MARKER,
    SADDLE_MARKER,
    STYLE,
    critical_point_markers,
    pi_ticks,
)

__all__ = [
    "fig1_underdamped_angle",
    "fig2_underdamped_angular_velocity",
    "fig3_damping_comparison",
    "fig4_underdamped_phase_curves",
    "fig5_phase_curves_many_initial_conditions",
    "fig6_phase_curve_in_time_3d",
    "fig7_damping_regimes_angle",
    "fig8_damping_regimes_phase",
    "fig9_nonlinear_phase_portrait",
    "fig10_flow_near_attractor_full_vs_linear",
    "fig11_flow_near_saddle_full_vs_linear",
    "fig12_linearised_flow_near_saddle",
    "FIGURES",
    "write_all",
]

THETA = "θ [rad]"
THETA_DOT = "θ̇ [rad/s]"
TIME = "t [s]"
#: Colours of the damping regimes in Figures 7–8: blue and vermilion either side of the black
#: critical case (Okabe & Ito's colour-blind-safe set; the essay's green and red are one
#: colour to a reader with deuteranopia or protanopia).
REGIME_COLORS = {"underdamped": "#0072b2", "critically damped": "#000000",
                 "overdamped": "#d55e00"}


# --------------------------------------------------------------------------- helpers


def _styled(draw):
    """Run a figure function inside the package's one plotting style."""

    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        with plt.rc_context(STYLE):
            return draw(*args, **kwargs)

    return wrapper


def _axes(ax_or_fig, n: int = 1, *, projection=None, figsize=(6.4, 4.0)):
    """(figure, list of n axes): draw into the given Axes (n = 1) or Figure, or a new one."""
    if isinstance(ax_or_fig, Axes):
        if n != 1:
            raise TypeError(f"this figure has {n} panels: pass a Figure, not an Axes")
        return ax_or_fig.figure, [ax_or_fig]
    fig = ax_or_fig if isinstance(ax_or_fig, Figure) else plt.figure(figsize=figsize)
    return fig, [fig.add_subplot(1, n, i + 1, projection=projection) for i in range(n)]


def _omega0(alpha: float, omega: float) -> float:
    """ω0 = √(ω² + α²) [rad/s] from the damped frequency ω of the underdamped motion."""
    return math.hypot(omega, alpha)


def _times(t_max: float, small: bool, n: int = 2000) -> np.ndarray:
    return np.linspace(0.0, t_max, n // 5 if small else n)


def _num(x: float) -> str:
    """x as 'kπ' when it is a nonzero integer multiple of π, else '%g'."""
    k = round(x / math.pi)
    return f"{'−' if k < 0 else ''}{abs(k) if abs(k) != 1 else ''}π" if (
        k != 0 and math.isclose(x, k * math.pi)) else f"{x:g}"


def _ic(theta0: float, theta_dot0: float) -> str:
    return f"θ0 = {_num(theta0)} rad, θ̇0 = {_num(theta_dot0)} rad/s"


def _legend_outside(ax) -> None:
    """Legend to the right of a phase plane, where it hides no curve."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)


def _mark_origin(ax) -> None:
    ax.plot([0.0], [0.0], **ATTRACTOR_MARKER, zorder=5, label="attracting point (0, 0)")


def _offset_ticks(ax, axis: str, centre: float, name: str, step: float, half: float) -> None:
    """Ticks at centre + j·step labelled 'name ± j·step' (e.g. 2π−0.5, 2π, 2π+0.5)."""
    j = np.arange(-math.floor(half / step), math.floor(half / step) + 1)
    labels = [name if k == 0 else f"{name}{'+' if k > 0 else '−'}{abs(k) * step:g}" for k in j]
    getattr(ax, f"set_{axis}ticks")(centre + j * step)
    getattr(ax, f"set_{axis}ticklabels")(labels)


def rk4_orbits(theta0, theta_dot0, t_max: float, *, alpha: float, omega0: float,
               dt: float = 0.01, every: int = 4):
    """Orbits of the full eq. (1) by classical RK4 at step ``dt`` [s] (global error O(dt⁴);
    the step of :mod:`atlas.kernels.rk4`), recorded every ``every`` steps up to ``t_max`` [s].

    Returns (t, theta, theta_dot) with t of shape (m,) and theta, theta_dot of shape
    (m, n_orbits) [s, rad, rad/s].
    """
    theta = np.array(theta0, dtype=float).ravel()
    theta_dot = np.broadcast_to(np.asarray(theta_dot0, dtype=float), theta.shape).copy()
    n_records = math.ceil(t_max / (dt * every))
    out = np.empty((2, n_records + 1, theta.size))
    record_straightforward(theta, theta_dot, float(alpha), float(omega0), float(dt), int(every),
                           out)
    return np.arange(n_records + 1) * (dt * every), out[0], out[1]


# --------------------------------------------------------------------------- §2 linear


@_styled
def fig1_underdamped_angle(ax_or_fig=None, *, small=False, alpha=0.4, omega=2.0, theta0=0.5,
                           theta_dot0=0.0, t_max=10.0) -> Figure:
    """Figure 1: θ(t) of the underdamped linear pendulum (blue, eq. 6 via :func:`linear.solve`)
    between its envelopes ±A e^{−αt} (red; A from :func:`linear.amplitude_phase`)."""
    fig, (ax,) = _axes(ax_or_fig)
    omega0 = _omega0(alpha, omega)
    t = _times(t_max, small)
    theta, _ = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=omega0)
    amplitude, _ = linear.amplitude_phase(theta0, theta_dot0, alpha, omega0)
    ax.plot(t, theta, color="blue", label="θ(t)")
    envelope = amplitude * np.exp(-alpha * t)
    ax.plot(t, envelope, color="red", lw=1, label=r"$\pm A\,e^{-\alpha t}$")
    ax.plot(t, -envelope, color="red", lw=1)
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.set(xlabel=TIME, ylabel=THETA, xlim=(0, t_max),
           title=f"Underdamped θ(t): α = {alpha:g} s⁻¹, ω = {omega:g} s⁻¹; "
                 f"{_ic(theta0, theta_dot0)}")
    ax.legend(loc="upper right")
    return fig


@_styled
def fig2_underdamped_angular_velocity(ax_or_fig=None, *, small=False, alpha=0.4, omega=2.0,
                                      theta0=0.5, theta_dot0=0.0, t_max=10.0) -> Figure:
    """Figure 2: θ̇(t) of the underdamped linear pendulum (eq. 8 via :func:`linear.solve`)."""
    fig, (ax,) = _axes(ax_or_fig)
    t = _times(t_max, small)
    _, theta_dot = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=_omega0(alpha, omega))
    ax.plot(t, theta_dot, color="blue", label="θ̇(t)")
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.set(xlabel=TIME, ylabel=THETA_DOT, xlim=(0, t_max),
           title=f"Underdamped θ̇(t): α = {alpha:g} s⁻¹, ω = {omega:g} s⁻¹; "
                 f"{_ic(theta0, theta_dot0)}")
    ax.legend(loc="upper right")
    return fig


@_styled
def fig3_damping_comparison(ax_or_fig=None, *, small=False, alphas=(0.4, 0.9), omega=2.0,
                            theta0=0.5, theta_dot0=0.0, t_max=10.0,
                            colors=("blue", "red")) -> Figure:
    """Figure 3: θ(t) for two damping constants with the same damped frequency ω."""
    fig, (ax,) = _axes(ax_or_fig)
    t = _times(t_max, small)
    for alpha, color in zip(alphas, colors):
        theta, _ = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=_omega0(alpha, omega))
        ax.plot(t, theta, color=color, label=f"α = {alpha:g} s⁻¹")
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.set(xlabel=TIME, ylabel=THETA, xlim=(0, t_max),
           title=f"Larger α, swifter decay: ω = {omega:g} s⁻¹; {_ic(theta0, theta_dot0)}")
    ax.legend(loc="upper right")
    return fig


@_styled
def fig4_underdamped_phase_curves(ax_or_fig=None, *, small=False, alphas=(0.4, 0.9), omega=2.0,
                                  theta0=0.5, theta_dot0=0.0, t_max=20.0,
                                  colors=("blue", "red")) -> Figure:
    """Figure 4: phase curves (θ, θ̇) for two parameter sets with the same ω (so different
    ω0), from the same initial condition; both spiral into the attracting point (0, 0)."""
    fig, (ax,) = _axes(ax_or_fig, figsize=(7.6, 4.6))
    t = _times(t_max, small)
    for alpha, color in zip(alphas, colors):
        omega0 = _omega0(alpha, omega)
        theta, theta_dot = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=omega0)
        ax.plot(theta, theta_dot, color=color,
                label=f"α = {alpha:g} s⁻¹, ω0 = {omega0:.3g} rad/s")
    _mark_origin(ax)
    ax.set(xlabel=THETA, ylabel=THETA_DOT,
           title=f"Underdamped phase curves, ω = {omega:g} s⁻¹;\n{_ic(theta0, theta_dot0)}")
    _legend_outside(ax)
    return fig


@_styled
def fig5_phase_curves_many_initial_conditions(ax_or_fig=None, *, small=False, alpha=0.4,
                                              omega0=2.0, radius=1.0, n_curves=12,
                                              t_max=12.0) -> Figure:
    """Figure 5: phase curves of one underdamped linear pendulum from ``n_curves`` initial
    conditions on the ellipse θ0² + (θ̇0/ω0)² = radius²; they spiral into (0, 0) and, by
    uniqueness of solutions, never cross."""
    fig, (ax,) = _axes(ax_or_fig, figsize=(7.6, 4.6))
    n = 6 if small else n_curves
    phase = 2.0 * np.pi * np.arange(n) / n
    theta0, theta_dot0 = radius * np.cos(phase), radius * omega0 * np.sin(phase)
    t = _times(t_max, small)
    theta, theta_dot = linear.solve(theta0[:, None], theta_dot0[:, None], t[None, :],
                                    alpha=alpha, omega0=omega0)
    for i in range(n):
        ax.plot(theta[i], theta_dot[i], color="blue", lw=0.9,
                label="phase curves" if i == 0 else None)
    ax.plot(theta0, theta_dot0, "o", color="blue", ms=3, label="initial conditions")
    _mark_origin(ax)
    ax.set(xlabel=THETA, ylabel=THETA_DOT,
           title=f"Many initial conditions: α = {alpha:g} s⁻¹, ω0 = {omega0:g} rad/s")
    _legend_outside(ax)
    return fig


@_styled
def fig6_phase_curve_in_time_3d(ax_or_fig=None, *, small=False, alpha=0.1, omega0=2.0,
                                theta0=2 * np.pi, theta_dot0=2 * np.pi, t_max=50.0) -> Figure:
    """Figure 6: the phase curve of the linear pendulum with time as a third axis,
    (θ(t), θ̇(t), t) (blue), and the attracting point θ = θ̇ = 0 where it ends (red dot)."""
    if isinstance(ax_or_fig, Axes) and ax_or_fig.name != "3d":
        raise TypeError("Figure 6 needs a 3-D Axes (projection='3d') or a Figure")
    fig, (ax,) = _axes(ax_or_fig, projection="3d", figsize=(6.4, 5.4))
    t = _times(t_max, small, n=4000)
    theta, theta_dot = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=omega0)
    ax.plot(theta, theta_dot, t, color="blue", lw=0.8, label="(θ(t), θ̇(t), t)")
    ax.plot([0.0], [0.0], [t_max], "o", color="red", ms=5, label="attracting point θ = θ̇ = 0")
    lim = float(np.max(np.abs(theta)))
    pi_ticks(ax, -lim, lim, most=5)  # the foreshortened θ axis holds five labels apart
    ax.set(xlabel=THETA, ylabel=THETA_DOT, zlabel=TIME)
    ax.set_title(f"Phase curve in time: α = {alpha:g} s⁻¹, ω0 = {omega0:g} rad/s;\n"
                 f"{_ic(theta0, theta_dot0)}")
    ax.legend(loc="upper left")
    return fig


def _regimes(alphas, omega0, theta0, theta_dot0, t):
    """(label, colour, θ, θ̇) per damping constant, the colour naming the regime."""
    for alpha in alphas:
        regime = Pendulum(alpha, omega0).regime
        theta, theta_dot = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=omega0)
        yield f"{regime}, α = {alpha:g} s⁻¹", REGIME_COLORS[regime], theta, theta_dot


@_styled
def fig7_damping_regimes_angle(ax_or_fig=None, *, small=False, omega0=2.0,
                               alphas=(0.4, 2.0, 4.0), theta0=0.5, theta_dot0=0.0,
                               t_max=10.0) -> Figure:
    """Figure 7: θ(t) underdamped, critically damped, overdamped (eqs. 6, 11, 18 via
    :func:`linear.solve`), in REGIME_COLORS (blue, black, vermilion of Okabe & Ito's
    colour-blind-safe set, where the essay had green, blue, red). The essay gives no
    parameters: ω0 = 2 rad/s and α = 0.4, 2, 4 s⁻¹ by default."""
    fig, (ax,) = _axes(ax_or_fig)
    t = _times(t_max, small)
    for label, color, theta, _ in _regimes(alphas, omega0, theta0, theta_dot0, t):
        ax.plot(t, theta, color=color, label=label)
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.set(xlabel=TIME, ylabel=THETA, xlim=(0, t_max),
           title=f"Damping regimes: ω0 = {omega0:g} rad/s; {_ic(theta0, theta_dot0)}")
    ax.legend(loc="upper right")
    return fig


@_styled
def fig8_damping_regimes_phase(ax_or_fig=None, *, small=False, omega0=2.0,
                               alphas=(0.4, 2.0, 4.0), theta0=0.5, theta_dot0=0.0,
                               t_max=20.0) -> Figure:
    """Figure 8: the phase curves of Figure 7's three regimes, all ending at (0, 0)."""
    fig, (ax,) = _axes(ax_or_fig, figsize=(7.6, 4.6))
    t = _times(t_max, small)
    for label, color, theta, theta_dot in _regimes(alphas, omega0, theta0, theta_dot0, t):
        ax.plot(theta, theta_dot, color=color, label=label)
    _mark_origin(ax)
    ax.set(xlabel=THETA, ylabel=THETA_DOT,
           title=f"Damping regimes in phase space: ω0 = {omega0:g} rad/s;\n"
                 f"{_ic(theta0, theta_dot0)}")
    _legend_outside(ax)
    return fig


# --------------------------------------------------------------------------- §3 nonlinear


@_styled
def fig9_nonlinear_phase_portrait(ax_or_fig=None, *, small=False, alpha=defaults.ALPHA,
                                  omega0=defaults.OMEGA0, theta_window=defaults.THETA0_WINDOW,
                                  theta_dot_window=defaults.THETA_DOT0_WINDOW, t_max=40.0,
                                  dt=defaults.DT) -> Figure:
    """Figure 9: phase portrait of the full eq. (1) by RK4 (blue), with the separatrices of
    the origin's basin — both branches of the stable manifolds of the saddles (±π, 0), from
    :func:`atlas.boundaries.trace.trace` — in red, the saddles and the attractors (0, 0),
    (±2π, 0) in the markers of the basin maps (:func:`critical_point_markers`).

    Initial conditions: on the window's four edges (θ̇0 at its top and bottom values there;
    θ̇0 > 0 on the left and < 0 on the right edge, so that every curve enters the window) and at
    θ0 = nπ ± 0.3 rad, θ̇0 = 0 next to each saddle.
    """
    from atlas.boundaries.trace import trace
    from atlas.store.separatrices import branches

    fig, (ax,) = _axes(ax_or_fig, figsize=(9.0, 5.0))
    pendulum = Pendulum(alpha, omega0)
    lo, hi = theta_window
    v_lo, v_hi = theta_dot_window
    n_edge = 4 if small else 16
    # Curves enter through all four edges: θ̇0 = v_hi/v_lo on top/bottom, ≷ 0 on the left/right.
    along = (np.arange(n_edge) + 0.5) / n_edge
    top = lo + (hi - lo) * along
    saddles = np.array([c.theta for c in critical_points(pendulum, lo, hi) if c.is_saddle])
    near = (saddles[:, None] + np.array([-0.3, 0.3])).ravel()
    theta0 = np.concatenate([top, top[::-1], np.full(n_edge, lo), np.full(n_edge, hi), near])
    theta_dot0 = np.concatenate([np.full(n_edge, v_hi), np.full(n_edge, v_lo), v_hi * along,
                                 v_lo * along, np.zeros(near.size)])
    _, theta, theta_dot = rk4_orbits(theta0, theta_dot0, t_max if not small else t_max / 4,
                                     alpha=alpha, omega0=omega0, dt=dt)
    for i in range(theta0.size):
        ax.plot(theta[:, i], theta_dot[:, i], color="tab:blue", lw=0.7,
                label="phase curves (RK4)" if i == 0 else None)
    separatrices = trace(pendulum, theta_window, theta_dot_window, dt=dt,
                         **({"tol": 1e-6, "max_spacing": 0.2} if small else {}))
    first = True
    for saddle_n, _, th, v in branches(separatrices):
        if abs(saddle_n) == 1:
            ax.plot(th, v, color="red", lw=1.6, label="separatrices of (0, 0)" if first else None)
            first = False
    points = critical_points(pendulum, lo, hi)
    critical_point_markers(ax, [c.theta for c in points], [c.is_saddle for c in points])
    ax.set(xlim=theta_window, ylim=theta_dot_window, xlabel=THETA, ylabel=THETA_DOT,
           title=f"Damped pendulum (full equation): α = {alpha:g} s⁻¹, ω0 = {omega0:g} rad/s")
    pi_ticks(ax, lo, hi)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.08), ncol=4, borderaxespad=0)
    return fig


def _field(pendulum: Pendulum, n: int, theta, theta_dot, *, linearised: bool):
    """(θ̇, θ̈) of the full flow (eqs. 20–21) or of its linearisation about (nπ, 0),
    θ̈ = −2αθ̇ − ω0² cos(nπ)(θ − nπ) (eqs. 22–24)."""
    if linearised:
        return theta_dot, (-2.0 * pendulum.alpha * theta_dot
                           - (-1) ** n * pendulum.omega0**2 * (theta - n * np.pi))
    return theta_dot, pendulum.acceleration(theta, theta_dot)


def _flow_full_vs_linear(ax_or_fig, small, n, alpha, omega0, half_width, half_height,
                         what: str) -> Figure:
    """Stream lines of the full field (left) and the linearised field (right) about (nπ, 0)."""
    fig, axes = _axes(ax_or_fig, 2, figsize=(10.0, 4.4))
    pendulum = Pendulum(alpha, omega0)
    centre = n * np.pi
    m = 25 if small else 60
    theta, theta_dot = np.meshgrid(np.linspace(centre - half_width, centre + half_width, m),
                                   np.linspace(-half_height, half_height, m))
    name = "π" if n == 1 else f"{n}π"
    saddle = n % 2 == 1
    for ax, linearised in zip(axes, (False, True)):
        u, v = _field(pendulum, n, theta, theta_dot, linearised=linearised)
        ax.streamplot(theta, theta_dot, u, v, density=0.8 if small else 1.4, color="blue",
                      linewidth=0.8, arrowsize=0.8)
        ax.plot([centre], [0.0], **(SADDLE_MARKER if saddle else ATTRACTOR_MARKER), zorder=5,
                label=f"{'saddle' if saddle else 'attractor'} ({name}, 0)")
        ax.set(xlim=(centre - half_width, centre + half_width),
               ylim=(-half_height, half_height), xlabel=THETA, ylabel=THETA_DOT,
               title=("Linearised, eqs. (22), (" + ("24" if saddle else "23") + ")"
                      if linearised else "Full equation, eqs. (20)–(21)"))
        _offset_ticks(ax, "x", centre, name, 0.5, half_width)
    fig.suptitle(f"Phase flow near the {what} ({name}, 0): α = {alpha:g} s⁻¹, "
                 f"ω0 = {omega0:g} rad/s")
    return fig


@_styled
def fig10_flow_near_attractor_full_vs_linear(ax_or_fig=None, *, small=False, alpha=0.1,
                                             omega0=1.0, n=2, half_width=1.0,
                                             half_height=1.0) -> Figure:
    """Figure 10: the flow near the attractor (nπ, 0), n = 2, by the full equation (left)
    and its linearisation (right), as stream lines of the two vector fields."""
    return _flow_full_vs_linear(ax_or_fig, small, n, alpha, omega0, half_width, half_height,
                                "stable critical point")


@_styled
def fig11_flow_near_saddle_full_vs_linear(ax_or_fig=None, *, small=False, alpha=0.1,
                                          omega0=1.0, n=1, half_width=1.0,
                                          half_height=1.0) -> Figure:
    """Figure 11: as Figure 10 near the saddle (π, 0)."""
    return _flow_full_vs_linear(ax_or_fig, small, n, alpha, omega0, half_width, half_height,
                                "unstable critical point")


@_styled
def fig12_linearised_flow_near_saddle(ax_or_fig=None, *, small=False, alpha=0.1, omega0=1.0,
                                      asymptote_speed=0.001, branch_offset=0.1,
                                      branch_speed=0.07, t_max=10.0,
                                      half_width=0.3) -> Figure:
    """Figure 12: phase curves near the saddle (π, 0) from the linearisation (eqs. 25–26 via
    :func:`linear.solve_saddle`), each run from t = 0 to ±t_max: the asymptotes (red) from
    θ0 = π, θ̇0 = ±0.001; left/right branches (blue) from θ0 = π ± 0.1, θ̇0 = 0; top/bottom
    branches (blue) from θ0 = π, θ̇0 = ±0.07. The starting points are black dots, in the
    legend (the asymptotes' lie under the saddle's marker)."""
    fig, (ax,) = _axes(ax_or_fig, figsize=(7.6, 5.0))
    t = np.linspace(-t_max, t_max, 801 if small else 4001)
    starts = [(0.0, s * asymptote_speed, "red", "asymptotes") for s in (1, -1)]
    starts += [(s * branch_offset, 0.0, "blue", "branches") for s in (-1, 1)]
    starts += [(0.0, s * branch_speed, "blue", "branches") for s in (1, -1)]
    labelled = set()
    for phi0, theta_dot0, color, label in starts:
        phi, theta_dot = linear.solve_saddle(phi0, theta_dot0, t, alpha=alpha, omega0=omega0)
        # Far outside the box the exponentials only slow the renderer down.
        phi, theta_dot = (np.where(np.abs(phi) < 100 * half_width, x, np.nan)
                          for x in (phi, theta_dot))
        ax.plot(np.pi + phi, theta_dot, color=color, lw=1.5 if color == "red" else 1.0,
                label=None if label in labelled else label)
        labelled.add(label)
    ax.plot([np.pi + phi0 for phi0, *_ in starts], [v for _, v, *_ in starts], "o",
            color="black", ms=3.5, ls="none", zorder=4,
            label=f"starting points (t = 0);\ntwo of them, θ̇0 = ±{asymptote_speed:g},\n"
                  "lie under the saddle's marker")
    ax.plot([np.pi], [0.0], **SADDLE_MARKER, zorder=5, label="saddle (π, 0)")
    ax.set(xlim=(np.pi - half_width, np.pi + half_width), ylim=(-half_width, half_width),
           xlabel=THETA, ylabel=THETA_DOT,
           title=f"Linearised flow near (π, 0), eqs. (25)–(26):\n"
                 f"α = {alpha:g} s⁻¹, ω0 = {omega0:g} rad/s, t ∈ [−{t_max:g}, {t_max:g}] s")
    _offset_ticks(ax, "x", np.pi, "π", 0.1, half_width)
    _legend_outside(ax)
    return fig


# --------------------------------------------------------------------------- all of them

#: File stem → figure function, in the essay's order.
FIGURES = {
    "fig01_underdamped_angle": fig1_underdamped_angle,
    "fig02_underdamped_angular_velocity": fig2_underdamped_angular_velocity,
    "fig03_damping_comparison": fig3_damping_comparison,
    "fig04_underdamped_phase_curves": fig4_underdamped_phase_curves,
    "fig05_phase_curves_many_initial_conditions": fig5_phase_curves_many_initial_conditions,
    "fig06_phase_curve_in_time_3d": fig6_phase_curve_in_time_3d,
    "fig07_damping_regimes_angle": fig7_damping_regimes_angle,
    "fig08_damping_regimes_phase": fig8_damping_regimes_phase,
    "fig09_nonlinear_phase_portrait": fig9_nonlinear_phase_portrait,
    "fig10_flow_near_attractor_full_vs_linear": fig10_flow_near_attractor_full_vs_linear,
    "fig11_flow_near_saddle_full_vs_linear": fig11_flow_near_saddle_full_vs_linear,
    "fig12_linearised_flow_near_saddle": fig12_linearised_flow_near_saddle,
}


def write_all(outdir: Path, *, small: bool = False) -> list[Path]:
    """Write Figures 1–12 as ``outdir/figNN_<what>.png`` (creating ``outdir``); returns the
    paths in the essay's order."""
    from atlas.store.outputs import check_output, figure_metadata

    outdir = Path(outdir)
    for stem in FIGURES:  # nothing is written where a figure would replace another file
        check_output(outdir / f"{stem}.png", "figure", option="--outdir",
                     command="atlas figures")
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    with plt.rc_context(STYLE):
        for stem, draw in FIGURES.items():
            fig = draw(small=small)
            fig.tight_layout()
            path = outdir / f"{stem}.png"
            fig.savefig(path, metadata=figure_metadata(".png", "atlas figures"))
            plt.close(fig)
            written.append(path)
    return written
