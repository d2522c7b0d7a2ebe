"""A driven pendulum's stability study: attractors followed across a swept parameter
(matching with a known answer), their sampled basin fractions checked against a grid count
of an atlas at the same point, reproducible whatever the threads or Dask, the bifurcations
located where find_attractors says they are, and bad input refused in one line.

The case: configs/driven.yaml's pendulum (α = 0.1, ω0 = 1, Ω = 1) between A = 1.66 (three
attractors: the Wada case) and A = 1.71, where a second period-1 oscillation has appeared."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.cli import main
from atlas.models.driven.attractors import Attractor, Drive, find_attractors
from atlas.models.driven.continuation import follow, locate, match, set_distance
from tests.helpers import write_config

WINDOW = ((-math.pi, math.pi), (-2.0, 4.0))

STUDY = """\
name: sweep
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {{amplitude: {amplitude}, frequency: {frequency}}}
grid:
  theta0: {{start: -pi, stop: pi, num: 2}}
  theta_dot0: {{start: -2, stop: 4, num: 2}}
integrator: {{dt: pi/100, t_max: 600}}
stability: {stability}
output: {output}
"""


def _periodic(points, period=None, winding=0):
    points = np.atleast_2d(np.asarray(points, float))
    return Attractor("periodic", points, period or len(points), winding)


# ---------------------------------------------------------------- matching, known answers

def test_set_distance_wraps_theta_and_takes_the_nearest_points():
    a = np.array([[math.pi - 0.01, 0.0]])
    b = np.array([[-math.pi + 0.02, 0.0], [0.0, 5.0]])
    assert set_distance(a, b) == pytest.approx(0.03)
    assert set_distance(a, np.zeros((0, 2))) == math.inf


def test_permuted_attractors_keep_their_ids():
    before = [_periodic([0.0, 0.0]), _periodic([[1.0, 1.0], [2.0, -1.0]], winding=2),
              _periodic([-2.0, 2.0], winding=-1)]
    after = [_periodic([-2.02, 2.01], winding=-1), _periodic([0.03, -0.01]),
             _periodic([[2.01, -1.0], [1.02, 1.0]], winding=2)]
    assert match(before, after) == {0: 2, 1: 0, 2: 1}
    ids, events = follow([before, after])
    assert ids[0].tolist() == [0, 1, 2] and ids[1].tolist() == [2, 0, 1]
    assert events == []


def test_a_birth_a_death_and_a_period_doubling_are_events_with_their_ids():
    one = [_periodic([0.0, 0.0]), _periodic([2.0, 1.0], winding=1)]
    # the oscillation doubles its period (two points straddling the old one); a new
    # attractor appears far away
    two = [_periodic([[0.05, 0.02], [-0.05, -0.02]]), _periodic([2.02, 1.0], winding=1),
           _periodic([-2.5, -1.5])]
    # the rotation dies
    three = [_periodic([[0.06, 0.02], [-0.06, -0.02]]), _periodic([-2.49, -1.5])]
    ids, events = follow([one, two, three])
    assert [i.tolist() for i in ids] == [[0, 1], [0, 1, 2], [0, 2]]
    got = [(e.step, e.kind, e.attractor, e.period_before, e.period_after) for e in events]
    assert got == [(0, "birth", 2, -1, 1), (0, "period_change", 0, 1, 2),
                   (1, "death", 1, 1, -1)]


def test_an_attractor_that_jumps_farther_than_the_threshold_dies_and_another_is_born():
    ids, events = follow([[_periodic([0.0, 0.0])], [_periodic([0.0, 0.9])]], threshold=0.5)
    assert ids[1].tolist() == [1]
    assert [e.kind for e in events] == ["birth", "death"]


def test_an_attractor_that_moves_fast_is_followed_through_midpoints():
    """An orbit at (2A, 0) moves by 2 from A = 0 to 1, four times the threshold: matched
    through two halvings (steps of 1/4 move it by 0.5, the threshold: a match; three
    midpoints found), it keeps its id; one that appears far away is still born."""
    from atlas.models.driven.continuation import bridge

    def find(a):
        return [_periodic([2 * a, 0.0])] + ([_periodic([0.0, 3.0])] if a > 0.7 else [])

    asked = []

    def counted(a):
        asked.append(a)
        return find(a)

    pairs = bridge(counted, 0.0, 1.0, find(0.0), find(1.0))
    assert pairs == {0: 0} and sorted(asked) == [0.25, 0.5, 0.75]
    ids, events = follow([find(0.0), find(1.0)], pairs={1: pairs})
    assert ids[1].tolist() == [0, 1] and [e.kind for e in events] == ["birth"]
    assert [e.kind for e in follow([find(0.0), find(1.0)])[1]] == ["birth", "birth", "death"]


def test_the_bisection_closes_in_on_synthetic_events():
    """find(A): an orbit at (A/10, 0) always; another born at A = 1.2345; the first doubles
    its period at A = 1.5; located within rtol."""
    def find(a):
        out = [_periodic([a / 10, 0.0]) if a < 1.5 else
               _periodic([[a / 10 - 0.02, 0.0], [a / 10 + 0.02, 0.0]])]
        if a >= 1.2345:
            out.append(_periodic([0.0, 2.0], winding=1))
        return out

    lo, hi = 1.0, 2.0
    ids, events = follow([find(lo), find(hi)])
    assert sorted(e.kind for e in events) == ["birth", "period_change"]
    located = locate(find, lo, hi, find(lo), find(hi), events, rtol=1e-5, max_steps=40)
    where = {e.kind: p for e, p in zip(events, located)}
    for kind, value in (("birth", 1.2345), ("period_change", 1.5)):
        p = where[kind]
        assert p.lo < value <= p.hi and p.hi - p.lo <= 1e-5 * p.hi
        assert abs(p.value - value) <= p.error


# ---------------------------------------------------------------- the physics

@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """A 2-point study over A (1.66, 1.71), 1,000 samples: the CLI's file."""
    from atlas.store.study import open_study

    folder = tmp_path_factory.mktemp("driven_study")
    config = write_config(folder / "s.yaml", STUDY.format(
        amplitude="[1.66, 1.71]", frequency=1.0, stability="{samples: 1000, seed: 7}",
        output=folder / "s.h5"))
    assert main(["stability", str(config)]) == 0
    return open_study(folder / "s.h5"), folder


