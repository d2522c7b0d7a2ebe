"""``separatrices.max_spacing`` honoured: the traced boundaries of an atlas run, read back from
its file, have consecutive vertices at most ``max_spacing`` apart (with torque, where the
vertices are picked along the exact boundaries' polylines, at most max_spacing + MAX_SEGMENT,
the bound :func:`atlas.boundaries.trace_tilted.trace_tilted` documents), and the spacing
follows the setting: under the default 0.05 at a finer setting, above it at a coarser one (a
run that ignored the key, or read the default instead, fails one or the other)."""

from __future__ import annotations

import numpy as np
import pytest

import atlas
from atlas import defaults
from atlas.boundaries.branches import MAX_SEGMENT
from atlas.store.separatrices import branches


def _spacings(tmp_path, torque: float, max_spacing: float) -> np.ndarray:
    """The distances [rad-ish] between consecutive vertices of every traced polyline of a
    small atlas at α = 0.1, ω0 = 1 on [−π, π] × [−3, 3]."""
    cfg = atlas.Config.model_validate({
        "name": "spacing", "pendulum": {"alpha": 0.1, "omega0": 1.0, "torque": torque},
        "grid": {"theta0": {"start": "-pi", "stop": "pi", "num": 8},
                 "theta_dot0": {"start": -3, "stop": 3, "num": 6}},
        "integrator": {"t_max": 200.0}, "separatrices": {"max_spacing": max_spacing},
        "output": str(tmp_path / f"s-{torque}-{max_spacing}.h5")})
    tree = atlas.run(cfg, quiet=True)
    sep = tree["separatrices"].to_dataset(inherit=False)
    assert float(sep.attrs["max_spacing"]) == max_spacing  # the setting is the one stored
    steps = [np.hypot(np.diff(theta), np.diff(theta_dot))
             for _, _, theta, theta_dot in branches(sep)]
    tree.close()
    assert sum(s.size for s in steps) > 20  # boundaries were traced in the window
    return np.concatenate(steps)


@pytest.mark.parametrize("torque, slack", [(0.0, 0.0), (0.3, MAX_SEGMENT)])
def test_vertices_are_at_most_max_spacing_apart(tmp_path, torque, slack):
    assert defaults.MAX_SPACING == 0.05  # the default both settings are told from
    fine = _spacings(tmp_path, torque, 0.02)
    coarse = _spacings(tmp_path, torque, 0.2)
    assert fine.max() <= 0.02 + slack < defaults.MAX_SPACING
    assert coarse.max() <= 0.2 + slack
    assert coarse.max() > defaults.MAX_SPACING  # the coarser setting is used, not the default
