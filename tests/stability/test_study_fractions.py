"""A study's basin stability is a grid run's exact fraction at the same point (to 1e-12), and
the grid counts of atlas's labels converge to it at first order in the grid step (the honest
lattice bound: the cells a boundary of length L crosses, ≤ L(hθ + hθ̇)/(hθ hθ̇), each
misjudged at most)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.boundaries.exact import exact_boundaries
from atlas.physics.pendulum import Pendulum
from atlas.stability.polygons import basin_shape, window_basins
from atlas.stability.study import StudySettings, compute_point
from tests.helpers import small_atlas

pytestmark = pytest.mark.slow  # grid runs and labels


def _window(ds):
    theta, speed = ds["theta0"].values, ds["theta_dot0"].values
    return ((float(theta[0]), float(theta[-1])), (float(speed[0]), float(speed[-1])))


def _compare(tree, points):
    ds = tree.to_dataset() if hasattr(tree, "to_dataset") else tree
    settings = StudySettings(window=_window(ds))
    for index, (alpha, omega0, torque) in points:
        stored = ds.isel(index) if index else ds
        r = compute_point(alpha, omega0, torque, settings)
        exact = stored["basin_fraction_exact"]
        for k, fraction in zip(r.k, r.fraction):
            assert abs(float(exact.sel(k=k)) - fraction) < 1e-12
        others = np.setdiff1d(exact["k"].values, r.k)
        assert np.all(np.nan_to_num(exact.sel(k=others).values) == 0.0)
        if "running_fraction_exact" in stored:
            assert abs(float(stored["running_fraction_exact"]) - r.running) < 1e-12


def test_untilted_sweep_equals_the_grid_run(tmp_path):
    tree = small_atlas(tmp_path, "u", {"alpha": [0.1, 0.3], "omega0": 1.0},
                       theta=("-pi", "pi"), speed=(-3.0, 3.0), num=(16, 12),
                       separatrices=False, t_max=200.0)
    _compare(tree, [({"alpha": 0}, (0.1, 1.0, 0.0)), ({"alpha": 1}, (0.3, 1.0, 0.0))])


def test_swing_point_equals_the_grid_run(swing_atlas):
    tree = atlas.open(swing_atlas)
    try:
        _compare(tree, [(None, (0.05, 1.0, 0.5))])
    finally:
        tree.close()


@pytest.mark.parametrize("alpha, torque", [(0.3, 0.0), (0.1, 0.5)])
def test_grid_counts_converge_at_first_order(alpha, torque):
    """Cell-centre lattices of n² orbits, n = 32 … 256: each basin's count (the wells', and
    with torque the running basin's) is within the lattice bound C·h of the exact fraction
    the study stores (first order in the step h: the cells a boundary crosses), and the
    error falls as h does."""
    from atlas.boundaries.basins import RUNNING_SIDE
    from atlas.physics.running import running_certificate
    from atlas.status import RUNNING

    p = Pendulum(alpha, 1.0, torque)
    window = ((-math.pi, math.pi), (-3.0, 3.0))
    b = exact_boundaries(p, window)
    exact = dict(zip(b.areas.k.tolist(), b.areas.fraction))
    study = compute_point(alpha, 1.0, torque, StudySettings(window=window))
    np.testing.assert_allclose([exact[k] for k in study.k], study.fraction, atol=1e-12)
    running = torque != 0.0
    if running:
        exact[RUNNING_SIDE] = b.areas.running
        assert 0.05 < b.areas.running < 0.95  # the running basin is a real share
    _, barrier = running_certificate(p, 0.01)
    # the boundaries' length inside the window, from the exact basin polygons
    basins = window_basins(basin_shape(b), window, b.areas.k, running)
    import shapely

    box = shapely.box(window[0][0], window[1][0], window[0][1], window[1][1])
    length = sum(g.boundary.difference(box.boundary).length for k, g in basins.items()
                 if k in exact) / 2.0
    area = (window[0][1] - window[0][0]) * (window[1][1] - window[1][0])
    errors, bounds = [], []
    for n in (32, 64, 128, 256):
        # cell centres of an n × n lattice over the window
        h_t, h_v = (window[0][1] - window[0][0]) / n, (window[1][1] - window[1][0]) / n
        theta = window[0][0] + h_t * (np.arange(n) + 0.5)
        speed = window[1][0] + h_v * (np.arange(n) + 0.5)
        res = atlas.label(theta[None, :], speed[:, None], alpha=p.alpha, omega0=p.omega0,
                          torque=torque, t_max=200.0, running=barrier)
        ran = res.status == RUNNING
        assert np.all((res.status == 0) | ran)
        count = {k: float(np.mean(np.where(ran, RUNNING_SIDE, res.attractor) == k))
                 for k in exact}
        errors.append(max(abs(count[k] - exact[k]) for k in exact))
        bounds.append((length * (h_t + h_v) + 4 * h_t * h_v) / area)
    assert all(e <= b for e, b in zip(errors, bounds)), (errors, bounds)
    # at least first order: within C·h at every step, and well below the 32² error at 256²
    assert errors[-1] < errors[0] / 4, errors
