"""The study file of ``atlas stability``: the CLI end to end on a small study (untilted, the
saddle-node and a pendulum without rest state), reading it back (``atlas info``, ``atlas
plot``, Zarr) and its validation (a damaged file refused with one line, exit 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from atlas.cli import main
from atlas.errors import InputFileError
from atlas.store.study import STUDY_SCHEMA, open_study
from tests.helpers import STUDY_BODY as BODY
from tests.helpers import write_config

pytestmark = pytest.mark.slow  # runs the CLI in-process, computes a study



@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study of torques 0 (untilted), 1 (= ω0², the saddle-node) and 1.5 (no rest
    state), written by the CLI in-process: (path, printed lines)."""
    tmp = tmp_path_factory.mktemp("study")
    cfg = write_config(tmp / "s.yaml", BODY.format(torque="[0.0, 1.0, 1.5]",
                                                   output=tmp / "s.h5"))
    assert main(["stability", str(cfg)]) == 0
    return tmp / "s.h5"


def test_the_saddle_node_is_flagged_not_refused(study):
    ds = open_study(study)
    assert ds.attrs["atlas_schema"] == STUDY_SCHEMA
    status = ds["point_status"].values
    assert status.tolist() == [0, 1, 0]
    frac = ds["basin_stability"].values
    assert np.isnan(frac[:, 1]).all() and np.isnan(ds["running_stability"].values[1])
    # no rest state above ω0²: the running basin is the whole window, exactly
    assert ds["running_stability"].values[2] == 1.0 and np.all(frac[:, 2] == 0.0)
    assert np.isnan(ds["minimal_fatal_shock"].values[:, 2]).all()
    # untilted: the strips fill the window (an invariant, not a stored number)
    assert abs(frac[:, 0].sum() - 1.0) < 1e-12 and ds["running_stability"].values[0] == 0.0


def test_the_fatal_shock_is_the_same_distance_for_every_well(study):
    """The basins are 2π-translates: one distance, its point translated by 2πk."""
    ds = open_study(study).isel(torque=0)
    d = ds["minimal_fatal_shock"].values
    assert np.ptp(d) == 0.0
    assert np.allclose(np.diff(ds["fatal_shock_theta"].values), 2 * math.pi, atol=1e-12)
    dist = np.hypot(ds["fatal_shock_theta"].values - 2 * math.pi * ds["k"].values,
                    ds["fatal_shock_theta_dot"].values)
    assert np.allclose(dist, d, rtol=1e-12)


def test_info_names_the_bifurcations_and_the_flagged_point(study, capsys):
    assert main(["info", str(study)]) == 0
    out = capsys.readouterr().out
    assert "stability study" in out
    assert "homoclinic_torque" in out and "saddle_node_torque: torque = 1" in out
    assert "1 point(s) saddle_node" in out


def test_plot_writes_the_curves(study, tmp_path, capsys):
    assert main(["plot", str(study), "--outdir", str(tmp_path)]) == 0
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == ["s_fatal_shock.png", "s_stability.png"]
    from PIL import Image

    for name in names:
        assert Image.open(tmp_path / name).size[0] > 500


