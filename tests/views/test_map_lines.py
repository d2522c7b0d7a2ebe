"""What the basin maps draw over their colours: separatrices that a thin tongue of a basin can
be seen through, band names past LABELLED_WELLS wells, a distance scale that spreads its
values, and words that say what is drawn."""

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from atlas.views import maps, plotting  # noqa: E402
from atlas.views.style import LABELLED_WELLS, MAP_SIZE, basin_colours  # noqa: E402


def _tongue_scene(n=400, rows=(199, 202)):
    """A map of well 0 with a tongue of well 1 three grid rows high across it, its two
    separatrices along the tongue's edges."""
    grid = np.linspace(0.0, 1.0, n)
    k = np.zeros((n, n))
    k[slice(*rows)] = 1.0
    half = 0.5 / (n - 1)
    edges = (grid[rows[0]] - half, grid[rows[1] - 1] + half)
    return {"grid": (grid, grid), "image": (k, 0, 1, False),
            "separatrices": [(grid, np.full(n, y)) for y in edges], "critical": None,
            "cycle": None, "title": "a tongue"}, rows[1] - rows[0]


def test_a_tongue_four_pixels_high_keeps_its_colour_between_its_outlines():
    """A tongue about 4 pixels high in the saved PNG, bounded by its two separatrices: at
    least half of its pixel rows show the tongue's own colour (the old red lines, 1.2 pt
    each, left one row of it)."""
    scene, tongue_rows = _tongue_scene()
    drawn = []

    def draw(ax, **scene):
        drawn.append(ax)
        return maps._draw_basin(ax, **scene)

    png = io.BytesIO()
    plotting._draw_figure(png, MAP_SIZE, draw, scene)
    png.seek(0)
    image = np.round(plt.imread(png)[..., :3] * 255)
    tongue_pixels = tongue_rows * drawn[0].get_window_extent().height / 399
    assert 3.5 < tongue_pixels < 6
    column = image[:, image.shape[1] // 3]
    colour = basin_colours([0, 1])[1]
    target = np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)])
    kept = np.all(np.abs(column - target) <= 12, axis=1).sum()
    assert kept >= 0.5 * tongue_pixels


def test_bands_are_named_past_sixteen_wells_and_not_before():
    """20 horizontal bands (wells −10 … 9), ten grid rows each: each named "k = …" inside its
    own band; with 12 wells, none named (the colours suffice)."""
    for wells, named in ((20, True), (12, False)):
        ks = np.arange(-10, wells - 10)
        k = np.repeat(ks, 10)[:, None] * np.ones((1, 40))
        theta, theta_dot = np.linspace(0, 1, 40), np.arange(k.shape[0], dtype=float)
        ax = Figure(figsize=MAP_SIZE).add_subplot()
        maps._draw_basin(ax, (theta, theta_dot), (k, int(ks[0]), int(ks[-1]), False), [],
                         None, None, "bands")
        texts = {t.get_text(): t.get_position() for t in ax.texts}
        assert (len(ks) > LABELLED_WELLS) == named
        if named:
            for j in ks:
                name = f"k = {j:+d}".replace("+0", "0").replace("-", "−")
                row = texts[name][1]
                assert np.all(k[int(round(row))] == j), name


#: The title line of a parameter point, as :func:`atlas.views.style.point_title` writes it.
POINT = "α = 0.35 s⁻¹, ω0 = 1 rad/s"


def _distance_scene(d_cert):
    """The distance to the line θ̇ = 0.5 of a 200 × 200 grid of the unit square (exact:
    |θ̇ − 0.5|), its boundary drawn."""
    grid = np.linspace(0.0, 1.0, 200)
    d = np.abs(grid[:, None] - 0.5) * np.ones((1, 200))
    return {"grid": (grid, grid), "image": (d, d[d > 0].min(), d.max()),
            "separatrices": [(grid, np.full(200, 0.5))], "d_cert": d_cert,
            "point": POINT}


def test_the_distance_scale_spreads_its_values():
    """No tenth of the colour scale holds half the map (from d_cert to the largest distance
    the top tenth held 87 %), and the colour bar says how its limits were chosen."""
    scene = _distance_scene(1e-9)
    ax = Figure(figsize=MAP_SIZE).add_subplot()
    maps._draw_boundary_distance(ax, **scene)
    norm = ax.images[0].norm
    d = scene["image"][0]
    position = np.clip(norm(d[d > 0]), 0, 0.9999)
    shares = np.histogram(position, bins=10, range=(0, 1))[0] / position.size
    assert shares.max() < 0.5
    label = ax.figure.axes[-1].get_ylabel()
    assert "percentile" in label and "rad-ish" not in label and "Euclidean" in label


