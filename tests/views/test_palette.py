"""The basin palette (atlas.views.style.basin_colours): every basin of a figure a colour of its
own, far apart in CAM02-UCS (colorspacious, an implementation independent of the Oklab
arithmetic the palette is built with), also as readers with deuteranopia or protanopia see it
(the Machado, Oliveira & Fernandes 2009 simulation, at full severity); ±k paired by hue,
|k| by lightness."""

import colorspacious  # a dev dependency (pyproject.toml): CAM02-UCS and CVD simulation
import numpy as np
import pytest

from atlas.views.style import NO_LABEL_COLOR, basin_colours

#: Colour-vision simulations: (name, colorspacious CVD space or None for normal vision).
VISIONS = [("normal", None)] + [
    (kind, {"name": "sRGB1+CVD", "cvd_type": kind, "severity": 100})
    for kind in ("deuteranomaly", "protanomaly")]
#: The least CAM02-UCS ΔE required between two basins of one figure, for up to 9 wells
#: (K ≤ 4 per side: wells −K … K, the running basin, no label) and for 11 to 31 (K ≤ 15): a
#: ΔE of about 1 is a just noticeable difference of two patches side by side, 3.5 plainly
#: visible; past 16 wells the map also names each band. The palette reaches, maps (lines):
#: normal 24.5 (24.0) up to K = 4 and 5.1 (5.0) up to K = 15, deuteranopia 16.8 (15.6) and
#: 4.1 (3.8), protanopia 9.8 (10.7) and 5.0 (4.5).
LEAST_DELTA_E = {"normal": (20.0, 4.5), "deuteranomaly": (14.0, 3.5),
                 "protanomaly": (8.0, 3.5)}


def _rgb(colours: dict) -> tuple[list, np.ndarray]:
    keys = list(colours)
    return keys, np.array([[int(colours[k][i:i + 2], 16) / 255 for i in (1, 3, 5)]
                           for k in keys])


def _ucs(rgb: np.ndarray, cvd) -> np.ndarray:
    """CAM02-UCS (J', a', b') of sRGB colours (0…1), as a reader with ``cvd`` sees them."""
    if cvd is not None:
        rgb = np.clip(colorspacious.cspace_convert(rgb, cvd, "sRGB1"), 0, 1)
    return colorspacious.cspace_convert(rgb, "sRGB1", "CAM02-UCS")


def _least_distance(colours: dict, cvd) -> tuple[float, tuple]:
    keys, rgb = _rgb(colours)
    ucs = _ucs(rgb, cvd)
    d = np.sqrt(((ucs[:, None] - ucs[None]) ** 2).sum(-1))
    np.fill_diagonal(d, np.inf)
    i, j = np.unravel_index(d.argmin(), d.shape)
    return float(d[i, j]), (keys[i], keys[j])


@pytest.mark.parametrize("lines", [False, True], ids=["maps", "lines"])
@pytest.mark.parametrize("vision, cvd", VISIONS, ids=[v for v, _ in VISIONS])
def test_every_basin_of_a_figure_is_far_from_every_other(vision, cvd, lines):
    """1 to 31 wells, with the running basin and "no label": no two share a colour, and
    every pair is at least LEAST_DELTA_E apart (CAM02-UCS), for every vision."""
    for far in range(0, 16):
        colours = basin_colours(range(-far, far + 1), running=True, lines=lines)
        assert len(colours) == 2 * far + 3 and len(set(colours.values())) == len(colours)
        least, pair = _least_distance(colours, cvd)
        assert least >= LEAST_DELTA_E[vision][far > 4], (far, pair, least)


def test_a_figure_of_wells_on_one_side_only_is_distinct_too():
    """An asymmetric window (wells −1 … 13, as a torque map may show): still distinct."""
    colours = basin_colours(range(-1, 14), running=True)
    for _, cvd in VISIONS:
        assert _least_distance(colours, cvd)[0] >= 4.0


@pytest.mark.parametrize("vision, cvd", VISIONS[:2], ids=["normal", "deuteranomaly"])
def test_sign_is_the_hue_and_distance_the_lightness(vision, cvd):
    """Hue by sign: a line through grey in the (a', b') plane of CAM02-UCS parts the wells
    k > 0 from the wells k < 0, every one more than 3 from it (also as a deuteranope sees
    them); lightness by |k|: J' falls as |k| grows, on each side; a pair ±k is closer in
    lightness than half the step to the next pair."""
    far = 10
    keys, rgb = _rgb(basin_colours(range(-far, far + 1)))
    ucs = dict(zip(keys, _ucs(rgb, cvd)))
    positive = np.array([ucs[k][1:] for k in range(1, far + 1)])
    negative = np.array([ucs[-k][1:] for k in range(1, far + 1)])
    across = positive.mean(axis=0) - negative.mean(axis=0)
    across /= np.hypot(*across)
    assert (positive @ across).min() > 3 and (negative @ across).max() < -3
    for sign in (1, -1):
        lightness = [ucs[sign * j][0] for j in range(1, far + 1)]
        assert np.all(np.diff(lightness) < 0)
    if cvd is None:  # a pair ±j is closer in lightness than half the step to the next pair
        assert all(abs(ucs[j][0] - ucs[-j][0]) < 0.5 * (ucs[j][0] - ucs[j + 1][0])
                   for j in range(1, far))


def test_running_is_neutral_grey_and_no_label_white():
    colours = basin_colours([-1, 0, 1], running=True)
    r, g, b = (int(colours["running"][i:i + 2], 16) for i in (1, 3, 5))
    assert r == g == b and 60 < r < 200
    assert colours["none"] == NO_LABEL_COLOR == "#ffffff"
    assert "running" not in basin_colours([0])


def test_the_basin_map_draws_with_the_palette(tmp_path):
    """The colours the basin map's image shows are basin_colours' of its wells."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from atlas.views.maps import _draw_basin

    k = np.array([[-2.0, -1.0, 0.0], [1.0, 2.0, np.nan]])
    fig = Figure()
    ax = fig.add_subplot()
    _draw_basin(ax, (np.arange(3.0), np.arange(2.0)), (k, -2, 2, False), [], None, None, "t")
    image = ax.images[0]
    drawn = image.to_rgba(image.get_array(), bytes=True)[..., :3]
    palette = basin_colours(range(-2, 3))
    for (r, c), well in np.ndenumerate(k):
        hex_colour = palette["none" if np.isnan(well) else int(well)]
        expected = [int(hex_colour[i:i + 2], 16) for i in (1, 3, 5)]
        np.testing.assert_array_equal(drawn[r, c], expected)
