"""The study file against the points' own numbers (issue 43, 2): every stored value of a 1-D
and of a 2-D (α × τ, with torque) study equals what compute_point gives at the same
(α, ω0, τ), read back by coordinate value, so that a transposed reshape, a swapped pair of
parameters or wells shifted by one k would fail. The parameter values are chosen so that
every point differs from every other (no symmetry hides a transposition)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.commands.stability import run_study
from atlas.stability.study import StudySettings, compute_point
from atlas.store.study import open_study
from tests.helpers import study_config

WINDOW = ((-math.pi, math.pi), (-3.0, 3.0))


def _check_point(ds, point: dict, settings: StudySettings) -> None:
    """Every per-point variable of ``ds`` at ``point`` (selected by value) against
    compute_point there: the wells' basin stability, fatal shocks and their feet (well 0's
    shifted by 2πk), the running basin and the running cycle's shock."""
    here = ds.sel(point)
    r = compute_point(float(here["alpha"]), float(here["omega0"]), float(here["torque"]),
                      settings)
    stored = dict(zip(ds["k"].values.tolist(), here["basin_stability"].values))
    expected = dict(zip(r.k.tolist(), r.fraction))
    for k in ds["k"].values.tolist():  # wells the point's basins do not reach: NaN or 0
        got, want = stored[k], expected.get(k, 0.0)
        assert (np.isnan(got) and want == 0.0) or got == want, (point, k, got, want)
    assert float(here["running_stability"]) == (r.running if r.running == r.running else 0.0)
    for j, k in enumerate(ds["k"].values):
        shock = here["minimal_fatal_shock"].values[j]
        assert shock == r.shock.distance or (np.isnan(shock) and np.isnan(r.shock.distance))
        np.testing.assert_array_equal(here["fatal_shock_theta"].values[j],
                                      r.shock.theta + 2.0 * np.pi * k)
        np.testing.assert_array_equal(here["fatal_shock_theta_dot"].values[j],
                                      r.shock.theta_dot)
    np.testing.assert_array_equal(float(here["running_fatal_shock"]),
                                  r.running_shock.distance)


@pytest.mark.slow
def test_a_1d_study_holds_each_points_own_numbers(tmp_path):
    torques = [0.05, 0.2, 0.45, 0.7]
    cfg = study_config(tmp_path / "s.yaml", f"alpha: 0.1, omega0: 1.0, torque: {torques}",
                       tmp_path / "s.h5")
    _, path, _ = run_study(cfg)
    ds = open_study(path)  # the file, as a reader finds it
    settings = StudySettings(window=WINDOW)
    assert ds["basin_stability"].dims == ("k", "torque")
    for torque in torques:
        _check_point(ds, {"torque": torque}, settings)


@pytest.mark.slow
def test_a_2d_study_with_torque_holds_each_points_own_numbers(tmp_path):
    """α × τ, three by two, τ of both signs: the reshape into (k, alpha, torque) and the
    wells' k (τ < 0 tilts the wells the other way) against each point's own result."""
    alphas, torques = [0.05, 0.15, 0.4], [-0.3, 0.5]
    cfg = study_config(tmp_path / "m.yaml", f"alpha: {alphas}, omega0: 1.0, torque: {torques}",
                       tmp_path / "m.h5")
    _, path, _ = run_study(cfg)
    ds = open_study(path)
    settings = StudySettings(window=WINDOW)
    assert ds["basin_stability"].dims == ("k", "alpha", "torque")
    values = ds["basin_stability"].values
    assert not np.allclose(values[:, 0, :], values[:, 1, :], equal_nan=True)
    for alpha in alphas:
        for torque in torques:
            _check_point(ds, {"alpha": alpha, "torque": torque}, settings)