def test_the_located_birth_lies_between_the_searches_that_lack_and_have_it(sweep):
    """Between A = 1.66 (one period-1 oscillation) and 1.71 (two), the second one's birth is
    located: at the lower end of its bracket find_attractors finds as many attractors as at
    1.66, at the upper end more (near the pitchfork where the oscillation splits into two
    mirror twins the orbits converge so slowly that the search records them as recurrent
    clouds), and a little further on, the two oscillations. Just outside the bracket
    nothing is asked: this close to the bifurcation the search is not monotone in A (1e-6
    below the bracket it recorded a slow transient as a cloud), as docs/continuation.md
    says of a located birth."""
    ds, _ = sweep
    births = [i for i in range(ds.sizes["bifurcation"])
              if int(ds["bifurcation_kind"][i]) == 0]
    assert len(births) == 1 and int(ds["bifurcation_period_after"][births[0]]) == 1
    value = float(ds["bifurcation_value"][births[0]])
    error = float(ds["bifurcation_error"][births[0]])
    assert 1.66 < value < 1.71 and error <= 1e-4 * value

    def found(a):
        return find_attractors(Drive(0.1, 1.0, 0.0, a, 1.0, 0.0, 200), WINDOW)

    before = len(found(1.66))
    assert len(found(value - error)) == before  # the bracket's ends, searched again
    assert len(found(value + error)) > before
    assert sum(1 for a in found(value + 0.005) if a.period == 1 and a.winding == 0) == 2
    gid = int(ds["bifurcation_attractor"][births[0]])
    assert (ds["attractor_kind"].values[:, gid] > 0).tolist() == [False, True]


