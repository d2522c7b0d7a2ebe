"""Independent parameter points run two at a time on threads only where Numba's threading
layer allows concurrent parallel calls: under ``workqueue`` (no OpenMP, no TBB) a parameter
sweep runs them one at a time instead of aborting, with the same arrays."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from tests.helpers import write_config


def _in_a_process(code: str, layer: str) -> str:
    env = {**os.environ, "NUMBA_THREADING_LAYER": layer}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip()


def test_workqueue_gets_one_point_at_a_time():
    code = ("from atlas.kernels.threads import concurrent_points as c; "
            "print(c(5), c(1), c(5, most=1))")
    assert _in_a_process(code, "workqueue") == "1 1 1"
    assert _in_a_process(code, "default") in ("2 1 1", "1 1 1")  # 1 only without OpenMP, TBB


@pytest.mark.slow  # two atlas runs in fresh processes
def test_a_sweep_under_workqueue_runs_and_equals_the_default(tmp_path):
    import atlas

    paths = {}
    for layer in ("workqueue", "default"):
        out = tmp_path / f"{layer}.h5"
        cfg = write_config(tmp_path / f"{layer}.yaml", f"""\
pendulum: {{alpha: [0.2, 0.5, 1.0], omega0: 1.0}}
grid:
  theta0: {{start: -1.5pi, stop: 1.5pi, num: 16}}
  theta_dot0: {{start: -3, stop: 3, num: 12}}
output: {out}
""")
        _in_a_process(f"from atlas.cli import main; raise SystemExit(main(['run', "
                      f"{str(cfg)!r}, '--quiet']))", layer)
        paths[layer] = out
    a, b = (atlas.open(paths[layer]) for layer in ("workqueue", "default"))
    for name in ("attractor", "status", "boundary_distance", "basin_fraction_exact", "d_cert"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    np.testing.assert_array_equal(a["separatrices/alpha1"]["theta"].values,
                                  b["separatrices/alpha1"]["theta"].values)
