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