def test_the_file_holds_fractions_that_sum_to_one_with_binomial_errors(sweep):
    ds, folder = sweep
    n = int(ds.attrs["samples"])
    assert n == 1000 and int(ds.attrs["seed"]) == 7 and ds.attrs["model"] == "driven_pendulum"
    f, e = ds["basin_fraction"].values, ds["basin_fraction_error"].values
    np.testing.assert_allclose(np.nansum(f, axis=1) + ds["unresolved_fraction"].values, 1.0)
    np.testing.assert_allclose(e, np.sqrt(f * (1 - f) / n))
    assert ds["attractor_count"].values.tolist()[0] == 3
    for name in ("basin_fraction", "orbit_theta", "bifurcation_value"):
        assert ds[name].attrs["long_name"] and "units" in ds[name].attrs
    assert ds["bifurcation_value"].attrs["units"] == "rad s-2"
    lines = "\n".join(_run(["info", str(folder / "s.h5")]))
    assert "driven pendulum study: amplitude from 1.66 to 1.71 (2 points)" in lines
    assert "birth of #" in lines
    assert main(["plot", str(folder / "s.h5")]) == 0
    for name in ("s_orbits.png", "s_fractions.png"):
        assert (folder / name).stat().st_size > 10_000


@pytest.mark.parametrize("spoil, words", [
    (lambda ds: ds["basin_fraction"].__setitem__((0, 0), 0.9),
     "not fractions summing to 1"),
    (lambda ds: ds["orbit_attractor"].__setitem__(0, 99), "orbit_attractor names"),
    (lambda ds: ds.attrs.__setitem__("swept_parameter", "gravity"), "swept parameter"),
    (lambda ds: ds.attrs.__setitem__("samples", 1.5), "samples"),
])
def test_a_spoiled_driven_study_is_refused_in_one_line(sweep, tmp_path, spoil, words):
    from atlas.errors import InputFileError
    from atlas.store.study import open_study

    ds, _ = sweep
    bad = ds.copy(deep=True)
    spoil(bad)
    bad.to_netcdf(tmp_path / "bad.h5", engine="h5netcdf")
    with pytest.raises(InputFileError, match=words) as caught:
        open_study(tmp_path / "bad.h5")
    assert "\n" not in str(caught.value)


def _run(argv):
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(argv) == 0
    return out.getvalue().splitlines()


def test_the_fractions_agree_with_a_grid_atlas_at_the_same_point(sweep, tmp_path):
    """The sampled fractions at A = 1.66 against an independent count: a driven atlas's grid
    (40 × 40 orbits, its own run), attractor by attractor, within 4 combined standard
    errors."""
    ds, _ = sweep
    body = STUDY.format(amplitude=1.66, frequency=1.0, stability="null",
                        output=tmp_path / "grid.h5").replace("num: 2}", "num: 40}")
    assert main(["run", str(write_config(tmp_path / "g.yaml", body)), "--quiet"]) == 0
    import xarray as xr

    grid = xr.open_dataset(tmp_path / "grid.h5", engine="h5netcdf")
    g = np.asarray(grid["basin_fraction"].values).ravel()
    n_grid = 40 * 40
    f = ds["basin_fraction"].values[0]
    present = np.isfinite(f)
    assert present.sum() == g.size == 3
    se = np.sqrt(f[present] * (1 - f[present]) / 1000 + g * (1 - g) / n_grid)
    assert np.all(np.abs(f[present] - g) <= 4 * se), (f, g)


def test_the_standard_error_is_the_spread_between_seeds():
    """At A = 1.66 the fractions of 8 seeds (400 samples each) scatter as the binomial
    standard error says (their standard deviation within a factor 2 of it)."""
    from atlas.stability.driven import DrivenSettings, compute_point

    params = {"alpha": 0.1, "omega0": 1.0, "torque": 0.0, "amplitude": 1.66,
              "frequency": 1.0, "phase": 0.0}
    runs = [compute_point(params, DrivenSettings(WINDOW, 400, seed, 8, 600.0, math.pi / 100))
            for seed in range(8)]
    f = np.array([r.counts / 400 for r in runs])
    spread = f.std(axis=0, ddof=1)
    binomial = np.sqrt(f.mean(axis=0) * (1 - f.mean(axis=0)) / 400)
    assert np.all((spread > binomial / 2) & (spread < 2 * binomial)), (spread, binomial)


