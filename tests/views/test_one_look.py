"""One meaning, one look: a saddle is SADDLE_MARKER (and a rest state ATTRACTOR_MARKER) on a
basin map, on a white page and in ``atlas orbit``'s figure, drawn whole where it sits on the
map's frame (the saddles ±3π of the default window); the page's data carry the figures' own
palette, colour maps and markers (the page's script keeps none of its own)."""

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.colors import to_hex  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from atlas.views import maps  # noqa: E402
from atlas.views.page import page_style  # noqa: E402
from atlas.views.style import (  # noqa: E402
    ATTRACTOR_MARKER,
    DISTANCE_CMAP,
    MAP_SIZE,
    ORBIT_START_MARKER,
    SADDLE_MARKER,
    T_TRAP_CMAP,
    WELL_CYCLE,
    colormap_table,
    critical_point_markers,
    well_colour,
)

PI = np.pi


def _markers(ax) -> dict:
    """The critical-point lines of ``ax`` by legend label: "saddles…" and "attractors…"."""
    return {line.get_label().split(" ")[0]: line for line in ax.lines
            if line.get_label().startswith(("saddles", "attractors"))}


def _looks_like(line, style: dict) -> bool:
    return (line.get_marker() == style["marker"] and line.get_markersize() == style["ms"]
            and to_hex(line.get_markerfacecolor()) == to_hex(style["mfc"])
            and to_hex(line.get_markeredgecolor()) == to_hex(style["mec"])
            and line.get_markeredgewidth() == style["mew"])


def test_a_saddle_looks_the_same_on_a_map_and_on_a_white_page():
    """The map's markers and the plain axes' (Figure 9, ``atlas orbit`` without a file) are
    the one SADDLE_MARKER and ATTRACTOR_MARKER (they were open white circles on the maps,
    red ones elsewhere)."""
    grid = (np.linspace(-3 * PI, 3 * PI, 31), np.linspace(-4.0, 4.0, 21))
    theta = np.arange(-3, 4) * PI
    critical = (theta, np.arange(-3, 4) % 2 != 0, False)
    on_map = Figure(figsize=MAP_SIZE).add_subplot()
    maps._draw_basin(on_map, grid, (np.zeros((21, 31)), 0, 0, False), [], critical, None,
                     "t")
    plain = Figure().add_subplot()
    critical_point_markers(plain, *critical[:2])
    for ax in (on_map, plain):
        found = _markers(ax)
        assert _looks_like(found["saddles"], SADDLE_MARKER)
        assert _looks_like(found["attractors"], ATTRACTOR_MARKER)
        np.testing.assert_array_equal(found["saddles"].get_xdata(), theta[::2])


def test_a_saddle_on_the_maps_edge_is_drawn_whole():
    """The default window −3π … 3π has saddles on its left and right edges: the half of each
    marker outside the frame is drawn too (its black ring, beside the frame)."""
    dpi = 100
    grid = (np.linspace(-3 * PI, 3 * PI, 61), np.linspace(-4.0, 4.0, 41))
    critical = (np.array([-3 * PI, -PI, PI, 3 * PI]), np.ones(4, bool), False)
    fig = Figure(figsize=MAP_SIZE, dpi=dpi)
    ax = fig.add_subplot()
    maps._draw_basin(ax, grid, (np.zeros((41, 61)), 0, 0, False), [], critical, None, "t")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    pixels = np.asarray(canvas.buffer_rgba())[..., :3].astype(int)
    # the ring's middle: the marker's radius (half its size, in points) from the centre
    ring = SADDLE_MARKER["ms"] / 2 * dpi / 72
    for theta, outward in ((-3 * PI, -1), (3 * PI, 1)):
        x, y = ax.transData.transform((theta, 0.0))
        assert (x + outward * ring > ax.bbox.x1) or (x + outward * ring < ax.bbox.x0)
        row, column = int(round(pixels.shape[0] - y)), int(round(x + outward * ring))
        assert pixels[row, column].max() < 100, (theta, pixels[row, column])


def test_a_zoom_off_the_theta_axis_draws_no_marker_outside_its_window():
    """A zoom window around θ̇0 = 2.41 rad/s holds no critical point: none is drawn (unclipped,
    one at θ̇ = 0 would sit far below the map, and the figure's tight layout failed), and
    the legend does not name them."""
    grid = (np.linspace(-0.5, 0.5, 21), np.linspace(2.4, 2.5, 21))
    critical = (np.array([-PI, 0.0, PI]), np.array([True, False, True]), False)
    fig = Figure(figsize=MAP_SIZE)
    ax = fig.add_subplot()
    maps._draw_basin(ax, grid, (np.zeros((21, 21)), 0, 0, False), [], critical, None, "t")
    assert _markers(ax) == {}
    box = fig.get_tightbbox(FigureCanvasAgg(fig).get_renderer())
    assert box.height < 2 * fig.get_figheight()  # nothing drawn far off the figure


def test_the_orbit_figure_has_no_colour_of_its_own_for_saddles(tmp_path, monkeypatch):
    """``atlas orbit`` without a file: its phase plane marks the saddles as SADDLE_MARKER and
    its θ(t) panel draws the saddles' levels in the marker's edge colour; nothing is red
    (the old figure's saddles were red, the maps' white); the orbit's start is no open circle
    (it looked like a saddle)."""
    from atlas.commands.orbit import report
    from atlas.commands.orbit_figure import plot_orbit

    saved = []
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: saved.append(fig))
    orbit, _, context = report(0.5, 2.6, alpha=0.1, omega0=1.0)
    plot_orbit(orbit, tmp_path / "o.png", context["tree"], context["index"])
    phase, angle = saved[0].axes[0], saved[0].axes[1]
    assert _looks_like(_markers(phase)["saddles"], SADDLE_MARKER)
    start = next(line for line in phase.lines if line.get_label().startswith("initial"))
    assert _looks_like(start, ORBIT_START_MARKER)  # a shape of its own: not a saddle's
    assert ORBIT_START_MARKER["marker"] != SADDLE_MARKER["marker"]
    levels = [line for line in angle.lines if line.get_linestyle() == ":"]
    assert levels and {to_hex(line.get_color()) for line in levels} == {
        to_hex(SADDLE_MARKER["mec"])}
    colours = {to_hex(c) for ax in saved[0].axes for line in ax.lines
               for c in (line.get_color(), line.get_markerfacecolor(),
                         line.get_markeredgecolor())}
    assert to_hex("red") not in colours


def test_the_page_carries_the_figures_palette_maps_and_markers():
    """The page's data (:func:`page_style`) hold the same colour of every k as the PNGs
    (looked up the script's way: by sign, then (|k| − 1) mod cycle), the PNGs' colour maps
    and the one saddle marker."""
    style = page_style()
    palette = style["palette"]
    assert palette["cycle"] == WELL_CYCLE
    for k in range(-40, 41):
        table = palette["positive"] if k > 0 else palette["negative"]
        page = palette["zero"] if k == 0 else table[(abs(k) - 1) % palette["cycle"]]
        assert page == well_colour(k), k
    for layer, name in (("t_trap", T_TRAP_CMAP), ("distance", DISTANCE_CMAP)):
        packed = style["colormaps"][layer]
        assert ["#" + packed[i:i + 6] for i in range(0, len(packed), 6)] == colormap_table(name)
    saddle = style["markers"]["saddle"]
    assert (saddle["fill"], saddle["edge"], saddle["size"], saddle["width"]) == (
        SADDLE_MARKER["mfc"], SADDLE_MARKER["mec"], SADDLE_MARKER["ms"],
        SADDLE_MARKER["mew"])
