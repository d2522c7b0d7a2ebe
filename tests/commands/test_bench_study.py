"""The bench's stability rows time the study that ships (configs/swing_stability.yaml), held
in the package so that an installed atlas benches it without the repository."""

from __future__ import annotations

from pathlib import Path

import yaml

from atlas.commands.bench_stability import STUDY
from atlas.pipeline.config import load_config

REPO = Path(__file__).resolve().parents[2]


def test_the_benched_study_is_the_shipped_one(tmp_path):
    held = tmp_path / "held.yaml"
    held.write_text(yaml.safe_dump(STUDY))
    a = load_config(held, study=True)
    b = load_config(REPO / "configs" / "swing_stability.yaml", study=True)
    for section in ("pendulum", "grid", "integrator", "separatrices"):
        assert getattr(a, section) == getattr(b, section), section


def test_the_2d_study_and_the_grid_point_are_valid_configs(tmp_path):
    """The 2-D study is 100 × 100 (α, τ) points on the 1-D study's window; the grid run is
    one of the 1-D study's points on a 512² grid."""
    from atlas.commands.bench_stability import GRID_POINT, STUDY_2D

    (tmp_path / "2d.yaml").write_text(yaml.safe_dump(STUDY_2D))
    (tmp_path / "grid.yaml").write_text(yaml.safe_dump(GRID_POINT))
    two = load_config(tmp_path / "2d.yaml", study=True)
    grid = load_config(tmp_path / "grid.yaml")
    one = load_config(REPO / "configs" / "swing_stability.yaml", study=True)
    assert two.grid == one.grid
    assert STUDY_2D["pendulum"]["alpha"]["num"] * STUDY_2D["pendulum"]["torque"]["num"] \
        == 10_000
    assert grid.grid.theta0.num == grid.grid.theta_dot0.num == 512
    assert (grid.grid.theta0.start, grid.grid.theta0.stop) == (one.grid.theta0.start,
                                                               one.grid.theta0.stop)
    assert grid.pendulum.torque == 0.5
