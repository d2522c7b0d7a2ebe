"""``atlas zoom`` of a driven pendulum's atlas: the config of a window at the file's drive,
integrator and period bound, whose attractors' search spreads its seeds over the file's
window (``drive.search_window``), so that a zoom, however small, finds and numbers the same
attractors as the atlas it zooms into."""

from __future__ import annotations

import numpy as np
import pytest

import atlas
from atlas.cli import main
from tests.helpers import write_config

PARENT = """\
name: parent
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {{amplitude: 1.66, frequency: 1.0}}
grid:
  theta0: {{start: -1.0, stop: 1.0, num: 9}}
  theta_dot0: {{start: 0.0, stop: 2.0, num: 9}}
integrator: {{dt: pi/50, t_max: 600}}
output: {output}
"""


@pytest.fixture(scope="module")
def parent(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("zoom-driven")
    cfg = atlas.load_config(write_config(tmp / "p.yaml", PARENT.format(output=tmp / "p.h5")))
    atlas.run(cfg, quiet=True)
    return tmp / "p.h5"


def _zoom(parent, tmp_path, capsys, *args) -> atlas.Config:
    target = tmp_path / "z.yaml"
    assert main(["zoom", str(parent), *args, "-o", str(target)]) == 0
    capsys.readouterr()
    return atlas.load_config(target)


def test_a_zoom_onto_the_whole_window_is_the_atlas_again(parent, tmp_path, capsys):
    """The zoom of width 2 around (0, 1) with 9 points per axis is the parent's own grid: it
    computes the same arrays, and the same attractors (the same search)."""
    cfg = _zoom(parent, tmp_path, capsys, "0", "1", "--width", "2", "--num", "9")
    assert cfg.pendulum.drive.amplitude == 1.66 and cfg.integrator.dt == pytest.approx(
        np.pi / 50, rel=1e-15)
    zoomed = atlas.run(cfg, quiet=True)
    original = atlas.open(parent)
    for node in ("/", "/attractors"):
        a = zoomed[node].to_dataset(inherit=False)
        b = original[node].to_dataset(inherit=False)
        for name in b.data_vars:
            np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_a_small_zoom_finds_the_files_attractors(parent, tmp_path, capsys):
    """A window 1e-3 wide: its attractors, searched over the parent's window, are the
    parent's, numbered alike, so that its labels mean what the parent's mean (a search
    seeded in the small window alone could miss a basin that does not cross it)."""
    cfg = _zoom(parent, tmp_path, capsys, "-0.5", "1.25", "--width", "1e-3", "--num", "5")
    window = cfg.pendulum.drive.search_window
    assert tuple(window.theta0) == (-1.0, 1.0) and tuple(window.theta_dot0) == (0.0, 2.0)
    zoomed = atlas.run(cfg.model_copy(update={"output": tmp_path / "z.h5"}), quiet=True)
    a = zoomed["/attractors"].to_dataset()
    b = atlas.open(parent)["/attractors"].to_dataset()
    np.testing.assert_array_equal(a["theta"].values, b["theta"].values)
    np.testing.assert_array_equal(a["period"].values, b["period"].values)


def test_bad_selectors_are_one_line(parent, tmp_path, capsys):
    for args, word in ((["--amplitude", "1.2"], "no single parameter point"),
                       (["--amplitude", "x"], "--amplitude")):
        assert main(["zoom", str(parent), "0", "1", "--width", "0.1", *args]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and word in err[0], err


def test_a_drive_selector_on_the_pendulums_atlas_is_one_line(tmp_path, capsys):
    body = ("pendulum: {alpha: 0.1, omega0: 1.0}\n"
            "grid: {theta0: {start: -1, stop: 1, num: 5}, theta_dot0: {start: 0, stop: 2, "
            f"num: 5}}}}\nseparatrices: {{enabled: false}}\noutput: {tmp_path / 'u.h5'}\n")
    atlas.run(atlas.load_config(write_config(tmp_path / "u.yaml", body)), quiet=True)
    assert main(["zoom", str(tmp_path / "u.h5"), "0", "1", "--width", "0.1",
                 "--amplitude", "1.66"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a driven pendulum's atlas" in err[0], err
