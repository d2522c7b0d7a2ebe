"""``atlas bench``, the stability rows: the study of ``configs/swing_stability.yaml`` (held
here as :data:`STUDY`, so that an installed atlas benches it without the repository; bSTAB's
window, α = 0.05, ω0 = 1, τ from 0 to 1) end to end — config, every point, the
bifurcations, the file — and the per-point cost of each phase of a point
(:data:`atlas.stability.study.PHASES`), for the study in bSTAB's setting (Stender & Hoffmann,
Nonlinear Dynamics 107, 1451, 2022). ``quick``: 101 torques over the same range.
"""

from __future__ import annotations

import copy
import tempfile
import time
from pathlib import Path

import numpy as np

__all__ = ["stability_rows", "STUDY"]

#: The study the rows time, that of configs/swing_stability.yaml (its torque range is
#: thinned for ``quick``).
STUDY = {"name": "swing_stability",
         "pendulum": {"alpha": 0.05, "omega0": 1.0,
                      "torque": {"start": 0.0, "stop": 1.0, "num": 1001}},
         "grid": {"theta0": {"start": "-5pi/6", "stop": "7pi/6", "num": 2},
                  "theta_dot0": {"start": -10.0, "stop": 10.0, "num": 2}}}


def stability_rows(quick: bool) -> list[dict]:
    """One row of the whole study ("phase": "end to end", wall time [s], points, seconds
    per point) and one per phase (mean and largest cost per point [s])."""
    import yaml

    from atlas.commands.stability import run_study
    from atlas.stability.study import PHASES

    text = copy.deepcopy(STUDY)
    if quick:
        text["pendulum"]["torque"]["num"] = 101
    results = []
    with tempfile.TemporaryDirectory() as folder:
        config = Path(folder) / "study.yaml"
        config.write_text(yaml.safe_dump(text))
        start = time.perf_counter()
        _, _, _ = run_study(config, output=Path(folder) / "study.h5",
                            on_result=lambda _, r: results.append(r))
        wall = time.perf_counter() - start
    rows = [{"phase": "end to end", "points": len(results), "wall_s": wall,
             "s_per_point": wall / max(len(results), 1)}]
    for phase in PHASES:
        times = np.array([r.seconds[phase] for r in results if phase in r.seconds])
        if times.size:
            rows.append({"phase": phase, "points": int(times.size),
                         "mean_s": float(times.mean()), "max_s": float(times.max())})
    return rows