def test_zarr_study_reads_back_equal(study, tmp_path):
    cfg = write_config(tmp_path / "z.yaml", BODY.format(torque="[0.0, 1.0, 1.5]",
                                                        output=tmp_path / "z.zarr"))
    assert main(["stability", str(cfg)]) == 0
    a, b = open_study(study), open_study(tmp_path / "z.zarr")
    for name in ("basin_stability", "minimal_fatal_shock", "point_status"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    import atlas  # a Zarr study where an atlas is expected: the Zarr way to open it

    with pytest.raises(InputFileError, match=r"a stability study.*xr\.open_zarr"):
        atlas.open(tmp_path / "z.zarr")


@pytest.mark.parametrize("change, message", [
    (lambda ds: ds.assign_attrs(format_version=np.int64(99)), "format_version"),
    (lambda ds: ds.drop_vars("minimal_fatal_shock"), "minimal_fatal_shock is missing"),
    (lambda ds: ds.assign(point_status=ds["point_status"] + np.int8(5)), "point_status"),
    (lambda ds: ds.assign(basin_stability=ds["basin_stability"] * 2), "summing to 1"),
    (lambda ds: ds.assign_attrs(config="[1, 2"), "config"),
    (lambda ds: ds.assign_attrs(window_theta=np.array([1.0, 0.0])), "window_theta"),
    (lambda ds: ds.assign_attrs(window_theta_dot="minus ten to ten"), "window_theta_dot"),
])
def test_a_damaged_study_is_refused(study, tmp_path, capsys, change, message):
    with xr.open_dataset(study, engine="h5netcdf", mask_and_scale=False) as f:
        ds = change(f.load())
    bad = tmp_path / "bad.h5"
    ds.to_netcdf(bad, engine="h5netcdf")
    with pytest.raises(InputFileError, match=message):
        open_study(bad)
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_a_two_dimensional_study_draws_its_map(tmp_path, capsys):
    """Two ranges make a 2-D study (α × ω0 here, without torque: the strips fill the
    window); its figure is the map with the focus–node curve α = ω0 on it."""
    cfg = write_config(tmp_path / "m.yaml", (
        "pendulum:\n  alpha: {start: 0.5, stop: 1.5, num: 2}\n"
        "  omega0: {start: 0.8, stop: 1.2, num: 2}\n"
        "grid:\n  theta0: {start: -pi, stop: pi, num: 2}\n"
        "  theta_dot0: {start: -2, stop: 2, num: 2}\n"
        f"output: {tmp_path / 'm.h5'}\n"))
    assert main(["stability", str(cfg)]) == 0
    ds = open_study(tmp_path / "m.h5")
    assert ds["basin_stability"].dims == ("k", "alpha", "omega0")
    np.testing.assert_allclose(ds["basin_stability"].sum("k").values, 1.0, atol=1e-12)
    np.testing.assert_array_equal(ds["focus_node_damping"].values, ds["omega0"].values)
    assert main(["plot", str(tmp_path / "m.h5")]) == 0
    assert (tmp_path / "m_stability_map.png").exists()
    capsys.readouterr()
    assert main(["info", str(tmp_path / "m.h5")]) == 0
    out = capsys.readouterr().out  # untilted: the wells fill the window at every point
    assert "basin stability of the rest states, lowest: 1.0000000000" in out


def test_gaussian_and_tipping_are_stored_when_asked(tmp_path, capsys):
    out = tmp_path / "t.h5"
    cfg = write_config(tmp_path / "t.yaml", (
        "pendulum:\n  alpha: {start: 0.1, stop: 0.3, num: 3}\n"
        "grid:\n  theta0: {start: -pi, stop: pi, num: 2}\n"
        "  theta_dot0: {start: -3, stop: 3, num: 2}\n"
        "stability: {sigma_theta: 0.4, sigma_theta_dot: 0.6, tipping: true}\n"
        f"output: {out}\n"))
    assert main(["stability", str(cfg)]) == 0
    ds = open_study(out)
    assert ds.attrs["sigma_theta"] == 0.4 and ds.attrs["sigma_theta_dot"] == 0.6
    g = ds["gaussian_stability"].values
    assert np.all((g > 0.5) & (g <= 1.0))
    assert np.all(np.diff(g) > 0)  # more damping, a wider basin around the rest state
    tip = ds["tipping_probability"]
    assert tip.dims == ("step", "source", "target") and tip.sizes["step"] == 2
    rows = tip.values[np.isfinite(tip.values).all(axis=2)]
    np.testing.assert_allclose(rows.sum(axis=1), 1.0, atol=1e-6)
    # without torque there is no running basin at either end of a step
    assert np.all(np.isnan(tip.sel(source=-32768).values))
    assert np.all(np.nan_to_num(tip.sel(target=-32768).values) == 0.0)
    assert main(["info", str(out)]) == 0
    assert "tipping probabilities: 2 steps" in capsys.readouterr().out


def test_a_zarr_study_written_over_keeps_one_whole_study(study, tmp_path, monkeypatch):
    """Writing a study over a Zarr one moves the old one aside first: if the rename of the new
    one fails, the old study is back in place, whole, and no temporary is left."""
    import os

    from atlas.store.study import write_study

    first = open_study(study)
    path = tmp_path / "s.zarr"
    write_study(first, path)
    real = os.replace

    def failing(src, dst):
        if str(src).endswith(".tmp"):
            raise OSError("no space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(OSError):
        write_study(first, path)
    monkeypatch.setattr(os, "replace", real)
    np.testing.assert_array_equal(open_study(path)["basin_stability"].values,
                                  first["basin_stability"].values)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]


def test_verbose_reports_each_phase_per_point(tmp_path):
    """``atlas stability -v`` logs the mean and largest cost per point of each phase, over
    every point that has it (the Gaussian stability only when asked)."""
    import re

    from atlas.stability.study import PHASES
    from tests.helpers import run_cli

    cfg = write_config(tmp_path / "v.yaml", BODY.format(
        torque="{start: 0.0, stop: 0.9, num: 4}", output=tmp_path / "v.h5")
        + "stability: {sigma_theta: 0.5, sigma_theta_dot: 0.5}\n")
    proc = run_cli("stability", cfg, "-v")
    assert proc.returncode == 0, proc.stderr
    found = {m.group(1): (float(m.group(2)), float(m.group(3)), int(m.group(4)))
             for m in re.finditer(r"per point, (\w+)\s+mean\s+([0-9.]+) ms, max\s+([0-9.]+) "
                                  r"ms \((\d+) of 4 points", proc.stderr)}
    assert set(found) == set(PHASES), proc.stderr
    for mean, most, points in found.values():
        assert 0.0 <= mean <= most and points == 4
