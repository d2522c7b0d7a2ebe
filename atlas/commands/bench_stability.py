"""``atlas bench``, the stability rows: the study of ``configs/swing_stability.yaml`` (held
here as :data:`STUDY`, so that an installed atlas benches it without the repository; bSTAB's
window, α = 0.05, ω0 = 1, τ from 0 to 1) end to end — config, every point, the
bifurcations, the file — and the per-point cost of each phase of a point
(:data:`atlas.stability.study.PHASES`), for the study in bSTAB's setting (Stender & Hoffmann,
Nonlinear Dynamics 107, 1451, 2022); a 2-D study of 100 × 100 (α, τ) points on the same
window (:data:`STUDY_2D`); and, for scale, one 512² grid run of one of the 1-D study's
points (τ = 0.5), which a study of 1,001 points should beat. ``quick``: 101 torques, 20 × 20
points and a 128² grid. Every kernel is compiled and cached first (:func:`_warm_up`).
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


#: The 2-D study: α from 0.02 to 0.5 and τ from 0 to 1 (the saddle-node, flagged, at 1).
STUDY_2D = {**STUDY, "name": "swing_stability_2d",
            "pendulum": {"alpha": {"start": 0.02, "stop": 0.5, "num": 100}, "omega0": 1.0,
                         "torque": {"start": 0.0, "stop": 1.0, "num": 100}}}
#: The grid run the 1-D study is compared with: one of its points, τ = 0.5, on a 512² grid.
GRID_POINT = {**STUDY, "name": "swing_point",
              "pendulum": {"alpha": 0.05, "omega0": 1.0, "torque": 0.5},
              "grid": {"theta0": {"start": "-5pi/6", "stop": "7pi/6", "num": 512},
                       "theta_dot0": {"start": -10.0, "stop": 10.0, "num": 512}}}


def _study(folder: Path, name: str, text: dict) -> tuple[float, list]:
    """(wall time [s], the points' results) of the study ``text`` end to end."""
    import yaml

    from atlas.commands.stability import run_study

    results = []
    config = folder / f"{name}.yaml"
    config.write_text(yaml.safe_dump(text))
    start = time.perf_counter()
    run_study(config, output=folder / f"{name}.h5", on_result=lambda _, r: results.append(r))
    return time.perf_counter() - start, results


def _grid_run(folder: Path, text: dict) -> float:
    """Wall time [s] of ``atlas run`` of ``text`` end to end, in this process."""
    import yaml

    from atlas.pipeline.config import load_config
    from atlas.pipeline.sweep import run

    config = folder / "grid.yaml"
    config.write_text(yaml.safe_dump({**text, "output": str(folder / "grid.h5")}))
    start = time.perf_counter()
    run(load_config(config), quiet=True, force=True, open_result=False,
        confirm=lambda _: True)
    return time.perf_counter() - start


def _warm_up(folder: Path) -> None:
    """Fill Numba's disk cache with every kernel the timed runs take, in a fresh interpreter
    (a small 1-D and 2-D study, and a grid run big enough for the threaded labelling
    kernels): the timed runs then load their kernels as a user's second run does, instead of
    timing their compilation (seconds per kernel in a fresh checkout)."""
    import yaml

    from atlas.commands.bench_e2e import run_python

    small = {"1d": {**STUDY, "pendulum": {**STUDY["pendulum"],
                                          "torque": {"start": 0.0, "stop": 1.0, "num": 5}}},
             "2d": {**STUDY_2D, "pendulum": {
                 "alpha": {"start": 0.02, "stop": 0.5, "num": 3}, "omega0": 1.0,
                 "torque": {"start": 0.0, "stop": 1.0, "num": 3}}},
             "grid": {**GRID_POINT, "grid": {key: {**GRID_POINT["grid"][key], "num": 64}
                                             for key in ("theta0", "theta_dot0")}}}
    for name, text in small.items():
        config = folder / f"warm_{name}.yaml"
        output = folder / f"warm_{name}.h5"
        config.write_text(yaml.safe_dump({**text, "output": str(output)}))
        command = "run" if name == "grid" else "stability"
        run_python(["-m", "atlas", command, str(config), "-o", str(output), "--force"])


def stability_rows(quick: bool) -> list[dict]:
    """One row of the whole 1-D study ("phase": "end to end", wall time [s], points,
    seconds per point) and one per phase (mean and largest cost per point [s]); one of the
    2-D study end to end; one of the 512² grid run of one point, with the 1-D study's time
    against it."""
    from atlas.stability.study import PHASES

    study, study_2d, grid = (copy.deepcopy(t) for t in (STUDY, STUDY_2D, GRID_POINT))
    if quick:
        study["pendulum"]["torque"]["num"] = 101
        for key in ("alpha", "torque"):
            study_2d["pendulum"][key]["num"] = 20
        for key in ("theta0", "theta_dot0"):
            grid["grid"][key]["num"] = 128
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        _warm_up(folder)
        wall, results = _study(folder, "study", study)
        wall_2d, results_2d = _study(folder, "study_2d", study_2d)
        grid_wall = _grid_run(folder, grid)
    side = grid["grid"]["theta0"]["num"]
    rows = [{"phase": "end to end", "points": len(results), "wall_s": wall,
             "s_per_point": wall / max(len(results), 1)}]
    for phase in PHASES:
        times = np.array([r.seconds[phase] for r in results if phase in r.seconds])
        if times.size:
            rows.append({"phase": phase, "points": int(times.size),
                         "mean_s": float(times.mean()), "max_s": float(times.max())})
    rows.append({"phase": "2-D study (alpha x torque) end to end", "points": len(results_2d),
                 "wall_s": wall_2d, "s_per_point": wall_2d / max(len(results_2d), 1)})
    rows.append({"phase": f"one {side}^2 grid run (torque 0.5) end to end", "points": 1,
                 "wall_s": grid_wall, "against": "the 1-D study",
                 "note": f"the 1-D study of {len(results)} points took "
                         f"{wall / grid_wall:.2f}x this grid run"})
    return rows
