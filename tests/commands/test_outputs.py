"""No command writes over its own input, or over a file it did not write as that kind of
output (atlas.store.outputs): the data losses a new user met (`atlas run -o q.png`, then
`atlas plot q.png` wrote the basin map over the atlas) and every orbit writing one figure."""

import hashlib
import io
import re
import shutil
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from atlas.cli import main
from atlas.store.outputs import KINDS, MAKER, check_output
from tests.helpers import SMALL, STUDY_BODY, write_config


def cli(*args) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, out.getvalue(), err.getvalue()


def refused(result, *fragments) -> str:
    """The one line of a refusal with exit status 2, holding each of ``fragments``."""
    code, _, err = result
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("atlas: error: "), (code, err)
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def listing(folder: Path) -> dict[str, str]:
    return {p.name: digest(p) for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.fixture(scope="module")
def atlas_file(tmp_path_factory) -> Path:
    """A small finished atlas, q.h5 (copied by each test that writes next to it)."""
    folder = tmp_path_factory.mktemp("atlas")
    out = folder / "q.h5"
    cfg = write_config(folder / "small.yaml", SMALL.format(sep="false", output=out))
    assert cli("run", cfg, "--quiet")[0] == 0
    return out


@pytest.fixture
def here(tmp_path, atlas_file) -> Path:
    shutil.copy(atlas_file, tmp_path / "q.h5")
    return tmp_path


@pytest.mark.parametrize("name", ["q.png", "v.html", "w.yaml", "t.json", "f.pdf", "noext"])
def test_run_refuses_an_atlas_named_like_another_output(tmp_path, name):
    """`atlas run -o q.png` was accepted: `atlas plot q.png` then wrote the basin map over
    the atlas. Refused up front, nothing created (not even the output's folder)."""
    cfg = write_config(tmp_path / "c.yaml", SMALL.format(sep="false", output="x.h5"))
    before = listing(tmp_path)
    line = refused(cli("run", cfg, "-o", tmp_path / "my" / name, "--quiet"), name,
                   "NAME.h5")
    assert "--force" not in line  # no option writes an atlas under another kind's name
    assert refused(cli("run", cfg, "-o", tmp_path / "my" / name, "--quiet", "--force"))
    assert listing(tmp_path) == before and not (tmp_path / "my").exists()


def test_stability_refuses_a_study_named_like_a_figure(tmp_path):
    cfg = write_config(tmp_path / "s.yaml", STUDY_BODY.format(torque="[0.1, 0.2]",
                                                              output=tmp_path / "s.h5"))
    refused(cli("stability", cfg, "-o", tmp_path / "s.png"), "s.png", "a study is written")
    assert not (tmp_path / "s.png").exists()


def test_plot_never_writes_over_the_atlas_itself(here):
    """An atlas already named like its figure (written by an earlier atlas, or renamed):
    `atlas plot` and `atlas view` refuse, and the atlas is intact."""
    legacy_png, legacy_html = here / "q2.png", here / "v.html"
    shutil.copy(here / "q.h5", legacy_png)
    shutil.copy(here / "q.h5", legacy_html)
    before = listing(here)
    refused(cli("plot", legacy_png), "q2.png", "input file itself")
    refused(cli("view", legacy_html), "v.html", "input file itself")
    assert listing(here) == before
    assert cli("info", legacy_png)[0] == 0  # still an atlas


def test_plot_refuses_a_foreign_file_where_a_figure_goes_and_writes_none(here):
    photo = here / "q_t_trap.png"
    photo.write_bytes(b"\x89PNG\r\n\x1a\n" + b"a holiday photo")
    before = listing(here)
    refused(cli("plot", here / "q.h5"), "q_t_trap.png", "atlas did not write")
    assert listing(here) == before  # not even the basin map, drawn before it in order


def test_plot_and_view_write_over_their_own_earlier_output(here):
    code, out, _ = cli("plot", here / "q.h5")
    assert code == 0
    figures = [Path(line.removeprefix("wrote ")) for line in out.splitlines()]
    assert figures and all(MAKER.encode() in p.read_bytes() for p in figures)
    assert all(KINDS["figure"].recognises(p) for p in figures)
    assert cli("plot", here / "q.h5")[0] == 0
    assert cli("view", here / "q.h5")[0] == 0 and cli("view", here / "q.h5")[0] == 0
    assert KINDS["page"].recognises(here / "q.html")


def test_a_figure_of_an_earlier_atlas_is_written_over(tmp_path):
    """Figures atlas wrote before it marked them are matplotlib's PNGs: taken as its own."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    old = tmp_path / "old.png"
    Figure().savefig(old)
    check_output(old, "figure")
    old.write_bytes(re.sub(rb"(?i)matplotlib", b"Photoshop!", old.read_bytes()))
    with pytest.raises(Exception, match="atlas did not write"):
        check_output(old, "figure")


def test_each_orbit_keeps_its_own_figure(here):
    """Every `atlas orbit FILE …` wrote outputs/NAME_orbit.png over the last one."""
    first, second = (cli("orbit", here / "q.h5", *point) for point in (("-1", "2.5"),
                                                                         ("1", "2")))
    assert first[0] == second[0] == 0
    paths = [Path(r[1].splitlines()[-1].split()[-1]) for r in (first, second)]
    assert paths[0] != paths[1] and all(p.exists() for p in paths)
    assert paths[0].name == "q_orbit_-1_2.5.png"
    again = cli("orbit", here / "q.h5", "-1", "2.5")
    assert again[0] == 0 and Path(again[1].splitlines()[-1].split()[-1]) == paths[0]


def test_orbit_refuses_to_draw_over_its_atlas_or_a_foreign_file(here):
    before = listing(here)
    refused(cli("orbit", here / "q.h5", "0", "1", "-o", here / "q.h5"), "input file itself")
    refused(cli("orbit", here / "q.h5", "0", "1", "-o", here / "o.txt"), "NAME.png")
    (here / "notes.png").write_bytes(b"\x89PNG\r\n\x1a\nnot a figure of atlas")
    after = listing(here)
    refused(cli("orbit", here / "q.h5", "0", "1", "-o", here / "notes.png"), "atlas did not write")
    assert listing(here) == after and set(after) - set(before) == {"notes.png"}


def test_orbit_names_the_missing_coordinate(here):
    """`atlas orbit FILE 1` blamed the file name; it is THETA_DOT0 that is missing."""
    line = refused(cli("orbit", here / "q.h5", "1"), "THETA_DOT0 is missing")
    assert "theta0:" not in line
    refused(cli("orbit", here / "q.h5"), "THETA0 and THETA_DOT0 are missing")
    refused(cli("orbit", "nonsense", "1"), "theta0")  # a bad number stays a bad number


def test_zoom_writes_over_its_own_config_only(here):
    mine = here / "mine.yaml"
    mine.write_text("name: precious\n")
    zoom = ("zoom", here / "q.h5", "0", "1", "--width", "0.5", "-o")
    assert cli(*zoom, here / "z.yaml")[0] == 0 and cli(*zoom, here / "z.yaml")[0] == 0
    refused(cli(*zoom, mine), "mine.yaml", "atlas did not write")
    refused(cli(*zoom, here / "z.h5"), "NAME.yaml")
    assert mine.read_text() == "name: precious\n"


def test_bench_and_figures_refuse_other_files(tmp_path):
    refused(cli("bench", "--quick", "--output", tmp_path / "b.h5"), "NAME.json")
    (tmp_path / "fig01_damped_oscillation.png").write_text("mine")
    folder_before = listing(tmp_path)
    from atlas.commands.figures import FIGURES

    stem = next(iter(FIGURES))
    (tmp_path / f"{stem}.png").write_text("mine")
    refused(cli("figures", "--outdir", tmp_path), f"{stem}.png", "atlas did not write")
    assert set(listing(tmp_path)) == set(folder_before) | {f"{stem}.png"}


def test_a_study_plot_writes_no_figure_where_one_would_replace_a_foreign_file(tmp_path):
    out = tmp_path / "s.h5"
    cfg = write_config(tmp_path / "s.yaml", STUDY_BODY.format(torque="[0.1, 0.2, 0.3]",
                                                              output=out))
    assert cli("stability", cfg)[0] == 0
    (tmp_path / "s_fatal_shock.png").write_text("mine")
    before = listing(tmp_path)
    refused(cli("plot", out), "s_fatal_shock.png", "atlas did not write")
    assert listing(tmp_path) == before  # not even s_stability.png, drawn first
    (tmp_path / "s_fatal_shock.png").unlink()
    code, printed, _ = cli("plot", out)
    assert code == 0 and all(KINDS["figure"].recognises(Path(line.removeprefix("wrote ")))
                             for line in printed.splitlines())


def test_a_run_of_many_wells_summarises_and_info_lists_them_all(tmp_path):
    """A window in degrees (57 turns) flooded `atlas run`'s terminal with 62 basin rows and
    lines of 62 saddles: the run's summary names the 9 largest basins (ties to the smaller
    |k|), says how many more and their share; `atlas info` lists every one."""
    out = tmp_path / "deg.h5"
    cfg = write_config(tmp_path / "deg.yaml", "grid:\n"
                       "  theta0: {start: -180, stop: 180, num: 64}\n"
                       "  theta_dot0: {start: -4, stop: 4, num: 32}\n"
                       f"output: {out}\n")
    code, printed, _ = cli("run", cfg)
    assert code == 0
    rows = [line.split() for line in printed.splitlines()
            if re.match(r"^\s+[+-]\d+\s+0\.\d+ ±", line)]
    assert [int(r[0]) for r in rows] == list(range(-4, 5))
    more = next(line for line in printed.splitlines() if "more basins" in line)
    n_more, share = re.search(r"… (\d+) more basins, ([\d.e+-]+) of the window", more).groups()
    code, info, _ = cli("info", out)
    every = [line.split() for line in info.splitlines()
             if re.match(r"^\s+[+-]\d+\s+0\.\d+ ±", line)]
    assert code == 0 and len(every) == 9 + int(n_more) > 50
    shown = {int(r[0]) for r in rows}
    assert float(share) == pytest.approx(sum(float(r[1]) for r in every
                                             if int(r[0]) not in shown), rel=1e-2)
    saddles = next(line for line in printed.splitlines() if "basin boundaries (saddles" in line)
    assert "in all)" in saddles and len(saddles) < 300
    assert max(map(len, printed.splitlines())) < 400


def test_one_commands_figure_is_not_written_over_by_another(here):
    """`atlas orbit FILE … -o NAME.png` replaced the basin map `atlas plot` drew there (and
    `make run` then kept the orbit as the README's figure); the reverse too. Each command
    writes over its own figures only."""
    assert cli("plot", here / "q.h5")[0] == 0
    basin_map = here / "q.png"
    before = digest(basin_map)
    refused(cli("orbit", here / "q.h5", "0", "1", "-o", basin_map), "another atlas command",
            "atlas orbit")
    assert digest(basin_map) == before
    orbit = here / "mine.png"
    assert cli("orbit", here / "q.h5", "0", "1", "-o", orbit)[0] == 0
    assert cli("orbit", here / "q.h5", "0", "2", "-o", orbit)[0] == 0  # its own: written over
    shutil.copy(here / "q.h5", here / "mine.h5")
    before = digest(orbit)
    refused(cli("plot", here / "mine.h5"), "mine.png", "another atlas command")
    assert digest(orbit) == before


def test_a_run_says_when_it_replaces_an_atlas_of_another_config(tmp_path, caplog):
    """Running a config over the atlas of another one replaced it without a word; it is
    allowed (a changed config run again writes over its own earlier atlas, as `make`
    relies on), and said in one warning; the same config again says nothing."""
    import logging

    import atlas

    out = tmp_path / "q.h5"
    first = atlas.load_config(write_config(tmp_path / "a.yaml",
                                           SMALL.format(sep="false", output=out)))
    atlas.run(first, quiet=True).close()
    with caplog.at_level(logging.WARNING, logger="atlas"):
        atlas.run(first, quiet=True).close()
    assert not [r for r in caplog.records if "another config" in r.getMessage()]
    other = atlas.load_config(write_config(
        tmp_path / "b.yaml", SMALL.format(sep="false", output=out).replace("alpha: 0.1",
                                                                           "alpha: 0.3")))
    with caplog.at_level(logging.WARNING, logger="atlas"):
        atlas.run(other, quiet=True).close()
    said = [r.getMessage() for r in caplog.records if "another config" in r.getMessage()]
    assert said == [f"{out} holds an atlas of another config (small); this run replaces it"]
