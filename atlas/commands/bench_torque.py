"""``atlas bench``, the torque-sweep rows: a swing-equation sweep over the torque, end to end,
against the untilted sweep of the same size, and the per-point cost of each phase.

The torque sweep is ``configs/swing_torque.yaml``'s problem (α = 0.05 s⁻¹, ω0 = 1 rad s⁻¹,
19 torques 0.06 … 0.96 rad s⁻², θ0 ∈ [−5π/6, 7π/6], θ̇0 ∈ [−10, 10], t_max = 400 s, dt = 0.01
s, separatrices on); the untilted sweep has the same window, grid, t_max and number of
points, with τ = 0 and 19 values of ω0 from 0.9 to 1.1 rad s⁻¹. Each is one ``atlas run -v``
in a fresh interpreter (:func:`atlas.commands.bench_e2e.run_python`), after a small warm-up
run of each (Numba's caches filled), the two run one after the other in the same bench run,
so that their ratio compares like with like on a loaded machine. The phases are the lines
``atlas run -v`` logs; a phase's per-point cost is its time over the 19 points. Quick: a 64²
grid and 7 points each.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np

from atlas.commands.bench_e2e import run_python

__all__ = ["torque_rows", "TITLE", "sweep_config"]

TITLE = "torque sweep (swing_torque) against the untilted sweep of the same size"

_PHASE = re.compile(r"^atlas: (.+?)\s+([0-9.]+) s$")
_TORQUES = np.round(np.linspace(0.06, 0.96, 19), 2)
_OMEGAS = np.round(np.linspace(0.9, 1.1, 19), 4)


def sweep_config(name: str, output: Path, *, torque: bool, points: int, num: int) -> str:
    """The YAML of the torque sweep (``torque``) or the untilted one: ``points`` parameter
    points (the first ``points`` of every ``19 // points``-th), a ``num``² grid."""
    pick = np.linspace(0, 18, points).round().astype(int)
    varied = (f"  omega0: 1.0\n  torque: {[float(t) for t in _TORQUES[pick]]}\n" if torque
              else f"  omega0: {[float(w) for w in _OMEGAS[pick]]}\n  torque: 0.0\n")
    return (f"name: {name}\npendulum:\n  alpha: 0.05\n{varied}"
            f"grid:\n  theta0: {{start: -5pi/6, stop: 7pi/6, num: {num}}}\n"
            f"  theta_dot0: {{start: -10.0, stop: 10.0, num: {num}}}\n"
            "integrator: {dt: 0.01, t_max: 400.0}\nseparatrices: {enabled: true}\n"
            f"output: {output}\n")


def _run(folder: Path, name: str, **kw) -> tuple[float, dict]:
    """(wall s, {phase: s}) of one ``atlas run -v`` of a sweep config."""
    config = folder / f"{name}.yaml"
    config.write_text(sweep_config(name, folder / f"{name}.h5", **kw))
    wall, out = run_python(["-m", "atlas", "run", str(config), "-v"])
    phases = {m.group(1).strip(): float(m.group(2))
              for m in map(_PHASE.match, out.stderr.splitlines())
              if m and not m.group(1).startswith("wrote")}
    return wall, phases


def torque_rows(quick: bool) -> list[dict]:
    """The rows (``atlas.commands.bench``'s row shape): the torque sweep end to end against
    the untilted one, then each phase's per-point cost against the untilted sweep's."""
    points, num = (7, 64) if quick else (19, 256)
    with tempfile.TemporaryDirectory(prefix="atlas-bench-torque-") as tmp:
        folder = Path(tmp)
        for torque in (False, True):  # warm-up: every kernel compiled and cached
            _run(folder, f"warm{int(torque)}", torque=torque, points=2, num=64)
        flat_wall, flat = _run(folder, "untilted", torque=False, points=points, num=num)
        tilt_wall, tilt = _run(folder, "torque", torque=True, points=points, num=num)
    rows = [{"variant": f"torque sweep, {points} points, {num}² grid, end to end",
             "wall_s": tilt_wall, "ratio": tilt_wall / flat_wall,
             "against": f"untilted sweep ({points} values of omega0), {flat_wall:.1f} s",
             "note": "goal: ratio <= 1.5, <= 15 s for 19 points at 256^2 on 2 cores"}]
    for phase in tilt:
        per_point, reference = tilt[phase] / points, flat.get(phase, float("nan")) / points
        rows.append({"variant": f"  {phase}, per point", "wall_s": per_point,
                     "ratio": per_point / reference if reference else float("nan"),
                     "against": f"untilted, {reference:.3g} s per point",
                     "note": "goal: < 0.1 s per point for what does not depend on the grid"})
    return rows
