"""The atlas file: schema, dtypes, attributes and groups round-trip; atomic completion."""

import json
from datetime import datetime

import numpy as np
import pytest
import xarray as xr

import atlas
from atlas.kernels import NEAR_BOUNDARY
from atlas.status import ATTRACTOR_FILL
from tests.helpers import crash_on_tile, lock_is_free, write_config


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    from tests.helpers import SMALL

    tmp = tmp_path_factory.mktemp("store")
    path = tmp / "c.yaml"
    path.write_text(SMALL.format(sep="false", output=tmp / "small.h5"))
    cfg = atlas.load_config(path)
    tree = atlas.run(cfg, quiet=True)
    return cfg, tree


def test_root_schema_with_plain_xarray(written):
    cfg, _ = written
    ds = xr.open_dataset(cfg.output, engine="h5netcdf")
    assert ds["attractor"].dims == ("theta_dot0", "theta0")
    assert ds.sizes == {"theta_dot0": 16, "theta0": 24, "k": ds.sizes["k"]}
    assert ds["theta0"].attrs["units"] == "rad"
    assert ds["theta_dot0"].attrs["units"] == "rad s-1"
    assert ds["t_trap"].attrs["units"] == "s" and ds["t_trap"].dtype == np.float32
    assert list(ds["status"].attrs["flag_values"]) == [0, 1, 2, 3, 4, 5]
    assert ds["status"].attrs["flag_meanings"] == \
        "trapped unresolved nonfinite near_boundary running running_near_boundary"
    assert ds["boundary_distance"].dims == ("theta_dot0", "theta0")
    assert ds["boundary_distance"].dtype == np.float32
    for name in ("attractor", "status", "t_trap", "boundary_distance", "basin_fraction",
                 "basin_fraction_exact", "basin_fraction_exact_error",
                 "basin_fraction_grid_error_bound", "basin_fraction_grid_error", "d_cert",
                 "certified_fraction", "trap_margin"):
        assert "long_name" in ds[name].attrs and "units" in ds[name].attrs
    # every parameter is a scalar coordinate of a single atlas, and of each variable
    assert {n: float(ds[n]) for n in ("alpha", "omega0", "torque")} == \
        {"alpha": 0.1, "omega0": 1.0, "torque": 0.0}
    assert all(ds[n].dims == () for n in ("alpha", "omega0", "torque"))
    assert float(ds["d_cert"]["alpha"]) == 0.1 and float(ds["attractor"]["torque"]) == 0.0
    attrs = ds.attrs
    assert "alpha" not in attrs and attrs["format_version"] == 4
    assert (attrs["dt"], attrs["t_max"]) == (0.01, 200.0)
    assert attrs["method"] == "rk4" and attrs["atlas_version"] == atlas.__version__
    datetime.fromisoformat(attrs["created"])
    assert json.loads(attrs["config"]) == json.loads(cfg.to_json())
    assert atlas.Config.model_validate_json(attrs["config"]) == cfg
    assert {"numba_version", "numpy_version", "xarray_version", "run_time_s"} <= set(attrs)


def test_open_keeps_dtypes_and_groups(written):
    cfg, tree = written
    again = atlas.open(cfg.output)
    assert set(again.children) == {"critical_points"}
    root = again.to_dataset(inherit=False)
    assert root["attractor"].dtype == np.int16 and root["status"].dtype == np.int8
    assert root["attractor"].attrs["_FillValue"] == ATTRACTOR_FILL
    cp = xr.open_datatree(cfg.output, engine="h5netcdf")["critical_points"]
    assert (cp.attrs["alpha"], cp.attrs["omega0"], cp.attrs["torque"]) == (0.1, 1.0, 0.0)
    assert list(cp["n"].values) == [-3, -2, -1, 0, 1, 2, 3]
    assert list(cp["kind"].values[1::2]) == ["attractor focus"] * 3
    assert list(cp["kind"].values[::2]) == ["saddle"] * 4


def test_file_holds_the_labels_of_its_grid(written):
    cfg, tree = written
    root = tree.to_dataset(inherit=False)
    th, v = np.meshgrid(root["theta0"].values, root["theta_dot0"].values)
    ref = atlas.label(th, v, alpha=0.1, omega0=1.0)
    np.testing.assert_array_equal(root["attractor"].values, ref.attractor)
    # separatrices are off here: d_cert is not measured, every label holds for RK4 only
    assert np.isnan(float(root["d_cert"])) and float(root["certified_fraction"]) == 0
    np.testing.assert_array_equal(root["status"].values,
                                  np.where(ref.status == 0, NEAR_BOUNDARY, ref.status))
    np.testing.assert_array_equal(root["t_trap"].values, ref.t_trap)
    assert root.attrs["complete"] == 1


