"""The model seam is real: a model defined in the tests alone (:mod:`tests.models.duffing`,
the double-well Duffing oscillator) runs through :func:`atlas.run` to a file that
``atlas info``, ``atlas plot`` and ``atlas view`` read, with no edit to any module of atlas
outside the model registry (the model registers itself)."""

from __future__ import annotations

import base64
import io
import json
import re

import numpy as np
import pytest
from PIL import Image
from scipy.integrate import solve_ivp

import atlas
from atlas.cli import main
from atlas.views.plotting import basin_map
from atlas.views.style import NO_LABEL_COLOR, well_colour
from tests.helpers import write_config
from tests.models import duffing

CONFIG = """\
name: duffing
model: duffing
duffing: {{delta: {delta}}}
grid:
  x0: {{start: -2, stop: 2, num: 33}}
  v0: {{start: -1.5, stop: 1.5, num: 25}}
integrator: {{dt: 0.05, t_max: 80}}
execution: {{tile_orbits: 200}}
output: {output}
"""


@pytest.fixture(scope="module")
def duffing_atlas(tmp_path_factory):
    """A Duffing atlas written by atlas.run (δ = 0.3, 33 × 25 orbits, several tiles)."""
    tmp = tmp_path_factory.mktemp("duffing")
    cfg = atlas.load_config(write_config(tmp / "duffing.yaml",
                                         CONFIG.format(delta=0.3, output=tmp / "duffing.h5")))
    atlas.run(cfg, quiet=True)
    return tmp / "duffing.h5"


def test_the_file_names_its_model_and_its_axes(duffing_atlas):
    ds = atlas.open(duffing_atlas).to_dataset(inherit=False)
    assert ds.attrs["model"] == "duffing"
    assert ds["attractor"].dims == ("v0", "x0") and float(ds["delta"]) == 0.3
    assert ds["x0"].attrs["long_name"] == "initial position"
    config = json.loads(ds.attrs["config"])
    assert config["duffing"] == {"delta": 0.3} and "pendulum" not in config
    assert set(config["grid"]) == {"x0", "v0"}


