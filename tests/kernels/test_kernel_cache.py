"""Numba's cache follows every kernel source: an edit to code the lane kernel inlines from
another file (fastsin.py) takes effect in the next process, not stale machine code."""

import os
import shutil
import subprocess
import sys

import pytest

PROBE = """
import numpy as np
from atlas.kernels import cache_dir
from atlas.kernels.lanes import propagate_lanes
theta, theta_dot = np.array([1.0, 2.0]), np.array([0.5, -1.0])
propagate_lanes(theta, theta_dot, 0.1, 1.0, 0.01, 100)
print(repr(theta[0]), cache_dir())
"""


def _probe(root, env):
    proc = subprocess.run([sys.executable, "-c", PROBE], cwd=root, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    value, folder = proc.stdout.split()
    return value, folder


@pytest.mark.slow
def test_an_edit_to_an_inlined_kernel_file_recompiles(tmp_path):
    from tests.helpers import REPO

    root = tmp_path / "copy"
    shutil.copytree(REPO / "atlas", root / "atlas",
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PYTHONPATH": str(root), "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    before, folder = _probe(root, env)
    assert folder.startswith(str(tmp_path / "cache" / "atlas"))
    assert any((tmp_path / "cache").rglob("*.nbi"))  # the kernel was cached there
    again, _ = _probe(root, env)
    assert again == before
    fastsin = root / "atlas" / "kernels" / "fastsin.py"
    text = fastsin.read_text()
    assert "_S1 = -0.16666666666666666" in text
    fastsin.write_text(text.replace("_S1 = -0.16666666666666666", "_S1 = -0.26666666666666666"))
    after, new_folder = _probe(root, env)
    assert new_folder != folder
    assert after != before  # a stale cache would give the old value
