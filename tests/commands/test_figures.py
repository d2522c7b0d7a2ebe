"""The essay's Figures 1–12 (atlas.commands.figures): each draws the right curves from the
right maths."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import same_color  # noqa: E402

from atlas import linear
from atlas.commands import figures  # noqa: E402
from atlas.views.style import ATTRACTOR_MARKER, SADDLE_MARKER  # noqa: E402

UNITS = {"θ [rad]", "θ̇ [rad/s]", "t [s]"}


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def curves(ax, color=None):
    """The lines of ``ax`` with more than one point (not markers or the grey zero line),
    optionally of one colour."""
    return [ln for ln in ax.lines if len(ln.get_xdata()) > 2 and ln.get_linestyle() != "None"
            and (color is None or same_color(ln.get_color(), color))]


def markers(ax):
    return [ln for ln in ax.lines if len(ln.get_xdata()) <= 10 and ln.get_marker() == "o"]


def assert_looks_like(line, marker: dict) -> None:
    """``line``'s marker is drawn as ``marker`` (style.SADDLE_MARKER, ATTRACTOR_MARKER): one
    look on the maps, the orbit figure and the essay's figures."""
    assert line.get_marker() == marker["marker"] and line.get_markersize() == marker["ms"]
    assert line.get_markeredgewidth() == marker["mew"]
    assert same_color(line.get_markerfacecolor(), marker["mfc"])
    assert same_color(line.get_markeredgecolor(), marker["mec"])


def _overlapping_labels(fig, labels) -> list:
    """The pairs of visible, non-empty tick labels whose boxes overlap once drawn."""
    fig.canvas.draw()
    boxes = [(t.get_text(), t.get_window_extent()) for t in labels
             if t.get_visible() and t.get_text()]
    return [(a, b) for i, (a, box) in enumerate(boxes) for b, other in boxes[i + 1:]
            if box.overlaps(other)]


@pytest.mark.slow
@pytest.mark.parametrize("stem", list(figures.FIGURES))
def test_every_figure_draws_labelled_axes(stem):
    fig = figures.FIGURES[stem](small=True)
    assert isinstance(fig, matplotlib.figure.Figure)
    assert fig.axes
    for ax in fig.axes:
        assert {ax.get_xlabel(), ax.get_ylabel()} <= UNITS
        assert ax.get_title() or fig.get_suptitle()
        assert ax.lines or ax.collections


def test_fig1_is_the_closed_form_between_its_envelopes():
    alpha, omega, theta0 = 0.4, 2.0, 0.5  # the caption's parameters (defaults)
    ax = figures.fig1_underdamped_angle(small=True).axes[0]
    (blue,) = curves(ax, "blue")
    t = blue.get_xdata()
    theta, _ = linear.solve(theta0, 0.0, t, alpha=alpha, omega0=math.hypot(omega, alpha))
    np.testing.assert_allclose(blue.get_ydata(), theta, rtol=0, atol=1e-15)
    red = curves(ax, "red")
    assert len(red) == 2
    amplitude = math.hypot(theta0, alpha * theta0 / omega)  # A sin Φ = θ0, A cos Φ = αθ0/ω
    upper = max(red, key=lambda ln: ln.get_ydata()[0])
    np.testing.assert_allclose(upper.get_ydata(), amplitude * np.exp(-alpha * t), rtol=1e-14)
    # the envelope touches the curve from outside
    assert np.all(np.abs(theta) <= upper.get_ydata() + 1e-15)
    assert ax.get_legend() is not None


def test_fig2_plots_the_angular_velocity():
    ax = figures.fig2_underdamped_angular_velocity(small=True).axes[0]
    (blue,) = curves(ax, "blue")
    _, theta_dot = linear.solve(0.5, 0.0, blue.get_xdata(), alpha=0.4,
                                omega0=math.hypot(2.0, 0.4))
    np.testing.assert_allclose(blue.get_ydata(), theta_dot, atol=1e-15)
    assert ax.get_ylabel() == "θ̇ [rad/s]"


def test_fig3_larger_damping_in_red_decays_faster():
    ax = figures.fig3_damping_comparison(small=True).axes[0]
    (blue,), (red,) = curves(ax, "blue"), curves(ax, "red")
    assert "0.4" in blue.get_label() and "0.9" in red.get_label()
    late = blue.get_xdata() > 3.0
    assert np.abs(red.get_ydata()[late]).max() < np.abs(blue.get_ydata()[late]).max()


@pytest.mark.parametrize("draw, n_curves", [
    (figures.fig4_underdamped_phase_curves, 2),
    (figures.fig5_phase_curves_many_initial_conditions, 6),
    (figures.fig8_damping_regimes_phase, 3),
])
def test_linear_phase_curves_end_at_the_attracting_point(draw, n_curves):
    ax = draw(small=True).axes[0]
    lines = curves(ax)
    assert len(lines) == n_curves
    for ln in lines:
        assert math.hypot(ln.get_xdata()[-1], ln.get_ydata()[-1]) < 0.05
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("θ [rad]", "θ̇ [rad/s]")


