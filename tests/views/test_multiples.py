"""`atlas plot` of a parameter atlas: small multiples of the basin maps (one panel per point,
one colour key), and `--point` / `--alpha` / `--torque` / `--omega0` choosing the points
drawn as full maps (inspect the Axes; the PNGs were looked at)."""

import io
from contextlib import redirect_stderr

import matplotlib

matplotlib.use("Agg")
import matplotlib.image  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import atlas  # noqa: E402
from atlas.cli import main  # noqa: E402
from atlas.status import NEAR_BOUNDARY, RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED  # noqa: E402
from atlas.views import multiples  # noqa: E402
from atlas.views.multiples import chosen_panels, draw_multiples, multiples_scene  # noqa: E402
from atlas.views.style import basin_colours  # noqa: E402
from tests.helpers import small_atlas  # noqa: E402

ALPHAS = (0.2, 0.5, 2.0)


@pytest.fixture(scope="module")
def alpha_atlas(tmp_path_factory):
    """Three damping values, 24 × 24 orbits of the window 6π × 8 rad/s, separatrices off."""
    tmp = tmp_path_factory.mktemp("multiples")
    small_atlas(tmp, "alphas", {"alpha": list(ALPHAS), "omega0": 1.0},
                theta=("-3pi", "3pi"), speed=(-4.0, 4.0), num=(24, 24), t_max=100.0,
                separatrices=False)
    return tmp / "alphas.h5"


@pytest.fixture(scope="module")
def torque_atlas(tmp_path_factory):
    """Two torques: τ = 0 (wells only) and τ = 1.5 > ω0² (no rest state: every orbit runs)."""
    tmp = tmp_path_factory.mktemp("multiples_torque")
    small_atlas(tmp, "torques", {"alpha": 0.5, "omega0": 1.0, "torque": [0.0, 1.5]},
                theta=("-3pi", "3pi"), speed=(-4.0, 4.0), num=(24, 24), t_max=60.0,
                separatrices=False)
    return tmp / "torques.h5"


def _drawn(path, monkeypatch=None, most=None):
    """The panels and the figure of the small multiples of the atlas at ``path``."""
    if most is not None:
        monkeypatch.setattr(multiples, "MAX_PANELS", most)
    with atlas.open(path) as tree:
        scene = multiples_scene(tree)
        data = tree.to_dataset(inherit=False).load()
    fig = Figure()
    return draw_multiples(fig.add_subplot(), **scene), fig, data, scene


def _wells(attractor, status):
    """The map as drawn: k where a well label is certified, NaN elsewhere (the file's own
    labels, not the figure's reading of them)."""
    return np.where(np.isin(status, (TRAPPED, NEAR_BOUNDARY)), attractor, np.nan)


def test_one_panel_per_point_with_its_parameter_and_its_own_map(alpha_atlas):
    panels, fig, ds, scene = _drawn(alpha_atlas)
    assert [ax.get_title() for ax in panels] == ["α = 0.2 s⁻¹  (#0)", "α = 0.5 s⁻¹  (#1)",
                                                 "α = 2 s⁻¹  (#2)"]
    assert "all 3 parameter points" in fig.get_suptitle()
    assert "ω0 = 1 rad/s" in fig.get_suptitle()
    for i, ax in enumerate(panels):
        point = ds.isel(alpha=i)
        np.testing.assert_array_equal(
            np.ma.filled(np.ma.masked_invalid(ax.images[0].get_array()), np.nan),
            _wells(point["attractor"].values, point["status"].values))
    # the θ axis is labelled once per column at the bottom, θ̇ once per row at the left
    assert panels[0].get_ylabel() and not panels[1].get_ylabel()
    assert all(ax.get_xlabel() for ax in panels)


def test_one_colour_key_for_every_panel_distinct_per_well(alpha_atlas):
    """Every well any point reaches is in the key once, its colour that of the basin palette
    for the whole figure, the same in every panel; no two wells share a colour."""
    panels, fig, ds, _ = _drawn(alpha_atlas)
    labelled = np.isin(ds["status"].values, (TRAPPED, NEAR_BOUNDARY))
    k = ds["attractor"].values[labelled]
    wells = list(range(int(k.min()), int(k.max()) + 1))
    key = fig.axes[-1]
    assert key not in panels
    names = [t.get_text() for t in key.get_yticklabels()]
    expected = [f"{w:+d}".replace("+0", "0").replace("-", "−") for w in wells]
    assert names[:len(wells)] == expected
    palette = basin_colours(wells)
    for ax in panels:
        image = ax.images[0]
        assert image.norm is panels[0].images[0].norm and image.cmap is panels[0].images[0].cmap
        drawn = [matplotlib.colors.to_hex(image.cmap(image.norm(w))) for w in wells]
        assert drawn == [palette[w] for w in wells]
    assert len({palette[w] for w in wells}) == len(wells)


