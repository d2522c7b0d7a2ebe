"""The driven pendulum θ̈ + 2αθ̇ + ω0² sin θ = τ + A cos(Ω t + φ) behind the model seam: its
attractors found and refined, its grid labelled, its file read by atlas info, plot and view.

The case: b = 0.2, F = 1.66, Ω = 1 of Wagemakers, Daza & Sanjuán, "How to detect Wada
basins", DCDS-B 26 (2021), Fig. 2(a) (atlas: α = b/2 = 0.1, ω0 = 1, A = F): three
attractors whose basins have the Wada property, on the window [−π, π] × [−2, 4]."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import atlas
from atlas.cli import main
from atlas.models.driven.attractors import Drive, find_attractors, wrap
from atlas.models.driven.description import CHAOTIC, CONVERGED, NEAR
from tests.helpers import write_config

WADA = Drive(alpha=0.1, omega0=1.0, torque=0.0, amplitude=1.66, frequency=1.0, phase=0.0,
             steps_per_period=200)
WINDOW = ((-math.pi, math.pi), (-2.0, 4.0))

CONFIG = """\
name: driven
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {{amplitude: {amplitude}, frequency: 1.0}}
grid:
  theta0: {{start: -pi, stop: pi, num: 20}}
  theta_dot0: {{start: -2, stop: 4, num: 16}}
integrator: {{dt: pi/100, t_max: 600}}
execution: {{tile_orbits: 100}}
output: {output}
"""


def _exact_map(state, periods: int, drive: Drive = WADA) -> np.ndarray:
    """P^periods by DOP853 at rtol 1e-12 (an independent integrator)."""
    def field(t, y):
        return (y[1], drive.torque + drive.amplitude * math.cos(drive.frequency * t
                                                                 + drive.phase)
                - drive.omega0 ** 2 * math.sin(y[0]) - 2 * drive.alpha * y[1])

    sol = solve_ivp(field, (0.0, periods * drive.period), state, method="DOP853",
                    rtol=1e-12, atol=1e-12)
    return sol.y[:, -1]


@pytest.fixture(scope="module")
def wada_attractors():
    return find_attractors(WADA, WINDOW)


def test_the_three_attractors_of_the_wada_case_are_found(wada_attractors):
    """Three attractors (the published count), each a stable periodic orbit refined by
    Newton to 1e-12 on the RK4 map, whose points are periodic points of the exact equation
    too: P^p by DOP853 returns to them within the RK4 map's own error (dt = T/200)."""
    found = wada_attractors
    assert len(found) == 3, [(a.kind, a.period, a.winding) for a in found]
    for a in found:
        assert a.kind == "periodic" and a.residual <= 1e-12
        assert np.all(np.abs(a.multipliers) < 1.0)
        x = a.points[0]
        image = _exact_map(x, a.period)
        miss = np.hypot(wrap(image[0] - x[0]), image[1] - x[1])
        assert miss < 1e-4, (a.period, a.winding, miss)
    # mirror twins are kept apart by their points, not merged by (period, winding)
    keys = [(a.period, a.winding) for a in found]
    firsts = np.array([a.points[0] for a in found])
    assert len({tuple(np.round(f, 6)) for f in firsts}) == len(keys)


def test_the_four_attractors_at_a_171_include_mirror_twins():
    """At F = 1.71 the published count is four (Wagemakers, Daza & Sanjuán 2021, Fig. 2(b)):
    two period-1 oscillations with the same period and winding (mirror twins, kept as two
    attractors by their points) and the two period-2 rotations; each a periodic point of
    the exact equation too (DOP853)."""
    found = find_attractors(replace(WADA, amplitude=1.71), WINDOW)
    assert sorted((a.period, a.winding) for a in found) == [(1, 0), (1, 0), (2, -2), (2, 2)]
    twins = [a for a in found if a.period == 1]
    assert np.hypot(wrap(twins[0].points[0, 0] - twins[1].points[0, 0]),
                    twins[0].points[0, 1] - twins[1].points[0, 1]) > 0.1
    for a in found:
        assert a.kind == "periodic" and a.residual <= 1e-12
        assert np.all(np.abs(a.multipliers) < 1.0)
        image = _exact_map(a.points[0], a.period, replace(WADA, amplitude=1.71))
        assert np.hypot(wrap(image[0] - a.points[0, 0]), image[1] - a.points[0, 1]) < 1e-4


