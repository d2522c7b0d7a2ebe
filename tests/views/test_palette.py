"""The basin palette (atlas.views.style.well_colour, basin_colours): the colour of a well is a
function of k alone, the same in every figure; neighbouring wells far apart and every well
of a figure distinct, in CAM02-UCS (colorspacious, an implementation independent of the
Oklab arithmetic the palette is built with), also as readers with deuteranopia or protanopia
see it (the Machado, Oliveira & Fernandes 2009 simulation, at full severity); ±k paired by
hue, neighbours told apart by lightness. And the colour maps of the t_trap and distance maps,
whose colours cannot be taken for the special ones (no label, running, closer than d_cert)."""

import colorspacious  # a dev dependency (pyproject.toml): CAM02-UCS and CVD simulation
import numpy as np
import pytest

from atlas.views.style import (
    DISTANCE_CMAP,
    NEAR_BOUNDARY_COLOR,
    NO_LABEL_COLOR,
    RUNNING_COLOR_HEX,
    T_TRAP_CMAP,
    WELL_CYCLE,
    attractor_colours,
    basin_colours,
    colormap_table,
    well_colour,
)

#: Colour-vision simulations: (name, colorspacious CVD space or None for normal vision).
VISIONS = [("normal", None)] + [
    (kind, {"name": "sRGB1+CVD", "cvd_type": kind, "severity": 100})
    for kind in ("deuteranomaly", "protanomaly")]
#: The least CAM02-UCS ΔE between two neighbouring wells k, k + 1 (whose bands touch on every
#: map), in every vision: a ΔE of about 1 is a just noticeable difference of two patches side
#: by side, 3.5 plainly visible; the old palette, which spread its lightness over the
#: figure's wells, left neighbours about 5 apart with 27 wells. The palette reaches 27.6
#: (maps, deuteranopia) and 28.6 (lines, protanopia).
LEAST_NEIGHBOUR_DELTA_E = 20.0
#: The least ΔE between any two basins of a figure of every well of a cycle (wells
#: −WELL_CYCLE … WELL_CYCLE, the running basin, no label): distinct, if not at a glance (such
#: a map names its bands). The palette reaches, maps (lines): normal 5.0 (4.0), deuteranopia
#: 3.8 (3.6), protanopia 3.0 (4.0).
LEAST_DELTA_E = {"normal": 4.0, "deuteranomaly": 3.0, "protanomaly": 2.5}
#: The least ΔE between any two basins of the default map (wells −4 … 4, the running basin,
#: no label): every class told apart at a glance, also across the map (not only neighbours).
#: 15 is about three times the 3.5 of "plainly visible" for normal vision; under deuteranopia
#: and protanopia the wells of one sign differ in lightness and in yellow–blue only, and 8 is
#: what the palette keeps with a margin (it reaches normal 16.8, deuteranopia 12.1,
#: protanopia 9.0: k = −1 against no-label white). The palette of 14 wells per cycle, hue and
#: lightness turning slowly with |k|, reached 6.6, 4.0 and 6.2 (k = −3 and −1; 1 and 3).
DEFAULT_MAP_WELLS, LEAST_DEFAULT_MAP_DELTA_E = range(-4, 5), {
    "normal": 15.0, "deuteranomaly": 8.0, "protanomaly": 8.0}
#: The same for the lines (lines=True: the fraction curves, atlas orbit's figure) of the wells
#: −6 … 6 and the running basin's line, on a white page: the palette reaches normal 12.6,
#: deuteranopia 5.5, protanopia 7.9 (the old one 6.9, 3.6 and 5.4: k = 2 and 4, 3 and 5, 1
#: and 3, all nearly the same dark olive or pale gold); thin lines are told apart also by the
#: legend, hence the lower bounds.
CURVE_WELLS, LEAST_CURVE_DELTA_E = range(-6, 7), {
    "normal": 12.0, "deuteranomaly": 5.0, "protanomaly": 7.0}


def _rgb(colours: list[str]) -> np.ndarray:
    return np.array([[int(c[i:i + 2], 16) / 255 for i in (1, 3, 5)] for c in colours])