def test_the_study_is_the_same_whatever_the_threads():
    from atlas.stability.driven import DrivenSettings, compute_point, compute_study

    settings = DrivenSettings(WINDOW, 300, 3, 8, 600.0, math.pi / 100, max_steps=3)
    points = [{"alpha": 0.1, "omega0": 1.0, "torque": 0.0, "amplitude": a, "frequency": 1.0,
               "phase": 0.0} for a in (1.66, 1.71)]
    one = compute_study(points, "amplitude", settings, workers=1)
    two = compute_study(points, "amplitude", settings, workers=2)
    for a, b in zip(one.results, two.results):
        np.testing.assert_array_equal(a.counts, b.counts)
    assert [p.value for p in one.located] == [p.value for p in two.located]
    assert [i.tolist() for i in one.ids] == [i.tolist() for i in two.ids]
    threads = [compute_point(points[0], settings, numba_threads=n).counts for n in (1, 2)]
    np.testing.assert_array_equal(*threads)


@pytest.mark.slow
def test_a_dask_cluster_computes_the_study_of_this_process():
    distributed = pytest.importorskip("distributed")
    from atlas.stability.driven import DrivenSettings, compute_study

    settings = DrivenSettings(WINDOW, 300, 3, 8, 600.0, math.pi / 100, max_steps=3)
    points = [{"alpha": 0.1, "omega0": 1.0, "torque": 0.0, "amplitude": a, "frequency": 1.0,
               "phase": 0.0} for a in (1.66, 1.71)]
    here = compute_study(points, "amplitude", settings, workers=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=":0") as cluster:
        there = compute_study(points, "amplitude", settings, backend="dask",
                              scheduler=cluster.scheduler_address)
    for a, b in zip(here.results, there.results):
        np.testing.assert_array_equal(a.counts, b.counts)
    assert [p.value for p in here.located] == [p.value for p in there.located]
    assert [(e.kind, e.attractor) for e in here.events] == \
        [(e.kind, e.attractor) for e in there.events]


# ---------------------------------------------------------------- bad input

@pytest.mark.parametrize("amplitude, frequency, stability, words", [
    ("[1.6, 1.7]", "[1.0, 2.0]", "null", "one swept parameter"),
    ("[1.6, 1.7]", 1.0, "{samples: 0}", "stability.samples"),
    ("[1.6, 1.7]", 1.0, "{samples: -5}", "stability.samples"),
    ("[1.6, 1.7]", 1.0, "{tipping: true}", "stability.tipping"),
    (1.66, "[1.0, 2.0]", "null", "pendulum.drive.frequency: a driven study's bisections"),
    ("[1.7, 1.6]", 1.0, "null", "pendulum.drive.amplitude: a driven study follows its "
                                "attractors along increasing values"),
    ("[1.6, 1.7], search_window: {theta0: [-4, 4], theta_dot0: [-3, 5]}", 1.0, "null",
     "pendulum.drive.search_window: a driven study searches"),
])
def test_bad_input_is_refused_in_one_line(tmp_path, capsys, amplitude, frequency, stability,
                                          words):
    config = write_config(tmp_path / "bad.yaml", STUDY.format(
        amplitude=amplitude, frequency=frequency, stability=stability,
        output=tmp_path / "bad.h5"))
    assert main(["stability", str(config)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err, err
    assert not (tmp_path / "bad.h5").exists()


def test_samples_are_refused_for_the_undriven_pendulum(tmp_path, capsys):
    config = write_config(tmp_path / "u.yaml", """\
        pendulum: {alpha: 0.1, omega0: 1.0, torque: [0.1, 0.2]}
        grid:
          theta0: {start: -pi, stop: pi, num: 2}
          theta_dot0: {start: -2, stop: 2, num: 2}
        stability: {samples: 1000}
        output: u.h5
        """)
    assert main(["stability", str(config)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "stability.samples" in err, err


def test_an_id_whose_period_changes_is_named_with_every_form_it_takes():
    """The key names an id as it is at most of its points and adds what else it is along
    the sweep (the period changes its events mark), in the order met; an id that never
    changes is named once."""
    import xarray as xr

    from atlas.views.driven_study import id_names

    dims = ("amplitude", "attractor_id")
    ds = xr.Dataset({"attractor_kind": (dims, [[1, 1], [1, 1], [1, 0], [2, 0]]),
                     "attractor_period": (dims, [[2, 1], [1, 1], [1, -1], [0, -1]]),
                     "attractor_winding": (dims, [[-2, 0], [-1, 0], [-1, 0], [0, 0]])},
                    coords={"attractor_id": [0, 1]})
    assert id_names(ds) == {0: "#0 rotation, period 1, winding -1; also period 2, winding -2, "
                               "chaotic",
                            1: "#1 oscillation, period 1"}
