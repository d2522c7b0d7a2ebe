"""`atlas info` of a parameter atlas: one table of basin k × parameter point, read from the
file, and the detail of one point behind `--point` / `--alpha` (the same as the info of an
atlas of that point alone)."""

import io
import re
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest

import atlas
from atlas.cli import main
from atlas.views import info_table
from atlas.views.info_table import table_lines
from tests.helpers import small_atlas

ALPHAS = (0.2, 0.5, 2.0)
WINDOW = {"theta": ("-3pi", "3pi"), "speed": (-4.0, 4.0), "num": (24, 24), "t_max": 100.0}


@pytest.fixture(scope="module")
def alpha_atlas(tmp_path_factory):
    """Three damping values, 24 × 24 orbits of the window 6π × 8 rad/s, separatrices on
    (d_cert measured at every point)."""
    tmp = tmp_path_factory.mktemp("info_table")
    small_atlas(tmp, "alphas", {"alpha": list(ALPHAS), "omega0": 1.0}, **WINDOW)
    return tmp / "alphas.h5"


def _info(*args):
    """`atlas info ARGS` in this process: (exit status, stdout lines, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["info", *map(str, args)])
    return code, out.getvalue().splitlines(), err.getvalue()


def _table(lines):
    """The table's blocks parsed: {row name: [cell per point]}, points in column order."""
    rows, width = {}, info_table._LABEL
    for line in lines:
        name, cells = line[:width].strip(), line[width:].split()
        if re.fullmatch(r"point|alpha \[1/s\]|k = [+-]?\d+|running|\|grid - exact\||d_cert|"
                        r"certified|separatrices", name):
            rows.setdefault(name, []).extend(cells)
    return rows


def test_one_column_per_point_and_a_row_per_basin_from_the_file(alpha_atlas):
    with atlas.open(alpha_atlas) as tree:
        lines = table_lines(tree)
        ds = tree.to_dataset(inherit=False).load()
    rows = _table(lines)
    assert rows["point"] == ["#0", "#1", "#2"]
    assert rows["alpha [1/s]"] == ["0.2", "0.5", "2"]
    exact = ds["basin_fraction_exact"]
    present = [int(k) for k in ds["k"].values
               if (exact.sel(k=k) > 0).any() or (ds["basin_fraction"].sel(k=k) > 0).any()]
    assert [name for name in rows if name.startswith("k =")] == [
        f"k = {k:+d}".replace("+0", "0") for k in present]
    error = ds["basin_fraction_exact_error"]
    for k in present:
        cells = rows[f"k = {k:+d}".replace("+0", "0")]
        assert cells == [f"{v:.6f}" if v > e else "~0" if v > 0 else "-"
                         for v, e in zip(exact.sel(k=k).values, error.sel(k=k).values)]
    assert "running" not in rows  # no torque: no running basin
    assert rows["d_cert"] == [f"{d:.1e}" for d in ds["d_cert"].values]
    assert rows["certified"] == [f"{c:.2%}" for c in ds["certified_fraction"].values]
    measured = ds["basin_fraction_grid_error"].max("k").values
    assert rows["|grid - exact|"] == [f"{m:.1e}" for m in measured]
    # the largest measured error is that of the grid counts against the exact fractions
    np.testing.assert_array_equal(
        measured, np.abs(ds["basin_fraction"] - exact).max("k").values)
    assert rows["separatrices"] == ["ok", "ok", "ok"]
    text = "\n".join(lines)
    assert "exact area fraction" in text and "a count, not an area" in text


def test_wide_atlases_are_cut_into_blocks_of_columns(alpha_atlas, monkeypatch):
    """Each point is one column of exactly one block; a row empty in a block is left out."""
    monkeypatch.setattr(info_table, "MAX_COLUMNS", 2)
    with atlas.open(alpha_atlas) as tree:
        lines = table_lines(tree)
    headers = [line.split()[1:] for line in lines if line.startswith("point")]
    assert headers == [["#0", "#1"], ["#2"]]
    second = lines[next(i for i, line in enumerate(lines) if line.split()[1:] == ["#2"]):]
    assert all("-" not in line.split()[-1:] for line in second if line.startswith("k ="))


def test_atlas_info_prints_the_table_not_every_point(alpha_atlas):
    code, lines, err = _info(alpha_atlas)
    assert code == 0 and err == ""
    assert not any(line.strip().startswith("pendulum  alpha =") for line in lines)
    assert any(line.split()[:4] == ["point", "#0", "#1", "#2"] for line in lines)
    assert any("atlas info FILE --point I" in line for line in lines)


@pytest.mark.slow
def test_the_detail_of_a_point_is_the_info_of_that_point_alone(alpha_atlas, tmp_path):
    """`--point 1` and `--alpha 0.6` (nearest: 0.5) print what `atlas info` prints of an
    atlas computed for α = 0.5 alone: its fractions, grid counts, d_cert, separatrices."""
    small_atlas(tmp_path, "alone", {"alpha": 0.5, "omega0": 1.0}, **WINDOW)

    def block(lines):
        start = next(i for i, line in enumerate(lines) if line.startswith("  pendulum"))
        end = next(i for i, line in enumerate(lines) if line.startswith("  unresolved"))
        return lines[start:end]

    code, alone, _ = _info(tmp_path / "alone.h5")
    assert code == 0 and block(alone)[0] == "  pendulum  alpha = 0.5, omega0 = 1, torque = 0"
    for selector in (("--point", 1), ("--alpha", 0.6)):
        code, detail, err = _info(alpha_atlas, *selector)
        assert code == 0 and err == ""
        assert block(detail) == block(alone)


@pytest.mark.parametrize("options,names", [
    (("--alpha", 3.0), ("--alpha 3", "0.2 to 2")),
    (("--omega0", 2.0), ("--omega0 2", "one omega0, 1")),
    (("--point", -4), ("--point -4", "0 to 2")),
])
def test_a_point_the_atlas_does_not_hold_is_one_line(alpha_atlas, options, names):
    code, lines, err = _info(alpha_atlas, *options)
    assert code == 2 and lines == [] and err.count("\n") == 1
    assert err.startswith("atlas: error: ") and all(name in err for name in names), err


def test_labels_near_boundary_only_for_want_of_a_trace_say_so(tmp_path):
    """Without separatrices no boundary shift is measured: every label stays near_boundary,
    and atlas info and the status comment say that this is why, in those words."""
    from atlas.status import NEAR_BOUNDARY, TRAPPED

    small_atlas(tmp_path, "untraced", {"alpha": 0.2, "omega0": 1.0}, **WINDOW,
                separatrices=False)
    code, lines, _ = _info(tmp_path / "untraced.h5")
    assert code == 0
    assert any("d_cert not measured (separatrices disabled)" in line for line in lines), lines
    with atlas.open(tmp_path / "untraced.h5") as ds:
        status = ds["status"].values
        assert (status == NEAR_BOUNDARY).any() and not (status == TRAPPED).any()
        assert "separatrices disabled" in ds["status"].attrs["comment"]