def _ucs(colours: list[str], cvd) -> np.ndarray:
    """CAM02-UCS (J', a', b') of "#rrggbb" colours, as a reader with ``cvd`` sees them."""
    rgb = _rgb(colours)
    if cvd is not None:
        rgb = np.clip(colorspacious.cspace_convert(rgb, cvd, "sRGB1"), 0, 1)
    return colorspacious.cspace_convert(rgb, "sRGB1", "CAM02-UCS")


def _distances(colours: list[str], cvd) -> np.ndarray:
    ucs = _ucs(colours, cvd)
    return np.sqrt(((ucs[:, None] - ucs[None]) ** 2).sum(-1))


def _closest_pair(colours: dict, cvd) -> tuple:
    """(key, key, ΔE) of the two nearest of ``colours`` (CAM02-UCS, under ``cvd``)."""
    keys = list(colours)
    d = _distances(list(colours.values()), cvd)
    np.fill_diagonal(d, np.inf)
    i, j = np.unravel_index(d.argmin(), d.shape)
    return keys[i], keys[j], d[i, j]


@pytest.mark.parametrize("lines", [False, True], ids=["maps", "lines"])
def test_a_wells_colour_is_the_same_whatever_the_figure_holds(lines):
    """The colour of k does not depend on the other wells of the figure (the 11-α atlas
    drew k = +2 pale gold, the default map orange)."""
    everything = basin_colours(range(-60, 61), running=True, lines=lines)
    for ks in ([2], range(-2, 3), range(-13, 14), range(-1, 14), [-7, 0, 30], range(0, 60)):
        colours = basin_colours(ks, running=True, lines=lines)
        assert all(colours[k] == everything[k] == well_colour(k, lines) for k in ks), ks
        assert colours["running"] == everything["running"]


@pytest.mark.parametrize("lines", [False, True], ids=["maps", "lines"])
@pytest.mark.parametrize("vision, cvd", VISIONS, ids=[v for v, _ in VISIONS])
def test_neighbouring_wells_are_far_apart(vision, cvd, lines):
    """k and k + 1 for every k in −40 … 40 (through 0 and through the palette's repeat at
    ±WELL_CYCLE): at least LEAST_NEIGHBOUR_DELTA_E apart, for every vision."""
    ks = range(-40, 41)
    d = _distances([well_colour(k, lines) for k in ks], cvd)
    steps = np.diagonal(d, offset=1)
    worst = int(steps.argmin())
    assert steps.min() >= LEAST_NEIGHBOUR_DELTA_E, (ks[worst], ks[worst + 1], steps.min())


@pytest.mark.parametrize("lines", [False, True], ids=["maps", "lines"])
@pytest.mark.parametrize("vision, cvd", VISIONS, ids=[v for v, _ in VISIONS])
def test_every_basin_of_a_figure_is_distinct(vision, cvd, lines):
    """The wells −WELL_CYCLE … WELL_CYCLE, the running basin and "no label": no two share a
    colour, every pair at least LEAST_DELTA_E apart."""
    colours = basin_colours(range(-WELL_CYCLE, WELL_CYCLE + 1), running=True, lines=lines)
    assert len(set(colours.values())) == len(colours) == 2 * WELL_CYCLE + 3
    *pair, least = _closest_pair(colours, cvd)
    assert least >= LEAST_DELTA_E[vision], (*pair, least)


@pytest.mark.parametrize("vision, cvd", VISIONS, ids=[v for v, _ in VISIONS])
def test_every_class_of_the_default_map_is_distinct_at_a_glance(vision, cvd):
    """Every pair of the default map's classes (wells −4 … 4, running, no label), not only
    neighbours, at least LEAST_DEFAULT_MAP_DELTA_E apart (the old palette drew k = −2 and −4
    nearly the same teal, +1 and +3 both pale yellow, +2 and +4 both olive)."""
    colours = basin_colours(DEFAULT_MAP_WELLS, running=True)
    *pair, least = _closest_pair(colours, cvd)
    assert least >= LEAST_DEFAULT_MAP_DELTA_E[vision], (*pair, least)


