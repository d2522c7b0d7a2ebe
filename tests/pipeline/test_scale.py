"""Streaming, resumable sweeps: kill -9 and resume, backends, parameter atlases, memory."""

import os
import signal
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import atlas
from tests.helpers import REPO, crash_on_tile, run_cli, write_config

pytestmark = pytest.mark.slow  # whole runs, kills and resumes

LABELS = ("attractor", "status", "t_trap")


def _arrays(path):
    ds = atlas.open(path).to_dataset(inherit=False)
    return {name: ds[name].values for name in (*LABELS, "basin_fraction", "k")}


def _assert_same(a, b):
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


#: 48 tiles of one row each: enough for a kill, a crash or a resume to land mid-run (a tile
#: costs a durable write, so not more of them)
MANY_TILES = """\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 48}}
  theta_dot0: {{start: -4, stop: 4, num: 48}}
integrator: {{t_max: {t_max}}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 48}}
output: {output}
"""


def test_kill_9_then_resume_gives_identical_arrays(tmp_path):
    out = tmp_path / "killed.h5"
    # a small step makes the run last a few seconds, so the kill lands mid-run
    body = MANY_TILES.replace("integrator: {{t_max: {t_max}}}",
                              "integrator: {{t_max: {t_max}, dt: 0.001}}")
    cfg = write_config(tmp_path / "c.yaml", body.format(t_max=200, output=out))
    partial = out.with_name(out.name + ".partial")
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "atlas.cli", "run", "-vv", str(cfg),
                             "--quiet"], env=env, cwd=REPO, stderr=subprocess.PIPE, text=True)
    for line in proc.stderr:  # -vv logs every tile written
        if "tile 5 of 48 written" in line:
            break
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    assert not out.exists() and partial.exists()
    from atlas.store.reader import describe

    done_at_kill = describe(partial)["tiles_done"]
    assert 5 <= done_at_kill < 48
    # the dead run's lock is stale and must not block the resume
    resumed = run_cli("run", cfg, "--resume", "--quiet", "-v")
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming" in resumed.stderr and "tiles already done" in resumed.stderr
    assert "--resume is deprecated and does nothing" in resumed.stderr
    assert out.exists() and not partial.exists()
    # the clean result, computed here
    atlas.run(atlas.load_config(cfg, output=tmp_path / "fresh.h5"), quiet=True)
    _assert_same(_arrays(out), _arrays(tmp_path / "fresh.h5"))


def test_resume_with_another_tile_size_keeps_the_files_tiling(tmp_path, monkeypatch):
    out = tmp_path / "t.h5"
    cfg = atlas.load_config(write_config(tmp_path / "c.yaml",
                                         MANY_TILES.format(t_max=50, output=out)))
    with monkeypatch.context() as m:
        crash_on_tile(m, 4, KeyboardInterrupt())
        with pytest.raises(KeyboardInterrupt):
            atlas.run(cfg, quiet=True)
    bigger = cfg.model_copy(update={"execution": cfg.execution.model_copy(
        update={"tile_orbits": 48 * 7})})
    resumed = atlas.run(bigger, quiet=True).to_dataset(inherit=False)
    # the partial run's tiling (one row per tile, one chunk per tile), not the new one
    assert resumed["attractor"].encoding["chunksizes"] == (1, 48)
    atlas.run(cfg.model_copy(update={"output": tmp_path / "f.h5"}), quiet=True)
    _assert_same(_arrays(out), _arrays(tmp_path / "f.h5"))