def test_the_distance_title_says_what_black_means():
    """d_cert measured and met: black is closer than d_cert (white is "no label" on every
    map); not met: none is; not measured: said so, never "closer than d_cert not
    measured"."""
    titles = {}
    for name, d_cert in (("met", 0.01), ("none", 1e-9), ("nan", float("nan"))):
        ax = Figure(figsize=MAP_SIZE).add_subplot()
        maps._draw_boundary_distance(ax, **_distance_scene(d_cert))
        titles[name] = ax.get_title()
    assert "black: closer than d_cert = 1.0e-02" in titles["met"]
    assert all(POINT in title for title in titles.values())
    assert "none closer than d_cert = 1.0e-09" in titles["none"]
    assert "d_cert not measured" in titles["nan"] and "closer than" not in titles["nan"]


def test_the_trap_time_map_says_running_orbits_are_certified_too():
    """t_trap is the time a label was certified, trapped or running: the colour bar says so,
    and white (no value) is no label, not 'never trapped'."""
    grid = np.linspace(0.0, 1.0, 20)
    t = np.outer(grid, grid) * 10
    ax = Figure(figsize=MAP_SIZE).add_subplot()
    maps._draw_trap_time(ax, (grid, grid), (t, 0.01, 10.0), [], POINT)
    assert "running" in ax.figure.axes[-1].get_ylabel()
    assert "no label" in ax.get_title() and "never" not in ax.get_title()
    assert POINT in ax.get_title()


def test_band_names_keep_off_the_rest_states_and_saddles():
    """The markers of the rest states and saddles lie on θ̇ = 0: a band that is deep enough
    elsewhere is named away from that row (here the well-0 band spans θ̇ ∈ [−15, 15], its
    deepest pixel on θ̇ = 0), and still inside its own band."""
    ks = np.arange(-10, 10)
    widths = np.where(ks == 0, 31, 6)
    k = np.repeat(ks, widths)[:, None] * np.ones((1, 40))
    rows = k.shape[0]
    zero = int(np.flatnonzero(k[:, 0] == 0).mean())
    theta, theta_dot = np.linspace(0, 1, 40), np.arange(rows, dtype=float) - zero
    ax = Figure(figsize=MAP_SIZE).add_subplot()
    maps._draw_basin(ax, (theta, theta_dot), (k, -10, 9, False), [], None, None, "bands")
    v = {t.get_text(): t.get_position()[1] for t in ax.texts}["k = 0"]
    assert abs(v) > 0.06 * (theta_dot[-1] - theta_dot[0])
    assert np.all(k[int(round(v + zero))] == 0)


def test_the_trap_time_map_draws_t0_at_its_dark_end_and_no_label_white():
    """t_trap = 0 (certified at once) is the colour map's own dark end, not a grey like the
    running basin's; no certified label (NaN) is white, as on the basin map."""
    from matplotlib import colormaps
    from matplotlib.colors import to_rgba

    from atlas.views.style import NO_LABEL_COLOR, T_TRAP_CMAP

    grid = np.linspace(0.0, 1.0, 4)
    t = np.array([[0.0, 1.0, 10.0, np.nan]] * 4)
    ax = Figure(figsize=MAP_SIZE).add_subplot()
    maps._draw_trap_time(ax, (grid, grid), (t, 1.0, 10.0), [], POINT)
    image = ax.images[0]
    drawn = image.to_rgba(image.get_array())[0]
    np.testing.assert_allclose(drawn[0], colormaps[T_TRAP_CMAP](0.0))
    np.testing.assert_allclose(drawn[2], colormaps[T_TRAP_CMAP](1.0))
    np.testing.assert_allclose(drawn[3], to_rgba(NO_LABEL_COLOR))


def test_the_distance_map_draws_near_states_black_and_missing_ones_white():
    """Closer than d_cert: NEAR_BOUNDARY_COLOR (black) over the map; no distance stored: the
    "no label" white, never the running basin's grey."""
    from matplotlib.colors import to_rgba

    from atlas.views.style import NEAR_BOUNDARY_COLOR, NO_LABEL_COLOR

    scene = _distance_scene(0.01)
    d = scene["image"][0].copy()
    d[:5] = np.nan
    scene["image"] = (d, *scene["image"][1:])
    ax = Figure(figsize=MAP_SIZE).add_subplot()
    maps._draw_boundary_distance(ax, **scene)
    base, near = ax.images
    np.testing.assert_allclose(base.to_rgba(base.get_array())[0, 0], to_rgba(NO_LABEL_COLOR))
    rows = np.flatnonzero(d[:, 0] <= 0.01)
    np.testing.assert_allclose(near.to_rgba(near.get_array())[rows[0], 0],
                               to_rgba(NEAR_BOUNDARY_COLOR))
    assert "white: no distance stored" in ax.get_title()