@pytest.mark.parametrize("vision, cvd", VISIONS, ids=[v for v, _ in VISIONS])
def test_every_line_of_a_curve_figure_is_distinct(vision, cvd):
    """The lines=True colours of the wells −6 … 6 and of the running basin: every pair at
    least LEAST_CURVE_DELTA_E apart (the old ones drew k = ±2, ±4, ±6 nearly the same dark
    olive)."""
    colours = basin_colours(CURVE_WELLS, running=True, lines=True)
    del colours["none"]  # no curve of its own
    *pair, least = _closest_pair(colours, cvd)
    assert least >= LEAST_CURVE_DELTA_E[vision], (*pair, least)


def test_the_palette_repeats_every_cycle_on_each_side():
    """Past ±WELL_CYCLE the sequence starts again (so that a map of any width has colours),
    the sign's hue family kept: the key and the band names tell such wells apart."""
    for k in range(1, 3 * WELL_CYCLE):
        assert well_colour(k + WELL_CYCLE) == well_colour(k)
        assert well_colour(-k - WELL_CYCLE) == well_colour(-k)
    assert well_colour(1) != well_colour(-1)


@pytest.mark.parametrize("vision, cvd", VISIONS[:2], ids=["normal", "deuteranomaly"])
def test_sign_is_the_hue_and_parity_the_lightness(vision, cvd):
    """Hue by sign: a line through grey in the (a', b') plane of CAM02-UCS parts the wells
    k > 0 from the wells k < 0, every one more than 3 from it (more than 1 as a deuteranope
    sees them: the rose wells of k > 0, |k| = 3, 5, 9, 11, are near-grey to a deuteranope,
    though still on the warm side, and told apart from the cool wells of their lightness by
    the distance tests above); lightness by parity: every odd |k| lighter than every even
    |k| (neighbours differ most in what every reader sees), and the four wells of each sign
    in the default map's −4 … 4 at four lightnesses at least 15 apart in J' (told apart by
    lightness alone); a pair
    ±j closer in lightness than half the step to the next well."""
    ks = range(-WELL_CYCLE, WELL_CYCLE + 1)
    ucs = dict(zip(ks, _ucs([well_colour(k) for k in ks], cvd)))
    positive = np.array([ucs[k][1:] for k in range(1, WELL_CYCLE + 1)])
    negative = np.array([ucs[-k][1:] for k in range(1, WELL_CYCLE + 1)])
    across = positive.mean(axis=0) - negative.mean(axis=0)
    across /= np.hypot(*across)
    margin = 3 if cvd is None else 1
    assert (positive @ across).min() > margin and (negative @ across).max() < -margin
    for sign in (1, -1):
        odd = [ucs[sign * j][0] for j in range(1, WELL_CYCLE + 1, 2)]
        even = [ucs[sign * j][0] for j in range(2, WELL_CYCLE + 1, 2)]
        assert min(odd) > max(even)
        near = np.sort([ucs[sign * j][0] for j in range(1, 5)])
        assert np.diff(near).min() >= 15, near
    if cvd is None:
        assert all(abs(ucs[j][0] - ucs[-j][0]) < 0.5 * abs(ucs[j][0] - ucs[j + 1][0])
                   for j in range(1, WELL_CYCLE))


def test_running_is_neutral_grey_and_no_label_white():
    colours = basin_colours([-1, 0, 1], running=True)
    r, g, b = (int(colours["running"][i:i + 2], 16) for i in (1, 3, 5))
    assert r == g == b and 60 < r < 200
    assert colours["running"] == RUNNING_COLOR_HEX
    assert colours["none"] == NO_LABEL_COLOR == "#ffffff"
    assert "running" not in basin_colours([0])