def _snapshot(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def test_a_partial_run_of_other_kernels_is_refused_until_restart(tmp_path, monkeypatch):
    """Tiles labelled by other kernel sources (a decision rule or a kernel that changed
    within one version) never mix with this build's: the run is refused in one line naming
    kernel_sources and --restart, and nothing is written."""
    from atlas.errors import InputFileError
    from atlas.pipeline import identity

    out = tmp_path / "x.h5"
    cfg = atlas.load_config(write_config(tmp_path / "c.yaml",
                                         MANY_TILES.format(t_max=50, output=out)))
    partial = out.with_name(out.name + ".partial")
    with monkeypatch.context() as m:
        m.setattr(identity, "source_hash", lambda: "an-older-build")
        crash_on_tile(m, 3, KeyboardInterrupt())
        with pytest.raises(KeyboardInterrupt):
            atlas.run(cfg, quiet=True)
    before = _snapshot(partial)
    with pytest.raises(InputFileError) as refused:
        atlas.run(cfg, quiet=True)
    assert "kernel_sources differ" in str(refused.value) and "--restart" in str(refused.value)
    assert _snapshot(partial) == before and not out.exists()
    assert atlas.run(cfg, quiet=True, restart=True).attrs["complete"] == 1


def test_a_partial_run_of_another_config_is_refused_until_restart(tmp_path, monkeypatch):
    out = tmp_path / "x.h5"
    cfg = write_config(tmp_path / "c.yaml", MANY_TILES.format(t_max=50, output=out))
    partial = out.with_name(out.name + ".partial")
    crash_on_tile(monkeypatch, 3, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        atlas.run(atlas.load_config(cfg), quiet=True)
    before = _snapshot(partial)
    assert len(before) == 3  # the manifest and two tiles
    assert not out.with_name("x.h5.lock").exists()  # an interrupted run leaves no lock
    other = write_config(tmp_path / "other.yaml", MANY_TILES.format(t_max=60, output=out))
    for flags in ([], ["--resume"]):
        proc = run_cli("run", other, *flags)
        assert proc.returncode == 2, proc.stderr
        line, = proc.stderr.strip().splitlines()
        assert "different config" in line and "integrator differ" in line
        assert "--restart" in line
        assert _snapshot(partial) == before and not out.exists()
        assert not out.with_name("x.h5.lock").exists()  # refused before taking the lock
    # separatrix settings while they are off, tiling and the name make no other identity
    same = write_config(tmp_path / "same.yaml", "name: renamed\n" + MANY_TILES.format(
        t_max=50, output=out).replace("enabled: false", "enabled: false, tol: 1e-10")
        .replace("tile_orbits: 48", "tile_orbits: 96"))
    monkeypatch.undo()
    resumed = atlas.run(atlas.load_config(same), quiet=True)
    assert resumed.attrs["complete"] == 1 and not partial.exists()
    # --restart discards a partial run of another config and starts over
    with monkeypatch.context() as m:
        crash_on_tile(m, 3, KeyboardInterrupt())
        with pytest.raises(KeyboardInterrupt):
            atlas.run(atlas.load_config(cfg), quiet=True)
    proc = run_cli("run", other, "--restart", "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert not partial.exists()
    assert atlas.open(out).attrs["t_max"] == 60


def test_dask_local_cluster_matches_the_local_backend(tmp_path):
    body = MANY_TILES.replace("execution: {{tile_orbits: 48}}",
                              "execution: {{tile_orbits: 480, workers: 2}}")
    cfg = write_config(tmp_path / "c.yaml", body.format(t_max=200, output=tmp_path / "l.h5"))
    atlas.run(atlas.load_config(cfg), quiet=True, backend="cpu")  # the local result, here
    dask = run_cli("run", cfg, "--quiet", "--backend", "dask", "-o", tmp_path / "d.h5")
    assert dask.returncode == 0, dask.stderr
    _assert_same(_arrays(tmp_path / "l.h5"), _arrays(tmp_path / "d.h5"))
    assert xr.open_dataset(tmp_path / "d.h5", engine="h5netcdf").attrs["backend"] == "dask"


def test_parameter_sweep_equals_single_parameter_runs(tmp_path):
    grid = """\
grid:
  theta0: {{start: -2pi, stop: 2pi, num: 18}}
  theta_dot0: {{start: -3, stop: 3, num: 10}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 40}}
pendulum: {{alpha: {alpha}, omega0: {omega0}}}
output: {output}
"""
    sweep_cfg = write_config(tmp_path / "s.yaml", grid.format(
        alpha="[0.05, 0.5, 2.0]", omega0="[1.0, 1.5]", output=tmp_path / "s.h5"))
    tree = atlas.run(atlas.load_config(sweep_cfg), quiet=True)
    ds = tree.to_dataset(inherit=False)
    assert ds["attractor"].dims == ("alpha", "omega0", "theta_dot0", "theta0")
    assert ds["basin_fraction"].dims == ("alpha", "omega0", "k")
    total = ds["basin_fraction"].sum("k") + ds["unresolved_fraction"]
    np.testing.assert_allclose(total, 1.0, atol=1e-12)
    # one /critical_points node per parameter point, found by its parameters; α = 0.05, 0.5
    # are underdamped for both ω0, α = 2 overdamped for both: the kinds follow α
    from atlas.layout import point_group, points

    assert len(points(ds)) == 6 and len(tree["critical_points"].children) == 6
    for point in points(ds):
        cp = point_group(tree, "critical_points", point)
        assert cp["eigenvalue_real"].dims == ("point", "eigen")
        kinds = set(cp["kind"].values[cp["n"].values % 2 == 0])
        assert kinds == {"attractor focus" if point["alpha"] < 1 else "attractor node"}
    for ia, a in enumerate([0.05, 0.5, 2.0]):
        for iw, w in enumerate([1.0, 1.5]):
            single = write_config(tmp_path / "one.yaml", grid.format(
                alpha=a, omega0=w, output=tmp_path / f"one_{ia}{iw}.h5"))
            one = atlas.run(atlas.load_config(single), quiet=True).to_dataset(inherit=False)
            for name in LABELS:
                np.testing.assert_array_equal(ds[name].values[ia, iw], one[name].values)
            frac = ds["basin_fraction"].isel(alpha=ia, omega0=iw)
            frac = frac.where(frac > 0, drop=True)
            np.testing.assert_array_equal(frac.values, one["basin_fraction"].values[
                one["basin_fraction"].values > 0])


def test_peak_memory_stays_bounded_by_the_tile(tmp_path):
    """A 2048 × 2048 grid (4.2 M orbits) in tiles of 32768 orbits: the process's peak RSS
    stays far below what holding the grid's inputs and outputs at once would take."""
    script = f"""
import resource, atlas
cfg = atlas.load_config({str(tmp_path / 'c.yaml')!r})
small = cfg.model_copy(update={{"output": cfg.output.with_name("small.h5"),
                               "grid": atlas.Config().grid.model_copy(update={{
                                   "theta0": cfg.grid.theta0.model_copy(update={{"num": 8}}),
                                   "theta_dot0": cfg.grid.theta_dot0.model_copy(
                                       update={{"num": 8}})}})}})
atlas.run(small, quiet=True)   # imports, JIT, HDF5 library: everything but the grid's size
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
atlas.run(cfg, quiet=True)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print((peak - base) / 1024)
"""
    write_config(tmp_path / "c.yaml", f"""\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 2048}}
  theta_dot0: {{start: -4, stop: 4, num: 2048}}
integrator: {{t_max: 0.08}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 32768}}
output: {tmp_path / 'big.h5'}
""")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=REPO, timeout=300)
    assert proc.returncode == 0, proc.stderr
    grown_mib = float(proc.stdout.strip().splitlines()[-1])
    whole_grid_mib = 2048 * 2048 * (8 + 8 + 2 + 1 + 4) / 2**20  # inputs + outputs: 92 MiB
    assert grown_mib < 0.5 * whole_grid_mib, grown_mib


def test_large_outputs_open_lazily(small_atlas_file):
    import dask.array as da

    ds = xr.open_dataset(small_atlas_file, engine="h5netcdf", chunks={})
    # dask arrays in the file's own chunks (one per tile: 100 orbits → 4 rows of 24), unread
    assert isinstance(ds["attractor"].data, da.Array)
    assert ds["attractor"].data.chunksize == ds["attractor"].encoding["chunksizes"] == (4, 24)
    tree = atlas.open(small_atlas_file, chunks={})
    assert isinstance(tree["attractor"].data, da.Array)
    assert tree["attractor"].data.chunksize == (4, 24)


def test_parameter_sweep_stores_each_points_separatrices(tmp_path):
    from atlas.boundaries.trace import trace
    from atlas.layout import point_group

    cfg = write_config(tmp_path / "s.yaml", f"""\
pendulum: {{alpha: [0.2, 1.0], omega0: 1.0}}
grid:
  theta0: {{start: -1.5pi, stop: 1.5pi, num: 12}}
  theta_dot0: {{start: -3, stop: 3, num: 10}}
output: {tmp_path / 's.h5'}
""")
    proc = run_cli("run", cfg)
    assert proc.returncode == 0, proc.stderr
    assert "2 parameter points" in proc.stdout
    assert "omega0 = 1, torque = 0 at every point" in proc.stdout
    table = {line[:20].strip(): line[20:].split() for line in proc.stdout.splitlines()}
    assert table["alpha [1/s]"] == ["0.2", "1"]          # one column per parameter point
    assert table["separatrices"] == ["ok", "ok"]         # each point's boundaries traced
    tree = atlas.open(tmp_path / "s.h5")
    assert sorted(tree["separatrices"].children) == ["alpha0", "alpha1"]
    for alpha in (0.2, 1.0):
        one = point_group(tree, "separatrices", {"alpha": alpha, "omega0": 1.0, "torque": 0.0})
        ref = trace(atlas.Pendulum(alpha, 1.0), (-1.5 * np.pi, 1.5 * np.pi), (-3.0, 3.0))
        np.testing.assert_array_equal(one["theta"].values, ref["theta"].values)
        np.testing.assert_array_equal(one["crossing_theta_dot"].values,
                                      ref["crossing_theta_dot"].values)
    assert atlas.open(tmp_path / "s.h5").attrs["complete"] == 1
    assert run_cli("plot", tmp_path / "s.h5").returncode == 0
