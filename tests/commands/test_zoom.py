"""``atlas zoom``: the config of a window centred on a point is centred and sized as asked,
loads as written (every number bit for bit), carries the file's parameters, runs end to end;
bad input is one line on stderr, exit status 2, nothing written."""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.cli import main
from atlas.commands.zoom import width_tag, zoom_config
from tests.helpers import run_cli

#: The k = 0 | 1 basin boundary of the default pendulum crosses θ0 = 0 here [rad/s].
BOUNDARY = 2.4149382176


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small atlas of the default pendulum with settings that differ from the defaults
    (dt, t_max, tol, max_spacing), and a parameter atlas of two points with a torque."""
    tmp = tmp_path_factory.mktemp("zoom")
    one = atlas.Config.model_validate({
        "name": "one", "pendulum": {"alpha": 0.1, "omega0": 1.0},
        "grid": {"theta0": {"start": "-pi", "stop": "pi", "num": 12},
                 "theta_dot0": {"start": -3, "stop": 3, "num": 10}},
        "integrator": {"dt": 0.005, "t_max": 150.0},
        "separatrices": {"tol": 3e-12, "max_spacing": 0.1}, "output": str(tmp / "one.h5")})
    atlas.run(one, quiet=True)
    sweep = atlas.Config.model_validate({
        "name": "sweep", "pendulum": {"alpha": [0.1, 0.3], "omega0": 1.0, "torque": 0.25},
        "grid": {"theta0": {"start": -3, "stop": 3, "num": 6},
                 "theta_dot0": {"start": -2, "stop": 2, "num": 6}},
        "separatrices": {"enabled": False}, "output": str(tmp / "sweep.h5")})
    atlas.run(sweep, quiet=True)
    return one.output, sweep.output


def _one_clean_line(proc, *fragments):
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith("atlas: error: ")
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def test_width_tag():
    assert [width_tag(w) for w in (1, 0.02, 1e-3, 1e-6, 2.5e-9, 10)] == [
        "1", "0.02", "1e-3", "1e-6", "2.5e-9", "10"]


@pytest.mark.parametrize("width", [1.0, 1e-3, 1e-6, 1e-8])
def test_the_config_is_centred_sized_and_carries_the_files_parameters(files, tmp_path, capsys,
                                                                      width):
    one, _ = files
    target = tmp_path / "zoom.yaml"
    assert main(["zoom", str(one), "0", str(BOUNDARY), "--width", repr(width),
                 "-o", str(target)]) == 0
    assert str(target) in capsys.readouterr().out
    cfg = atlas.load_config(target)  # the round trip: it loads as written
    th, v = cfg.grid.theta0, cfg.grid.theta_dot0
    assert th.num == v.num == 101
    assert (th.start, th.stop) == (0.0 - width / 2, 0.0 + width / 2)  # bit for bit
    assert (v.start, v.stop) == (BOUNDARY - width / 2, BOUNDARY + width / 2)
    assert math.isclose(v.stop - v.start, width, rel_tol=1e-6)
    assert math.isclose((v.start + v.stop) / 2, BOUNDARY, rel_tol=1e-15)
    # the file's parameters, integrator and separatrix settings, not the defaults
    assert (cfg.pendulum.alpha, cfg.pendulum.omega0, cfg.pendulum.torque) == (0.1, 1.0, 0.0)
    assert (cfg.integrator.dt, cfg.integrator.t_max, cfg.integrator.method) == (
        0.005, 150.0, "rk4")
    assert cfg.separatrices.enabled
    assert (cfg.separatrices.tol, cfg.separatrices.max_spacing) == (3e-12, 0.1)
    # named by its width and centre: two zooms of one width around two points never share it
    assert cfg.output == one.with_name(f"one-zoom-{width_tag(width)}-at-0_{BOUNDARY:.10g}.h5")


def test_without_o_the_config_goes_to_stdout_and_loads(files, tmp_path, capsys):
    one, _ = files
    centre = (-0.123456789012345678, 1.0000000000000002)  # repr needs every digit
    assert main(["zoom", "--num", "7", "--width", "2e-5", str(one), "--",
                 repr(centre[0]), repr(centre[1])]) == 0
    text = capsys.readouterr().out
    (tmp_path / "z.yaml").write_text(text)
    cfg = atlas.load_config(tmp_path / "z.yaml")
    assert cfg.grid.theta0.num == cfg.grid.theta_dot0.num == 7
    assert cfg.grid.theta0.start == centre[0] - 1e-5 and cfg.grid.theta0.stop == centre[0] + 1e-5
    assert cfg.grid.theta_dot0.start == centre[1] - 1e-5
    assert list(tmp_path.iterdir()) == [tmp_path / "z.yaml"]  # nothing else written


def test_a_parameter_atlas_needs_its_point_chosen(files, tmp_path, capsys):
    _, sweep = files
    assert main(["zoom", str(sweep), "0", "1", "--width", "0.5"]) == 2
    assert "choose one with --alpha" in capsys.readouterr().err
    zoom = zoom_config(sweep, -1.0, 0.5, 0.5, alpha=0.3)
    p = zoom.config.pendulum
    assert (p.alpha, p.omega0, p.torque) == (0.3, 1.0, 0.25)
    assert not zoom.config.separatrices.enabled
    assert main(["zoom", str(sweep), "0", "1", "--width", "0.5", "--alpha", "0.3",
                 "--torque", "0.25", "-o", str(tmp_path / "z.yaml")]) == 0
    assert atlas.load_config(tmp_path / "z.yaml").pendulum.alpha == 0.3


def test_a_zoom_runs_end_to_end_around_a_boundary_point(files, tmp_path, capsys):
    one, _ = files
    cfg_path = tmp_path / "z.yaml"
    out = tmp_path / "z.h5"
    assert main(["zoom", str(one), "0", str(BOUNDARY), "--width", "1e-2", "--num", "11",
                 "-o", str(cfg_path)]) == 0
    assert main(["run", str(cfg_path), "-o", str(out), "--quiet"]) == 0
    ds = atlas.open(out).to_dataset(inherit=False)
    np.testing.assert_allclose(ds["theta0"].values, np.linspace(-5e-3, 5e-3, 11), atol=1e-15)
    np.testing.assert_allclose(ds["theta_dot0"].values,
                               np.linspace(BOUNDARY - 5e-3, BOUNDARY + 5e-3, 11), rtol=1e-15)
    k = ds["attractor"].values
    assert set(np.unique(k[ds["status"].values >= 0])) >= {0, 1}  # both basins in the window
    assert float(ds.attrs["dt"]) == 0.005


def _nothing_written(tmp_path, before):
    assert sorted(tmp_path.iterdir()) == before


class _Exit:
    """What a process would see of ``main(argv)`` run in this one: its status and stderr."""

    def __init__(self, argv, capsys):
        try:
            self.returncode = main(argv)
        except SystemExit as exc:  # argparse's own refusals
            self.returncode = exc.code
        self.stderr = capsys.readouterr().err


def test_bad_input_is_one_line_exit_2_and_nothing_written(files, tmp_path, capsys):
    one, _ = files
    cfg = tmp_path / "c.yaml"
    cfg.write_text("name: x\n")
    text = tmp_path / "t.h5"
    text.write_text("not an atlas")
    before = sorted(tmp_path.iterdir())
    out = str(tmp_path / "out.yaml")
    centre = ("0", str(BOUNDARY))
    for args, fragment in [
        ([str(cfg), *centre, "--width", "1"], "a config, not an atlas file"),
        ([str(text), *centre, "--width", "1"], "t.h5"),
        ([str(tmp_path / "missing.h5"), *centre, "--width", "1"], "no such file"),
        ([str(one), *centre, "--width", "0"], "--width must be a finite number > 0"),
        ([str(one), *centre, "--width=-1e-3"], "--width must be a finite number > 0"),
        ([str(one), *centre, "--width", "1e-14"], "too narrow for double precision"),
        ([str(one), *centre, "--width", "1e-11"], "separatrices.tol"),
        ([str(one), *centre, "--width", "1e-9"], "separatrices.tol"),  # < 1000 tol = 3e-9
        ([str(one), *centre, "--width", "1", "--num", "1"], "--num must be at least 2"),
        ([str(one), "x", "1", "--width", "1"], "theta0: cannot read 'x'"),
        ([str(one), *centre], "required: --width"),
        ([str(one), *centre, "--width", "1", "-o", str(one)], "an atlas file"),
    ]:
        argv = ["zoom", *args] + ([] if "-o" in args else ["-o", out])
        _one_clean_line(_Exit(argv, capsys), fragment)
        _nothing_written(tmp_path, before)
    # and as a real process: one line, exit status 2, no traceback
    _one_clean_line(run_cli("zoom", str(cfg), *centre, "--width", "1", "-o", out),
                    "a config, not an atlas file")
    _nothing_written(tmp_path, before)


@pytest.mark.parametrize("lo,hi,label,ticks", [
    (BOUNDARY - 5e-7, BOUNDARY + 5e-7, "θ̇0 − 2.4149382176 [µrad/s]", "−0.4 −0.2 0 0.2 0.4"),
    (-5e-4, 5e-4, "θ̇0 [mrad/s]", "−0.4 −0.2 0 0.2 0.4"),
])
def test_a_zoom_s_axes_read_as_offsets_in_prefixed_units(lo, hi, label, ticks):
    """A narrow window's ticks are offsets from its centre in SI-prefixed units, not seven
    equal leading digits or matplotlib's offset text (which collides with the title)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from atlas.views.style import window_ticks

    fig, ax = plt.subplots()
    ax.set_ylim(lo, hi)
    window_ticks(ax, lo, hi, "y", "θ̇0", "rad/s")
    assert ax.get_ylabel() == label
    assert " ".join(t.get_text() for t in ax.get_yticklabels()) == ticks
    fig.canvas.draw()
    assert ax.yaxis.get_offset_text().get_text() == ""
    plt.close(fig)