@pytest.mark.parametrize("figure", ["trap_time", "boundary_distance", "basin"])
def test_each_map_of_a_parameter_atlas_names_its_point(alpha_atlas, figure):
    """The t_trap and distance maps of each α (and the basin map) say which α they show:
    every α's value is in its own map's title, and in no other's."""
    from atlas.layout import points
    from atlas.views.maps import MAP_FIGURES
    from atlas.views.selectors import point_index

    read, draw = MAP_FIGURES[figure]
    titles = []
    with atlas.open(alpha_atlas) as tree:
        ds = tree.to_dataset(inherit=False)
        for point in points(ds):
            ax = Figure().add_subplot()
            draw(ax, **read(tree, None, **point_index(ds, point)))
            titles.append(ax.get_title())
    for alpha, title in zip(ALPHAS, titles):
        named = [a for a in ALPHAS if f"α = {a:g} s⁻¹" in title]
        assert named == [alpha], title
        assert "ω0 = 1 rad/s" in title


def test_the_running_basin_has_one_colour_across_panels(torque_atlas):
    """τ = 0 has wells and no running basin, τ = 1.5 only the running basin: its panel is
    drawn in the key's "running" colour everywhere the file says running."""
    panels, fig, ds, _ = _drawn(torque_atlas)
    assert [ax.get_title() for ax in panels] == ["τ = 0 rad/s²  (#0)", "τ = 1.5 rad/s²  (#1)"]
    status = ds["status"].isel(torque=1).values
    assert np.all(np.isin(status, (RUNNING, RUNNING_NEAR_BOUNDARY)))  # the case it tests
    key = fig.axes[-1]
    ticks = {t.get_text(): v for t, v in zip(key.get_yticklabels(), key.get_yticks())}
    image = panels[1].images[0]
    np.testing.assert_array_equal(np.asarray(image.get_array()), ticks["running"])
    wells = [int(v) for name, v in ticks.items() if name not in ("running", "no label")]
    colour = matplotlib.colors.to_hex(image.cmap(image.norm(ticks["running"])))
    assert colour == basin_colours(wells, running=True)["running"]
    assert colour not in [matplotlib.colors.to_hex(image.cmap(image.norm(w))) for w in wells]


def test_past_the_cap_the_points_are_chosen_evenly_and_named(alpha_atlas, monkeypatch):
    assert chosen_panels(11) == list(range(11))
    chosen = chosen_panels(19, 12)
    gaps = np.diff(chosen)
    assert len(chosen) == 12 and chosen[0] == 0 and chosen[-1] == 18
    assert gaps.min() >= 1 and gaps.max() - gaps.min() <= 1  # as even as integers allow
    panels, fig, _, _ = _drawn(alpha_atlas, monkeypatch, most=2)
    assert [ax.get_title() for ax in panels] == ["α = 0.2 s⁻¹  (#0)", "α = 2 s⁻¹  (#2)"]
    assert "2 of 3 parameter points, chosen evenly (#0, 2;" in fig.get_suptitle()


def _plot(path, *options):
    """`atlas plot PATH OPTIONS` in this process: (exit status, stderr)."""
    err = io.StringIO()
    with redirect_stderr(err):
        code = main(["plot", str(path), *map(str, options)])
    return code, err.getvalue()


@pytest.mark.slow
def test_selectors_draw_the_nearest_points_as_full_maps(alpha_atlas, tmp_path):
    """--alpha takes the nearest stored value (0.3 → 0.2, 1.9 → 2); --point an index (−1 the
    last); only those points' three maps are written, named by their α."""
    assert _plot(alpha_atlas, "--outdir", tmp_path / "a", "--alpha", 0.3, "--alpha",
                 1.9) == (0, "")
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == sorted(
        f"alphas_alpha_{a}{suffix}.png" for a in ("0.2", "2")
        for suffix in ("", "_t_trap", "_boundary_distance"))
    assert _plot(alpha_atlas, "--outdir", tmp_path / "p", "--point", -1) == (0, "")
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == [
        "alphas_alpha_2.png", "alphas_alpha_2_boundary_distance.png",
        "alphas_alpha_2_t_trap.png"]
    image = matplotlib.image.imread(tmp_path / "p" / "alphas_alpha_2.png")
    assert image.shape[0] > 300  # a full map, not a panel


@pytest.mark.parametrize("options,names", [
    (("--alpha", 2.5), ("--alpha 2.5", "0.2 to 2")),
    (("--alpha", 0.1), ("--alpha 0.1", "0.2 to 2")),
    (("--torque", 0.1), ("--torque 0.1", "one torque, 0")),
    (("--point", 3), ("--point 3", "0 to 2")),
    (("--point", 0, "--alpha", 0.2), ("--point", "not both")),
])
def test_a_point_the_atlas_does_not_hold_is_one_line_and_nothing_written(
        alpha_atlas, tmp_path, options, names):
    code, err = _plot(alpha_atlas, "--outdir", tmp_path / "out", *options)
    assert code == 2 and err.count("\n") == 1 and err.startswith("atlas: error: ")
    assert all(name in err for name in names), err
    assert not (tmp_path / "out").exists()