@pytest.mark.parametrize("name", [T_TRAP_CMAP, DISTANCE_CMAP])
@pytest.mark.parametrize("vision, cvd", VISIONS, ids=[v for v, _ in VISIONS])
def test_the_colour_maps_cannot_be_taken_for_the_special_colours(name, vision, cvd):
    """Every colour of the t_trap and distance maps is far (ΔE ≥ 20) from "no label" white
    and from the d_cert black; their ends (the lowest and highest tenth, where t = 0 and the
    longest times sit) far from the running basin's grey (magma's pale top looked white;
    t = 0 was drawn in a grey like the running basin's)."""
    table = colormap_table(name)
    ucs = _ucs(table, cvd)
    special = _ucs([NO_LABEL_COLOR, NEAR_BOUNDARY_COLOR, RUNNING_COLOR_HEX], cvd)
    d = np.sqrt(((ucs[:, None] - special[None]) ** 2).sum(-1))
    assert d[:, :2].min() >= 20.0, d[:, :2].min(axis=0)
    tenth = len(table) // 10
    assert np.r_[d[:tenth, 2], d[-tenth:, 2]].min() >= 20.0
    assert T_TRAP_CMAP != DISTANCE_CMAP  # two quantities, two maps


def test_the_colour_map_tables_are_matplotlibs():
    """The page's tables sample the PNGs' colour maps at their ends and evenly between."""
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    for name in (T_TRAP_CMAP, DISTANCE_CMAP):
        table = colormap_table(name)
        assert len(table) == 256
        assert table[0] == to_hex(colormaps[name](0.0))
        assert table[-1] == to_hex(colormaps[name](1.0))
        assert table[100] == to_hex(colormaps[name](100 / 255))


@pytest.mark.parametrize("wells", [(-2, 2), (-13, 13), (2, 5)], ids=str)
def test_the_basin_map_draws_each_well_in_its_own_colour(wells):
    """The colours the basin map's image shows are well_colour's of each k, whatever range
    of wells the map holds (a planted palette that spreads its colours over the map's wells
    draws k = 2 differently in the three maps)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from atlas.views.maps import _draw_basin

    kmin, kmax = wells
    k = np.array([[kmin, 2.0, kmax], [kmax, 2.0, np.nan]])
    ax = Figure().add_subplot()
    _draw_basin(ax, (np.arange(3.0), np.arange(2.0)), (k, kmin, kmax, False), [], None, None,
                "t")
    image = ax.images[0]
    drawn = image.to_rgba(image.get_array(), bytes=True)[..., :3]
    for (r, c), well in np.ndenumerate(k):
        colour = NO_LABEL_COLOR if np.isnan(well) else well_colour(int(well))
        np.testing.assert_array_equal(drawn[r, c], _rgb([colour])[0] * 255)


#: A driven pendulum's attractors of every kind: two oscillations (mirror twins, as at
#: F = 1.71), a rotation each way and a chaotic attractor, with no label.
DRIVEN_KINDS = (["periodic", "periodic", "periodic", "periodic", "chaotic"], [0, 0, -2, 2, 0])


def _hue_chroma(colour: str) -> tuple[float, float]:
    """CIECAM02 hue [deg] and chroma of an sRGB colour (colorspacious: independent of the
    Oklab arithmetic the palette is built with)."""
    jch = colorspacious.cspace_convert(_rgb([colour])[0], "sRGB1", "JCh")
    return float(jch[2]), float(jch[1])


def test_a_driven_attractors_colour_family_is_its_kind():
    """Oscillations green (the first one k = 0's green), rotations with winding > 0 warm and
    < 0 cool (the wells' families: the i-th of a sign is well ±i's colour), chaotic ones
    grey (no chroma); two attractors of one kind differ, and every attractor of the set and
    no-label white are told apart at a glance, as the default map's classes, for every
    vision."""
    colours = attractor_colours(*DRIVEN_KINDS)
    assert colours[0] == well_colour(0)
    assert colours[2] == well_colour(-1) and colours[3] == well_colour(1)
    green, _ = _hue_chroma(colours[0])
    twin_hue, twin_chroma = _hue_chroma(colours[1])
    assert abs(twin_hue - green) < 25 and twin_chroma > 20 and colours[1] != colours[0]
    assert _hue_chroma(colours[4])[1] < 4  # a neutral sRGB grey: CIECAM02 C ≈ 2.6
    for vision, cvd in VISIONS:  # at a glance, as the default map's classes
        d = _distances(colours + [NO_LABEL_COLOR], cvd)
        assert d[np.triu_indices(len(d), 1)].min() > LEAST_DEFAULT_MAP_DELTA_E[vision], d