def test_the_labels_are_the_models_own_and_the_exact_flows(duffing_atlas):
    """Every stored label is the model's RK4 label of its grid point (the tiles assembled in
    place), the map has the flow's point symmetry (x, v) → (−x, −v), which takes the basin of
    +1 to that of −1, and labels far from the boundary agree with DOP853 at rtol 1e-11."""
    ds = atlas.open(duffing_atlas).to_dataset(inherit=False)
    x0, v0 = ds["x0"].values, ds["v0"].values
    attractor = ds["attractor"].values.astype(np.int16)
    own = duffing.DuffingPoint(0.3, 0.05, 80.0).label(x0[None, :], v0[:, None])[0]
    np.testing.assert_array_equal(attractor, own)
    trapped = ds["status"].values == duffing.TRAPPED
    assert set(np.unique(attractor[trapped])) == {-1, 1}
    # the saddle (0, 0) is a grid point, and stays one: the only orbit without a label
    assert np.argwhere(~trapped).tolist() == [[v0.size // 2, x0.size // 2]]
    np.testing.assert_array_equal(attractor, -attractor[::-1, ::-1])
    fractions = ds["basin_fraction"].values
    assert fractions[0] == fractions[1] == pytest.approx(0.5, abs=0.05)

    def exact(x, v):
        sol = solve_ivp(lambda t, y: (y[1], -0.3 * y[1] + y[0] - y[0] ** 3), (0, 80), (x, v),
                        method="DOP853", rtol=1e-11, atol=1e-12)
        return int(np.sign(sol.y[0, -1]))

    rng = np.random.default_rng(3)
    for i, j in zip(rng.integers(v0.size, size=12), rng.integers(x0.size, size=12)):
        if not trapped[i, j]:
            continue
        assert exact(x0[j], v0[i]) == attractor[i, j], (x0[j], v0[i])


def test_info_plot_and_view_read_it(duffing_atlas, capsys):
    ds = atlas.open(duffing_atlas).to_dataset(inherit=False)
    assert main(["info", str(duffing_atlas)]) == 0
    out = capsys.readouterr().out
    assert "grid      33 x 25 (x0 x v0) = 825 orbits" in out and "delta [1/s]" in out
    assert "duffing   delta = 0.3" in out
    for k, fraction in zip((-1, 1), ds["basin_fraction"].values):  # the stored numbers
        assert f"{k:+d} {fraction:>14.6f}" in out
    assert "unresolved 1 orbits" in out  # the saddle
    assert main(["plot", str(duffing_atlas)]) == 0
    assert duffing_atlas.with_suffix(".png").exists()
    assert duffing_atlas.with_name("duffing_t_trap.png").exists()
    ax = basin_map(atlas.open(duffing_atlas))  # the figure's image: the stored labels
    drawn = np.asarray(ax.images[0].get_array())
    trapped = ds["status"].values == duffing.TRAPPED
    np.testing.assert_array_equal(drawn[trapped], ds["attractor"].values[trapped])
    assert np.isnan(drawn[~trapped]).all()
    assert ax.get_xlabel() == "x0 [1]" and ax.get_ylabel() == "v0 [1/s]"
    names = [t.get_text() for t in ax.figure.axes[1].get_yticklabels()]
    assert names == ["−1", "+1", "no label"]  # no key entry for a k no orbit has
    assert main(["view", str(duffing_atlas)]) == 0
    page = duffing_atlas.with_suffix(".html").read_text()
    assert "<script" not in page and "model duffing" in page
    # the page's map: each pixel the colour of the stored label (velocity upward)
    uri = re.search(r'src="data:image/png;base64,([^"]+)"', page).group(1)
    image = np.asarray(Image.open(io.BytesIO(base64.b64decode(uri))).convert("RGB"))
    attractor, trapped = ds["attractor"].values, ds["status"].values == duffing.TRAPPED
    want = np.array([[_rgb(well_colour(int(k)) if t else NO_LABEL_COLOR) for k, t in zip(a, s)]
                     for a, s in zip(attractor, trapped)])[::-1]
    np.testing.assert_array_equal(image, want)
    for k, fraction in zip((-1, 1), ds["basin_fraction"].values):
        assert f"k = {k:+d}</td><td>{fraction:.4f} of the grid" in page


def _rgb(colour: str) -> list[int]:
    return [int(colour[i:i + 2], 16) for i in (1, 3, 5)]


def test_a_parameter_atlas_of_the_second_model(tmp_path):
    """A list of δ is a dim of the file, as α is for the pendulum; each point's map equals
    the one-point atlas of its δ."""
    cfg = atlas.load_config(write_config(tmp_path / "d.yaml", CONFIG.format(
        delta="[0.2, 0.5]", output=tmp_path / "d.h5")))
    tree = atlas.run(cfg, output=None, quiet=True)
    ds = tree.to_dataset(inherit=False)
    assert ds["attractor"].dims == ("delta", "v0", "x0")
    one = atlas.load_config(write_config(tmp_path / "one.yaml", CONFIG.format(
        delta=0.5, output=tmp_path / "one.h5")))
    single = atlas.run(one, output=None, quiet=True).to_dataset(inherit=False)
    np.testing.assert_array_equal(ds["attractor"].sel(delta=0.5).values,
                                  single["attractor"].values)


def test_its_bad_input_is_one_line(tmp_path, capsys):
    bad = write_config(tmp_path / "bad.yaml", CONFIG.format(delta=-1, output=tmp_path / "b.h5"))
    assert main(["run", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "duffing.delta" in err[0]
    assert not (tmp_path / "b.h5").exists()
    unknown = write_config(tmp_path / "u.yaml", "model: lorenz\n")
    assert main(["run", str(unknown)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "model" in err[0] and "lorenz" in err[0]


def test_the_command_line_runs_it_and_says_what_is_the_pendulums(duffing_atlas, tmp_path,
                                                                   capsys):
    """``atlas run`` of the model's config prints its summary; the commands that integrate
    the pendulum's own orbits (orbit, zoom), its selectors (--alpha) and its study refuse
    the second model's file or config in one line, exit status 2, nothing written."""
    cfg = write_config(tmp_path / "d.yaml", CONFIG.format(delta=0.3, output=tmp_path / "d.h5"))
    assert main(["run", str(cfg)]) == 0
    assert "duffing   delta = 0.3" in capsys.readouterr().out
    for argv, word in ((["orbit", str(duffing_atlas), "0.5", "0.1"], "atlas orbit"),
                       (["zoom", str(duffing_atlas), "0.5", "0.1", "--width", "0.1"],
                        "atlas zoom"),
                       (["info", str(duffing_atlas), "--alpha", "0.1"], "--alpha"),
                       (["stability", str(cfg), "-o", str(tmp_path / "s.h5")], "no study")):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and word in err[0], (argv, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.h5", "d.yaml"]


def test_a_file_of_a_model_atlas_does_not_know_is_one_line(duffing_atlas, tmp_path, capsys):
    import shutil

    import h5py

    copy = tmp_path / "lorenz.h5"
    shutil.copy(duffing_atlas, copy)
    with h5py.File(copy, "r+") as f:
        f.attrs["model"] = "lorenz"
    for command in ("info", "plot", "view"):
        assert main([command, str(copy)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "'lorenz' is not one atlas knows" in err[0], err


def test_the_pendulums_warning_about_degrees_is_not_the_second_models(tmp_path):
    """A θ0 window of ±180 warns that θ0 is in radians; x0 of the Duffing oscillator is no
    angle, so the same numbers say nothing."""
    body = CONFIG.format(delta=0.3, output=tmp_path / "d.h5").replace(
        "x0: {start: -2, stop: 2", "x0: {start: -180, stop: 180")
    assert atlas.load_config(write_config(tmp_path / "d.yaml", body)).warnings == ()
    pendulum = atlas.load_config(write_config(tmp_path / "p.yaml", """\
grid:
  theta0: {start: -180, stop: 180, num: 8}
  theta_dot0: {start: -1, stop: 1, num: 8}
separatrices: {enabled: false}
"""))
    assert "radians" in pendulum.warnings[0]


def test_the_config_of_another_model_is_checked_in_its_own_words(tmp_path, capsys):
    """Errors name the keys the config of the model has (grid.x0, not the pendulum's
    grid.theta0); its grid has no default; ``model_section`` is no key of any config."""
    def error(body: str) -> str:
        path = write_config(tmp_path / "c.yaml", body)
        assert main(["run", str(path)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        return err[0]

    good = CONFIG.format(delta=0.3, output=tmp_path / "d.h5")
    assert "grid.x0: start (2) must be less than stop (-2)" in error(
        good.replace("x0: {start: -2, stop: 2", "x0: {start: 2, stop: -2"))
    assert "grid.v0.nm: unknown key" in error(good.replace("num: 25", "nm: 25"))
    assert "has no default window; give grid.x0 and grid.v0" in error(
        "model: duffing\nduffing: {delta: 0.3}\n")
    assert "pendulum: not a section of model duffing" in error(
        good + "pendulum: {alpha: 0.1}\n")
    assert "model_section: unknown key" in error("model_section: {alpha: 0.5}\n")
    assert not list(tmp_path.glob("*.h5"))