def test_basin_fractions(written):
    _, tree = written
    root = tree.to_dataset(inherit=False)
    n = root.sizes["theta0"] * root.sizes["theta_dot0"]
    p = root["basin_fraction"].values
    assert np.all((p >= 0) & (p <= 1))
    assert p.sum() + float(root["unresolved_fraction"]) == pytest.approx(1.0, abs=1e-12)
    labelled = np.isin(root["status"].values, (0, NEAR_BOUNDARY))
    for k, pk in zip(root["k"].values, p):
        assert pk == np.count_nonzero(root["attractor"].values[labelled] == k) / n
    exact = root["basin_fraction_exact"].values
    assert abs(exact.sum() - 1) <= root["basin_fraction_exact_error"].values.sum() + 1e-15
    np.testing.assert_array_equal(root["basin_fraction_grid_error"], np.abs(p - exact))
    assert np.all(root["basin_fraction_grid_error"] <= root["basin_fraction_grid_error_bound"])


def test_tile_size_does_not_change_results(written, tmp_path):
    cfg, tree = written
    other = cfg.model_copy(update={"output": tmp_path / "one_tile.h5",
                                   "execution": cfg.execution.model_copy(
                                       update={"tile_orbits": 10_000})})
    a = tree.to_dataset(inherit=False)
    b = atlas.run(other, quiet=True).to_dataset(inherit=False)
    # one HDF5 chunk per tile: 100 orbits → 4 rows of 24; 10 000 → all 16 rows
    assert a["attractor"].encoding["chunksizes"] == (4, 24)
    assert b["attractor"].encoding["chunksizes"] == (16, 24)
    for name in ("attractor", "status", "t_trap", "basin_fraction"):
        np.testing.assert_array_equal(a[name].values, b[name].values)


def test_failed_run_leaves_no_file_at_the_output(written, tmp_path, monkeypatch):
    cfg, _ = written
    out = tmp_path / "fails.h5"
    cfg = cfg.model_copy(update={"output": out})
    crash_on_tile(monkeypatch, 3, RuntimeError("simulated crash"))
    with pytest.raises(RuntimeError, match="simulated crash"):
        atlas.run(cfg, quiet=True)
    assert not out.exists()
    partial = out.with_name(out.name + ".partial")
    assert partial.exists() and lock_is_free(out)
    assert not out.with_name(out.name + ".lock.owner").exists()
    from atlas.store.reader import describe

    info = describe(partial)
    assert not info["complete"] and info["tiles_done"] == 2


@pytest.mark.slow
def test_the_python_api_does_not_write_over_a_file_atlas_did_not_write(written, tmp_path):
    from atlas.errors import OutputInTheWay

    cfg, _ = written
    foreign = tmp_path / "notes.h5"
    foreign.write_text("someone's notes")
    cfg = cfg.model_copy(update={"output": foreign})
    with pytest.raises(OutputInTheWay, match="notes.h5"):
        atlas.run(cfg, quiet=True)
    assert foreign.read_text() == "someone's notes"
    assert atlas.run(cfg, quiet=True, force=True).attrs["complete"] == 1


@pytest.mark.slow
def test_the_summary_from_memory_is_the_files(tmp_path):
    """``atlas run`` prints its summary from memory (``open_result=False``) instead of
    reading the file back: the same lines as from the file opened again, for an atlas of
    several parameter points with torque and separatrices (every group the summary reads)."""
    import atlas
    from atlas.views.info import summary_lines

    cfg = write_config(tmp_path / "swept.yaml", f"""\
        name: swept
        pendulum: {{alpha: 0.1, omega0: 1.0, torque: [0.0, 0.3]}}
        grid:
          theta0: {{start: -pi, stop: pi, num: 12}}
          theta_dot0: {{start: -2, stop: 2, num: 10}}
        integrator: {{dt: 0.01, t_max: 100}}
        output: {tmp_path / 'swept.h5'}
    """)
    memory = atlas.run(atlas.load_config(cfg), quiet=True, open_result=False)
    with atlas.open(tmp_path / "swept.h5") as written:
        assert set(memory.groups) == set(written.groups)
        assert {"/separatrices/torque1", "/limit_cycle/torque1"} <= set(written.groups)
        assert summary_lines(memory) == summary_lines(written)
        torques = next(line for line in summary_lines(written) if line.startswith("torque ["))
        assert torques.split()[-2:] == ["0", "0.3"]  # a column per point of the table