def test_a_chaotic_attractor_is_named_chaotic_not_periodic():
    """θ̈ + θ̇/q + sin θ = g cos(ω_D t) with q = 2, g = 1.5, ω_D = 2/3 is chaotic (Baker &
    Gollub, *Chaotic Dynamics: An Introduction*, 2nd ed., CUP 1996, ch. 3; atlas: α =
    1/(2q) = 0.25, A = g, Ω = ω_D): the finder reports a chaotic attractor, with no
    period."""
    drive = Drive(0.25, 1.0, 0.0, 1.5, 2.0 / 3.0, 0.0, 200)
    found = find_attractors(drive, WINDOW, seeds=4)
    assert any(a.kind == "chaotic" and a.period == 0 for a in found), \
        [(a.kind, a.period) for a in found]


@pytest.fixture(scope="module")
def wada_atlas(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("wada")
    cfg = atlas.load_config(write_config(tmp / "wada.yaml",
                                         CONFIG.format(amplitude=1.66, output=tmp / "w.h5")))
    atlas.run(cfg, quiet=True)
    return tmp / "w.h5"


def test_the_file_names_its_model_and_stores_its_attractors(wada_atlas):
    tree = atlas.open(wada_atlas)
    ds = tree.to_dataset(inherit=False)
    assert ds.attrs["model"] == "driven_pendulum"
    assert float(ds["amplitude"]) == 1.66 and float(ds["frequency"]) == 1.0
    group = tree["attractors"].to_dataset()
    assert group.sizes["attractor"] == 3
    assert json.loads(ds.attrs["config"])["pendulum"]["drive"]["amplitude"] == 1.66
    labelled = np.isin(ds["status"].values, (CONVERGED, NEAR, CHAOTIC))
    assert set(np.unique(ds["attractor"].values[labelled])) <= {0, 1, 2}
    # the summary is the map's own count
    for k in range(3):
        assert float(ds["basin_fraction"].sel(k=k)) == pytest.approx(
            np.mean(ds["attractor"].values == k), abs=1e-12)


def test_each_label_is_the_attractor_its_orbit_reaches(wada_atlas, wada_attractors):
    """Every labelled orbit, iterated further by the RK4 map (the kernel's own P, 200 more
    periods), ends within the capture radius of the attractor it is labelled with."""
    from atlas.kernels import driven as kernels

    tree = atlas.open(wada_atlas)
    ds = tree.to_dataset(inherit=False)
    group = tree["attractors"].to_dataset()
    n = int(group.attrs["steps_per_period"])
    drive = Drive(0.1, 1.0, 0.0, 1.66, 1.0, 0.0, n)
    theta0, theta_dot0 = np.meshgrid(ds["theta0"].values, ds["theta_dot0"].values)
    labelled = np.isin(ds["status"].values, (CONVERGED, NEAR))
    theta, theta_dot = theta0[labelled].copy(), theta_dot0[labelled].copy()
    kernels.advance(theta, theta_dot, drive.alpha, drive.omega0, drive.torque, drive.table,
                    drive.dt, 600)
    for th, v, k in zip(theta, theta_dot, ds["attractor"].values[labelled]):
        pts = np.column_stack([group["theta"].values[k], group["theta_dot"].values[k]])
        pts = pts[np.isfinite(pts[:, 0])]
        d = np.hypot(wrap(th - pts[:, 0]), v - pts[:, 1]).min()
        assert d < float(group["capture_radius"].values[k]), (th, v, k, d)


@pytest.mark.parametrize("amplitude", [1.66, 1.71])
def test_one_return_into_a_contracting_ball_decides_as_eight_in_a_row(amplitude):
    """A ``converged`` label is decided at the first return into its attractor's capture
    ball, which was seen to map into itself: on a 64² grid of the window (and at F = 1.71,
    four attractors) every label is the one that eight returns in a row give (the rule
    before), each decided at least CONFIRM − 1 returns sooner."""
    from atlas.models.driven.description import CONFIRM
    from atlas.models.driven.points import prepared

    drive = replace(WADA, amplitude=amplitude)
    point, found, statuses, _ = prepared(drive, WINDOW, 8, 600.0)
    assert list(point.confirm) == [1] * len(found) and np.all(statuses == CONVERGED)
    x0, v0 = np.linspace(-math.pi, math.pi, 64)[None, :], np.linspace(-2, 4, 64)[:, None]
    one = point.label(x0, v0)
    eight = replace(point, confirm=np.full(len(found), CONFIRM)).label(x0, v0)
    decided = np.isfinite(eight[2])
    assert decided.mean() > 0.99
    np.testing.assert_array_equal(one[0][decided], eight[0][decided])
    np.testing.assert_array_equal(one[1][decided], eight[1][decided])
    assert np.all(one[2][decided] <= eight[2][decided] - (CONFIRM - 1) * drive.period + 1e-3)
    # undecided by t_max at eight in a row: within the last CONFIRM - 1 periods at one
    late = ~decided & np.isfinite(one[2])
    assert np.all(one[2][late] > (point.max_periods - CONFIRM + 1) * drive.period - 1e-3)


def test_info_plot_and_view_read_it(wada_atlas, capsys):
    assert main(["info", str(wada_atlas)]) == 0
    out = capsys.readouterr().out
    assert "attractors of the stroboscopic map: 3" in out
    assert out.count("#") >= 3 and "period" in out
    assert main(["plot", str(wada_atlas)]) == 0
    assert wada_atlas.with_suffix(".png").exists()
    assert main(["view", str(wada_atlas)]) == 0
    assert "driven_pendulum" in wada_atlas.with_suffix(".html").read_text()


def test_its_bad_input_is_one_line(tmp_path, capsys):
    body = CONFIG.format(amplitude=1.66, output=tmp_path / "b.h5")
    for bad, word in ((body.replace("dt: pi/100", "dt: 1.0"), "integrator.dt"),
                      (body.replace("t_max: 600", "t_max: 20"), "integrator.t_max"),
                      (body.replace("amplitude: 1.66", "amplitude: -1"), "amplitude"),
                      (body.replace("dt: pi/100", "dt: 1e-5"), "integrator.dt"),
                      (body.replace("t_max: 600", "t_max: 1e9"), "integrator.t_max"),
                      (body.replace("frequency: 1.0", "frequency: 0"), "frequency"),
                      (body.replace("amplitude: 1.66", "amplitude: []"), "amplitude"),
                      (body.replace("amplitude: 1.66", "amplitude: .nan"), "amplitude"),
                      (body.replace("frequency: 1.0", "frequency: -1.0"), "frequency"),
                      (body.replace("frequency: 1.0", "frequency: 1.0, max_period: 0"),
                       "max_period"),
                      (body.replace("frequency: 1.0", "frequency: 1.0, max_period: 2.5"),
                       "max_period"),
                      (body.replace("dt: pi/100", "dt: 0.05"), "integrator.dt"),
                      (body.replace("frequency: 1.0", "frequency: 1.0, search_window: "
                                    "{theta0: [-1, 1], theta_dot0: [-2, 4]}"),
                       "search_window.theta0: [-1, 1] must contain the grid's"),
                      (body.replace("frequency: 1.0", "frequency: 1.0, search_window: "
                                    "{theta0: [-1e300, 1e300], theta_dot0: [-2, 4]}"),
                       "times as wide as the grid's window")):
        path = write_config(tmp_path / "bad.yaml", bad)
        assert main(["run", str(path)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and word in err[0], err
    assert not list(tmp_path.glob("*.h5"))


def test_a_dt_that_is_not_a_whole_fraction_of_the_period_names_the_nearest_that_are(
        tmp_path, capsys):
    """dt = 0.05 s is not T/N for T = 2π s: the line names N = 126 and N = 125 and their dt,
    which (written as 2pi/126) are then accepted; in a sweep over Ω the frequency at which
    dt fails is named."""
    body = CONFIG.format(amplitude=1.66, output=tmp_path / "n.h5")
    path = write_config(tmp_path / "n.yaml", body.replace("dt: pi/100", "dt: 0.05"))
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert "N = 126 gives dt = 0.0498665" in err and "N = 125 gives 0.0502654" in err, err
    for n in (125, 126):
        ok = body.replace("dt: pi/100", f"dt: 2pi/{n}")
        atlas.load_config(write_config(tmp_path / "ok.yaml", ok))  # no error
    swept = body.replace("frequency: 1.0", "frequency: [1.0, 1.1]")
    path = write_config(tmp_path / "s.yaml", swept)
    assert main(["run", str(path)]) == 2
    assert "Ω = 1.1 rad/s" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.h5"))


def test_the_period_bound_is_the_configs_and_is_stored(tmp_path, caplog):
    """``drive.max_period`` bounds the periodic orbits searched for and is stored: with 1,
    the period-2 rotations of the three-attractor case are not periodic up to the bound and
    are kept as recurrent (chaotic) attractors, never as periodic ones; with the default 8
    all three are periodic."""
    def attractors(extra: str):
        body = CONFIG.format(amplitude=1.66, output=tmp_path / "m.h5").replace(
            "frequency: 1.0", "frequency: 1.0" + extra).replace("num: 20", "num: 4").replace(
            "num: 16", "num: 4")
        cfg = atlas.load_config(write_config(tmp_path / "m.yaml", body))
        return atlas.run(cfg, output=None, quiet=True)["attractors"].to_dataset()

    bounded = attractors(", max_period: 1")
    assert "raise max_period to find it periodic" in caplog.text
    default = attractors("")
    assert int(bounded.attrs["max_period"]) == 1 and int(default.attrs["max_period"]) == 8
    assert sorted(default["period"].values.tolist()) == [1, 2, 2]
    assert set(default["kind"].values.tolist()) == {"periodic"}
    periodic = bounded["kind"].values == "periodic"
    assert bounded["period"].values[periodic].tolist() == [1]
    assert (~periodic).sum() == 2  # the two rotations, kept apart


def test_labels_that_change_with_dt_are_flagged_and_fewer_as_dt_shrinks(tmp_path):
    """Each label is computed again with dt/2: ``changes_at_half_dt`` is 1 exactly where
    the label at dt/2 (the same config at half the step, computed on its own) differs, and
    the share of such labels falls as dt → 0 (the fractions converge)."""
    def run(steps: int):
        body = CONFIG.format(amplitude=1.66, output=tmp_path / "c.h5").replace(
            "dt: pi/100", f"dt: {2 * math.pi / steps!r}")
        cfg = atlas.load_config(write_config(tmp_path / f"c{steps}.yaml", body))
        return atlas.run(cfg, output=None, quiet=True).to_dataset(inherit=False)

    shares = {}
    for steps in (50, 100, 200, 400):
        ds = run(steps)
        shares[steps] = float(ds["changed_at_half_dt_fraction"])
        assert shares[steps] == pytest.approx(float(ds["changes_at_half_dt"].mean()))
        if steps == 100:
            halved = run(200)  # its own run at dt/2 (its own attractors: the same ones here)
            np.testing.assert_array_equal(
                ds["changes_at_half_dt"].values == 1,
                ds["attractor"].values != halved["attractor"].values)
    assert shares[50] > shares[400], shares
    assert shares[400] <= shares[100], shares


DRIVEN_CUDA = r"""
import json
import numpy as np
import atlas
from atlas.kernels.cuda import cuda_status
assert cuda_status() == (True, "CUDA simulator"), cuda_status()
cfg = atlas.load_config({config!r})
gpu = atlas.run(cfg, output=None, backend="cuda", quiet=True).to_dataset(inherit=False)
cpu = atlas.run(cfg, output=None, backend="cpu", quiet=True).to_dataset(inherit=False)
print(json.dumps({{name: bool(np.array_equal(gpu[name].values, cpu[name].values,
                                            equal_nan=True))
                  for name in ("attractor", "status", "t_trap", "changes_at_half_dt")}}))
"""


@pytest.mark.slow
def test_the_cuda_backend_labels_as_the_cpu(tmp_path):
    """``backend: cuda`` (numba's simulator, in a process of its own) labels a driven atlas,
    its check at dt/2 included, as the CPU kernels do."""
    from tests.kernels.test_cuda import _child

    cfg = write_config(tmp_path / "gpu.yaml", CONFIG.format(
        amplitude=1.66, output=tmp_path / "gpu.h5").replace("num: 20", "num: 4").replace(
        "num: 16", "num: 3").replace("dt: pi/100, t_max: 600", "dt: pi/16, t_max: 320"))
    assert _child(DRIVEN_CUDA.format(config=str(cfg)), simulator=True) == {
        "attractor": True, "status": True, "t_trap": True, "changes_at_half_dt": True}


@pytest.mark.slow
def test_a_dask_cluster_labels_as_this_process(tmp_path):
    """The driven pendulum's tiles on a local Dask cluster (2 worker processes, each point's
    plan pickled to them) give this process's arrays."""
    distributed = pytest.importorskip("distributed")
    body = CONFIG.format(amplitude=1.66, output=tmp_path / "d.h5")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        dask = atlas.load_config(write_config(tmp_path / "d.yaml", body.replace(
            "execution: {tile_orbits: 100}",
            f'execution: {{tile_orbits: 100, backend: dask, scheduler: '
            f'"{cluster.scheduler_address}"}}')))
        there = atlas.run(dask, quiet=True).to_dataset(inherit=False)
    here = atlas.run(dask, output=None, backend="cpu", quiet=True).to_dataset(inherit=False)
    for name in ("attractor", "status", "t_trap", "changes_at_half_dt"):
        np.testing.assert_array_equal(there[name].values, here[name].values, err_msg=name)


@pytest.mark.parametrize("suffix", [".h5", ".zarr"])
def test_a_crash_mid_run_loses_nothing_and_the_resumed_file_is_the_same(tmp_path, monkeypatch,
                                                                        suffix):
    """A driven run stopped at its third tile (HDF5 or Zarr) keeps its finished tiles; run
    again, it computes the rest, and its arrays (labels, their check at dt/2, the summary,
    the attractors) equal an undisturbed run's."""
    pytest.importorskip("zarr") if suffix == ".zarr" else None
    from tests.helpers import crash_on_tile

    body = CONFIG.format(amplitude=1.66, output=tmp_path / f"r{suffix}").replace(
        "tile_orbits: 100", "tile_orbits: 64")
    cfg = atlas.load_config(write_config(tmp_path / "r.yaml", body))
    with monkeypatch.context() as m:
        crash_on_tile(m, 3, KeyboardInterrupt())
        with pytest.raises(KeyboardInterrupt):
            atlas.run(cfg, quiet=True)
    assert not (tmp_path / f"r{suffix}").exists()
    assert (tmp_path / f"r{suffix}.partial").exists()
    resumed = atlas.run(cfg, quiet=True)
    fresh = atlas.run(cfg.model_copy(update={"output": tmp_path / f"f{suffix}"}), quiet=True)
    for node in ("/", "/attractors"):
        a, b = resumed[node].to_dataset(inherit=False), fresh[node].to_dataset(inherit=False)
        assert set(a.data_vars) == set(b.data_vars)
        for name in a.data_vars:
            np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_labels_do_not_depend_on_thread_count_or_batch_split():
    """The same orbits labelled with 1 thread, with every thread, and in three batches:
    the same attractor, status and t_trap (the lanes of a block do not share anything that
    the thread count or the split could change)."""
    import numba

    from atlas.models.driven.points import DrivenPoint

    found = find_attractors(WADA, WINDOW)
    targets = np.concatenate([a.points for a in found])
    owner = np.concatenate([np.full(len(a.points), i, np.int16) for i, a in enumerate(found)])
    point = DrivenPoint(WADA, targets, owner, np.zeros(len(found), np.int8),
                        np.full(len(owner), 0.02), np.full(len(found), 8), 100)
    rng = np.random.default_rng(3)
    theta0, theta_dot0 = rng.uniform(-math.pi, math.pi, 777), rng.uniform(-2, 4, 777)
    one = point.label(theta0, theta_dot0, numba_threads=1)[:3]
    many = point.label(theta0, theta_dot0, numba_threads=numba.config.NUMBA_NUM_THREADS)[:3]
    pieces = [point.label(theta0[s], theta_dot0[s])[:3]
              for s in (slice(0, 1), slice(1, 300), slice(300, 777))]
    for i in range(3):
        np.testing.assert_array_equal(one[i], many[i])
        np.testing.assert_array_equal(one[i], np.concatenate([p[i] for p in pieces]))
    assert (one[1] == 0).mean() > 0.5  # most of them decided: the test compares labels


def test_the_shifted_spread_is_that_of_the_four_interleaved_grids(wada_atlas):
    """basin_fraction_shifted_spread, tallied tile by tile, is the spread of the fractions
    counted on the stored map's four parity subgrids, recomputed here from the map."""
    ds = atlas.open(wada_atlas).to_dataset(inherit=False)
    labels = ds["attractor"].values
    fractions = np.array([[np.mean(labels[i::2, j::2] == k) for k in ds["k"].values]
                          for i in (0, 1) for j in (0, 1)])
    np.testing.assert_allclose(ds["basin_fraction_shifted_spread"].values,
                               fractions.std(axis=0, ddof=1) / 2, rtol=1e-12)
    f = ds["basin_fraction"].values
    binomial = np.sqrt(f * (1 - f) / labels.size)
    half = np.abs(f - np.array([np.mean(labels == k) for k in ds["k"].values]))  # 0: same map
    assert np.all(ds["basin_fraction_error"].values + 1e-15 >= np.maximum(
        binomial, ds["basin_fraction_shifted_spread"].values) + half)


def test_a_coarse_grids_error_covers_a_fine_grids_fraction(tmp_path):
    """A resolution study: the fractions of a 40² grid lie within two of their stated
    errors of the fractions of a 160² grid of the same window (the fine grid's own error
    added), for every attractor."""
    def run(num):
        body = CONFIG.format(amplitude=1.66, output=tmp_path / "g.h5").replace(
            "num: 20", f"num: {num}").replace("num: 16", f"num: {num}")
        cfg = atlas.load_config(write_config(tmp_path / f"g{num}.yaml", body))
        return atlas.run(cfg, output=None, quiet=True).to_dataset(inherit=False)

    coarse, fine = run(40), run(160)
    gap = np.abs(coarse["basin_fraction"].values - fine["basin_fraction"].values)
    bound = 2 * coarse["basin_fraction_error"].values + fine["basin_fraction_error"].values
    assert np.all(gap <= bound), (gap, bound)


@pytest.mark.slow
def test_orbits_on_a_chaotic_attractor_are_labelled_chaotic(tmp_path):
    """Baker & Gollub's chaotic pendulum (as above), a 12 × 12 grid: its one attractor is a
    cloud, and most orbits are labelled on it within t_max (the capture radius is measured
    on the points it is tested against; measured on the whole recorded cloud, twice as dense,
    it left half the orbits unresolved)."""
    body = CONFIG.format(amplitude=1.5, output=tmp_path / "c.h5").replace(
        "alpha: 0.1", "alpha: 0.25").replace("frequency: 1.0", "frequency: 0.6666666666666666"
    ).replace("num: 20", "num: 12").replace("num: 16", "num: 12").replace(
        "dt: pi/100, t_max: 600", "dt: 3pi/200, t_max: 1000")
    cfg = atlas.load_config(write_config(tmp_path / "c.yaml", body))
    tree = atlas.run(cfg, output=None, quiet=True)
    assert tree["attractors"].to_dataset()["kind"].values.tolist() == ["chaotic"]
    status = tree.to_dataset(inherit=False)["status"].values
    assert np.mean(status == CHAOTIC) >= 0.8, np.mean(status == CHAOTIC)


def test_the_stored_confirm_is_read_back_checked_and_has_a_fallback(wada_atlas, tmp_path,
                                                                    capsys):
    """``/attractors/confirm`` as the run wrote it (1 for each converged attractor); a file
    without it (written before it) decides with its ``confirm`` attribute for all; a damaged
    one (0) is refused by ``atlas orbit`` and ``atlas view`` in one line, nothing written."""
    import shutil

    import h5py

    from atlas.models.driven.description import stored_confirm

    group = atlas.open(wada_atlas)["attractors"].to_dataset()
    assert stored_confirm(group).tolist() == [1, 1, 1]
    older = group.drop_vars("confirm").assign_attrs(confirm=np.int64(8))
    assert stored_confirm(older).tolist() == [8, 8, 8]
    bad = tmp_path / "bad.h5"
    shutil.copy(wada_atlas, bad)
    with h5py.File(bad, "r+") as f:
        f["attractors/confirm"][...] = 0
    for args in (["orbit", str(bad), "-2", "3", "-o", str(tmp_path / "o.png")],
                 ["view", str(bad), "-o", str(tmp_path / "v.html")]):
        assert main(args) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "confirm" in err[0] and ">= 1" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.h5"]