def test_fig4_has_the_same_damped_frequency_but_two_omega0():
    ax = figures.fig4_underdamped_phase_curves(small=True).axes[0]
    labels = [ln.get_label() for ln in curves(ax)]
    assert [same_color(ln.get_color(), c) for ln, c in zip(curves(ax), ("blue", "red"))] == \
        [True, True]
    assert "2.04" in labels[0] and "2.19" in labels[1]  # ω0 = √(4 + α²), α = 0.4, 0.9


def test_fig6_is_three_dimensional_with_a_red_attracting_point():
    """The closed form in (θ, θ̇, t); θ ticks at multiples of π whose labels, on the
    foreshortened axis, stand apart (at nine ticks, −3π/2 and −π ran into each other)."""
    fig = figures.fig6_phase_curve_in_time_3d(small=True)
    (ax,) = fig.axes
    assert ax.name == "3d"
    assert ax.get_zlabel() == "t [s]"
    (blue,) = curves(ax, "blue")
    theta, theta_dot, t = blue.get_data_3d()
    ref = linear.solve(2 * np.pi, 2 * np.pi, t, alpha=0.1, omega0=2.0)
    np.testing.assert_allclose(np.array([theta, theta_dot]), np.array(ref), atol=1e-13)
    (dot,) = [ln for ln in ax.lines if same_color(ln.get_color(), "red")]
    x, y, z = dot.get_data_3d()
    assert (x[0], y[0], z[0]) == (0.0, 0.0, t[-1])
    ticks = ax.get_xticks()
    np.testing.assert_allclose(ticks / np.pi, np.round(ticks / np.pi), atol=1e-12)
    assert _overlapping_labels(fig, ax.get_xticklabels()) == []


def test_fig7_colours_name_the_damping_regimes():
    ax = figures.fig7_damping_regimes_angle(small=True).axes[0]
    lines = curves(ax)
    assert [ln.get_label().split(",")[0] for ln in lines] == \
        ["underdamped", "critically damped", "overdamped"]
    for ln, regime in zip(lines, ("underdamped", "critically damped", "overdamped")):
        assert same_color(ln.get_color(), figures.REGIME_COLORS[regime])
        assert ln.get_ydata()[0] == 0.5


#: The least CAM02-UCS ΔE between two regimes' lines, for every vision: 30 is plainly
#: apart (the essay's green and red are 17 apart to a deuteranope, 8.5 to a protanope).
LEAST_REGIME_DELTA_E = 30.0


@pytest.mark.parametrize("draw", [figures.fig7_damping_regimes_angle,
                                  figures.fig8_damping_regimes_phase])
def test_the_damping_regimes_stay_apart_for_colour_blind_readers(draw):
    """The three regimes' lines, read back from the Axes, are far apart in CAM02-UCS as
    readers with normal vision, deuteranopia and protanopia see them (colorspacious, the
    Machado et al. 2009 simulation at full severity)."""
    import colorspacious
    from matplotlib.colors import to_rgb

    rgb = np.array([to_rgb(ln.get_color()) for ln in curves(draw(small=True).axes[0])])
    assert len(rgb) == 3
    for cvd in (None, "deuteranomaly", "protanomaly"):
        seen = rgb if cvd is None else np.clip(colorspacious.cspace_convert(
            rgb, {"name": "sRGB1+CVD", "cvd_type": cvd, "severity": 100}, "sRGB1"), 0, 1)
        ucs = colorspacious.cspace_convert(seen, "sRGB1", "CAM02-UCS")
        apart = [np.linalg.norm(ucs[i] - ucs[j]) for i in range(3) for j in range(i)]
        assert min(apart) >= LEAST_REGIME_DELTA_E, (cvd, apart)


def test_fig9_portrait_has_red_separatrices_through_the_saddles():
    ax = figures.fig9_nonlinear_phase_portrait(small=True).axes[0]
    red = curves(ax, "red")
    assert len(red) == 4  # both branches of the stable manifolds of (±π, 0)
    starts = sorted(round(ln.get_xdata()[0] / np.pi) for ln in red)
    assert starts == [-1, -1, 1, 1]
    for ln in red:  # each branch starts at its saddle
        theta, theta_dot = ln.get_xdata()[0], ln.get_ydata()[0]
        assert math.hypot(theta - np.pi * np.sign(theta), theta_dot) < 0.05
    # saddles at odd multiples of π, attractors at 0, ±2π, each in the look of the maps
    (saddles,) = [m for m in markers(ax) if m.get_label().startswith("saddles")]
    assert_looks_like(saddles, SADDLE_MARKER)
    np.testing.assert_allclose(saddles.get_xdata(), [-3 * np.pi, -np.pi, np.pi, 3 * np.pi])
    (attractors,) = [m for m in markers(ax) if m.get_label().startswith("attractors")]
    assert_looks_like(attractors, ATTRACTOR_MARKER)
    np.testing.assert_allclose(attractors.get_xdata(), [-2 * np.pi, 0.0, 2 * np.pi], atol=1e-15)
    assert len(curves(ax)) - len(red) >= 10  # the blue phase curves
    assert ax.get_xlim() == pytest.approx((-3 * np.pi, 3 * np.pi))


