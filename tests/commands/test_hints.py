"""The command line a newcomer meets: ``--version``, a bare ``atlas``, help for every argument,
``-v`` only where it shows something, ``atlas plot``'s options, and the one-line hints for
the common mistakes (a config given for an atlas file and back, negative numbers, the output
of an interrupted run, degrees for radians)."""

from __future__ import annotations

import argparse
import struct

import pytest

import atlas
from atlas.cli import build_parser, main
from tests.helpers import run_cli, write_config

#: The commands that log nothing at INFO or DEBUG: ``-v`` would show nothing there.
SILENT = ("info", "plot", "figures", "bench", "view", "orbit", "zoom")


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _one_error_line(capsys, argv, *fragments) -> str:
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("atlas: error: "), err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def test_version_is_the_package_s(capsys):
    """``atlas --version``: the installed distribution's version (``pendulum-atlas``), which
    is the package's own, written once."""
    from importlib.metadata import PackageNotFoundError, version

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    out = capsys.readouterr().out.split()
    assert out == ["atlas", atlas.__version__]
    try:
        assert version("pendulum-atlas") == atlas.__version__
    except PackageNotFoundError:  # a source tree that is not installed: the package's own
        pass


def test_a_bare_atlas_prints_the_help_and_exits_0(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: atlas") and "Exit status" in out
    for command in ("run", "info", "plot", "figures", "bench", "view", "orbit", "zoom"):
        assert command in out


def test_every_argument_of_every_command_has_help():
    """Walk the parser: every option and positional of the top level and of every
    subcommand says what it is."""
    parser = build_parser()
    parsers = {"atlas": parser, **_subparsers(parser)}
    missing = [f"{name} {action.dest}" for name, p in parsers.items() for action in p._actions
               if not isinstance(action, argparse._SubParsersAction)
               and not (action.help and action.help.strip())]
    assert missing == []
    assert set(SILENT) | {"run"} <= set(parsers)


def test_verbose_only_where_it_shows_something():
    """``-v`` is offered by ``atlas run`` (each stage's time, -vv every tile), not by the
    commands that log nothing."""
    commands = _subparsers(build_parser())
    assert "-v" in commands["run"]._option_string_actions
    help_text = commands["run"]._option_string_actions["-v"].help
    assert "stage" in help_text and "tile" in help_text
    offering = [name for name in SILENT if "-v" in commands[name]._option_string_actions]
    assert offering == []


@pytest.mark.parametrize("argv,values", [
    (["orbit", "F.h5", "-pi/2", "1"], ["F.h5", "-pi/2", "1"]),
    (["orbit", "-pi/2", "-1e-3", "--alpha", "-0.5", "--omega0", "1"], ["-pi/2", "-1e-3"]),
    (["orbit", "F.h5", "-3pi", "-(1+2)", "-o", "x.png"], ["F.h5", "-3pi", "-(1+2)"]),
    (["orbit", "F.h5", "--", "-pi/2", "1"], ["F.h5", "-pi/2", "1"]),  # the old spelling
    (["orbit", "F.h5", "-π/2", "-.5"], ["F.h5", "-π/2", "-.5"]),
])
def test_orbit_takes_negative_numbers_as_they_are(argv, values):
    """``atlas orbit FILE -pi/2 1`` once said only "unrecognized arguments"."""
    args = build_parser().parse_args(argv)
    assert args.values == values
    if "--alpha" in argv:
        assert args.alpha == "-0.5"


def test_zoom_takes_negative_numbers_as_they_are():
    args = build_parser().parse_args(["zoom", "F.h5", "-pi/2", "-1", "--width", "-1e-3"])
    assert (args.theta0, args.theta_dot0, args.width) == ("-pi/2", "-1", "-1e-3")


def test_an_unknown_option_is_still_refused(capsys):
    _one_error_line(capsys, ["orbit", "F.h5", "1", "2", "-x"], "unrecognized arguments: -x")


def test_a_config_given_for_an_atlas_file(capsys, tmp_path):
    """Every command that reads an atlas file says that a config is run with `atlas run`."""
    cfg = write_config(tmp_path / "c.yaml", "name: c\n")
    for argv in (["info", cfg], ["plot", cfg], ["view", cfg, "-o", tmp_path / "p.html"],
                 ["orbit", cfg, "0", "1", "-o", tmp_path / "o.png"],
                 ["zoom", cfg, "0", "1", "--width", "1", "-o", tmp_path / "z.yaml"]):
        _one_error_line(capsys, argv, f"{cfg}: a config, not an atlas file",
                        f"`atlas run {cfg}`")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


def test_an_atlas_file_given_for_a_config(capsys, small_atlas_file, tmp_path):
    """``atlas run OUT.h5`` once said "UnicodeDecodeError"."""
    before = small_atlas_file.read_bytes()
    _one_error_line(capsys, ["run", small_atlas_file], f"{small_atlas_file}: an atlas file, "
                    f"not a config; look at it with `atlas info {small_atlas_file}`")
    assert small_atlas_file.read_bytes() == before
    text = tmp_path / "notes.h5"
    text.write_text("neither HDF5 nor a config")
    _one_error_line(capsys, ["info", text], f"{text}: not an atlas file")
    binary = tmp_path / "noise.yaml"
    binary.write_bytes(b"\xff\xfe\x00 not text")
    line = _one_error_line(capsys, ["run", binary], f"{binary}: cannot read config file")
    assert "an atlas file" not in line


def test_the_output_of_an_interrupted_run(capsys, small_config):
    """``atlas info NAME.h5`` when only ``NAME.h5.partial`` is there: how far the run got and
    how to finish it (exit 0); the commands that need the atlas say so in one line."""
    from atlas.pipeline.identity import run_identity
    from atlas.pipeline.sweep import layout_of
    from atlas.store.partial import TileStore, partial_path

    cfg = atlas.load_config(small_config())
    partial = partial_path(cfg.output)
    layout = layout_of(cfg)
    TileStore.create(partial, layout, run_identity(cfg, "cpu"), {})
    assert main(["info", str(cfg.output)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == (f"{cfg.output}: not written yet: its run was interrupted; {partial} "
                      f"holds 0 of {layout.n_tiles} tiles (run the same config again, "
                      "`atlas run CONFIG`, to finish it)")
    for argv in (["plot", cfg.output], ["view", cfg.output],
                 ["orbit", cfg.output, "0", "1"]):
        _one_error_line(capsys, argv, f"{cfg.output}: not written yet", str(partial),
                        "atlas run CONFIG")
    assert not cfg.output.exists()


def test_a_missing_file_is_still_no_such_file(capsys, tmp_path):
    _one_error_line(capsys, ["info", tmp_path / "none.h5"], "none.h5: no such file")


@pytest.mark.slow
def test_plot_outdir_format_dpi(small_atlas_file, tmp_path):
    """``atlas plot --outdir DIR --format svg|pdf|png --dpi N``: the figures land in DIR
    (made), in that format; a PNG's width in pixels is its width in inches times the dpi."""
    from atlas.views.style import MAP_SIZE

    outdir = tmp_path / "figs" / "deeper"
    proc = run_cli("plot", small_atlas_file, "--outdir", outdir, "--format", "svg")
    assert proc.returncode == 0, proc.stderr
    svgs = sorted(p.name for p in outdir.iterdir())
    assert svgs == ["small.svg", "small_boundary_distance.svg", "small_t_trap.svg"]
    assert all(b"<svg" in (outdir / name).read_bytes()[:2000] for name in svgs)
    assert run_cli("plot", small_atlas_file, "--outdir", outdir, "--format", "pdf",
                   "--dpi", "72").returncode == 0
    assert (outdir / "small.pdf").read_bytes().startswith(b"%PDF")
    assert run_cli("plot", small_atlas_file, "--outdir", outdir, "--dpi", "60").returncode == 0
    header = (outdir / "small.png").read_bytes()[:24]
    width, height = struct.unpack(">II", header[16:24])  # the PNG's IHDR chunk
    assert (width, height) == (round(MAP_SIZE[0] * 60), round(MAP_SIZE[1] * 60))
    assert not list(small_atlas_file.parent.glob("*.svg"))  # nothing next to the file


def test_plot_refuses_bad_options_and_writes_nothing(capsys, small_atlas_file, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    _one_error_line(capsys, ["plot", small_atlas_file, "--outdir", blocker / "figs"],
                    "cannot create the output folder", f"{blocker} is a file")
    _one_error_line(capsys, ["plot", small_atlas_file, "--dpi", "0"], "--dpi must be between")
    _one_error_line(capsys, ["plot", small_atlas_file, "--format", "gif"], "invalid choice")
    _one_error_line(capsys, ["plot", tmp_path / "none.h5", "--outdir", tmp_path / "figs"],
                    "no such file")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]  # no folder made


@pytest.mark.slow
def test_a_window_in_degrees_runs_with_a_warning_on_stderr(tmp_path):
    """±180 (degrees in mind) once was refused over the separatrix tolerance: now it runs,
    with a warning that θ0 is in radians and the hint in radians, and the tol it used."""
    cfg = write_config(tmp_path / "deg.yaml", f"""\
        grid:
          theta0: {{start: -180, stop: 180, num: 8}}
          theta_dot0: {{start: -1, stop: 1, num: 4}}
        separatrices: {{tol: 1.0e-12}}
        output: {tmp_path / 'deg.h5'}
        """)
    proc = run_cli("run", cfg, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "deg.h5").exists()
    warnings = [line for line in proc.stderr.splitlines() if line.startswith("atlas: warning")]
    units = [line for line in warnings if "radians" in line]
    assert len(units) == 1
    assert "did you mean -pi … pi?" in units[0] and "check_radians: false" in units[0]
    tol = [line for line in warnings if "separatrices.tol = 1e-12" in line]
    assert len(tol) == 1 and "tol = 1.9e-12" in tol[0]
    with atlas.open(tmp_path / "deg.h5") as tree:
        assert tree["separatrices"].attrs["tol"] == pytest.approx(1.9e-12, rel=1e-12)
        assert tree.attrs["config"].count('"tol": 1.9e-12') == 1


def test_a_study_file_given_for_a_config_or_an_atlas(capsys, tmp_path):
    """``atlas stability STUDY.h5`` once said "cannot read config file (UnicodeDecodeError)",
    and ``atlas.open(STUDY.h5)`` "not an atlas" without saying what reads it."""
    import h5py

    from atlas.errors import InputFileError
    from tests.helpers import STUDY_BODY

    cfg = write_config(tmp_path / "s.yaml", STUDY_BODY.format(torque="[0.0, 0.5]",
                                                              output=tmp_path / "s.h5"))
    assert main(["stability", str(cfg)]) == 0
    capsys.readouterr()
    study = tmp_path / "s.h5"
    for command in ("stability", "run"):
        _one_error_line(capsys, [command, study], f"{study}: a stability study, not a config",
                        f"`atlas info {study}`")
    with pytest.raises(InputFileError, match="a stability study, not an atlas file") as raised:
        atlas.open(study)
    assert f"xr.open_dataset('{study}', engine='h5netcdf')" in str(raised.value)
    hdf5 = tmp_path / "other.h5"
    with h5py.File(hdf5, "w") as f:
        f["x"] = [1.0]
    _one_error_line(capsys, ["run", hdf5], f"{hdf5}: an HDF5 file, not a YAML config")