def test_rk4_orbits_follow_equation_1():
    """Small oscillations of the full equation are the linear closed form (sin θ ≈ θ)."""
    t, theta, theta_dot = figures.rk4_orbits([1e-4, -2e-4], [0.0, 1e-4], 10.0, alpha=0.1,
                                             omega0=1.0, dt=0.01, every=4)
    ref = linear.solve(np.array([1e-4, -2e-4]), np.array([0.0, 1e-4]), t[:, None], alpha=0.1,
                       omega0=1.0)
    np.testing.assert_allclose(theta, ref[0], rtol=0, atol=1e-11)
    np.testing.assert_allclose(theta_dot, ref[1], rtol=0, atol=1e-11)
    assert t[-1] == pytest.approx(10.0)


@pytest.mark.parametrize("draw, centre", [
    (figures.fig10_flow_near_attractor_full_vs_linear, 2 * np.pi),
    (figures.fig11_flow_near_saddle_full_vs_linear, np.pi),
])
def test_full_and_linear_flow_side_by_side(draw, centre):
    fig = draw(small=True)
    left, right = fig.axes
    for ax in (left, right):
        assert ax.collections  # the stream lines
        assert np.mean(ax.get_xlim()) == pytest.approx(centre)
        (point,) = markers(ax)
        assert point.get_xdata()[0] == centre
        assert_looks_like(point, SADDLE_MARKER if round(centre / np.pi) % 2 else
                          ATTRACTOR_MARKER)
    assert "Full" in left.get_title() and "Linearised" in right.get_title()


def test_fig12_curves_are_the_saddle_closed_form():
    ax = figures.fig12_linearised_flow_near_saddle(small=True).axes[0]
    red, blue = curves(ax, "red"), curves(ax, "blue")
    assert (len(red), len(blue)) == (2, 4)
    t = np.linspace(-10.0, 10.0, 801)
    phi, theta_dot = linear.solve_saddle(0.0, 0.001, t, alpha=0.1, omega0=1.0)
    shown = np.isfinite(red[0].get_xdata())
    np.testing.assert_allclose(red[0].get_xdata()[shown], np.pi + phi[shown], atol=1e-14)
    np.testing.assert_allclose(red[0].get_ydata()[shown], theta_dot[shown], atol=1e-14)
    # The asymptotes cross at the saddle; the branches stay off it.
    for ln in blue:
        assert np.nanmin(np.hypot(ln.get_xdata() - np.pi, ln.get_ydata())) > 0.03
    # the six starting points, in the legend, each on its curve (at t = 0); the saddle
    (starts,) = [ln for ln in ax.lines if ln.get_label().startswith("starting points")]
    assert starts.get_label() in [t.get_text() for t in ax.get_legend().get_texts()]
    theta0, theta_dot0 = starts.get_xdata(), starts.get_ydata()
    np.testing.assert_allclose(sorted(zip(theta0 - np.pi, theta_dot0)),
                               [(-0.1, 0.0), (0.0, -0.07), (0.0, -0.001), (0.0, 0.001),
                                (0.0, 0.07), (0.1, 0.0)], atol=1e-15)
    for start, ln in zip(zip(theta0, theta_dot0), red + blue):
        assert np.nanmin(np.hypot(ln.get_xdata() - start[0], ln.get_ydata() - start[1])) < 1e-12
    (saddle,) = [ln for ln in markers(ax) if ln.get_label() == "saddle (π, 0)"]
    assert_looks_like(saddle, SADDLE_MARKER)


def test_figures_draw_into_given_axes():
    fig, ax = plt.subplots()
    assert figures.fig1_underdamped_angle(ax, small=True) is fig
    assert len(curves(ax)) == 3
    with pytest.raises(TypeError, match="Figure"):
        figures.fig10_flow_near_attractor_full_vs_linear(ax, small=True)
    with pytest.raises(TypeError, match="3-D"):
        figures.fig6_phase_curve_in_time_3d(ax, small=True)


@pytest.mark.slow
def test_write_all_writes_twelve_pngs(tmp_path):
    paths = figures.write_all(tmp_path / "figs", small=True)
    assert [p.name for p in paths] == [f"{stem}.png" for stem in figures.FIGURES]
    assert len(paths) == 12
    assert [p.name[:5] for p in paths] == [f"fig{i:02d}" for i in range(1, 13)]
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert p.stat().st_size > 5000
    assert not plt.get_fignums()  # write_all leaves no figures open
