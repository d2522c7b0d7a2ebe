"""512-bit vectors (:mod:`atlas.kernels.vector_width`) change no bit of a kernel's result, and
a user's own choice of Numba's CPU features is left alone. Each case runs in a fresh
interpreter: the width is fixed when Numba makes its CPU target, once per process."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

#: The bulk RK4 lanes, the scalar straightforward RK4 (fast-math with reassociation, libm
#: sin) and the driven pendulum's map and labels on orbits that take both the shared and
#: the full reduction path; prints the width's features and a digest of the bits.
SCRIPT = """
import hashlib, json, math
import numpy as np
from atlas.kernels import driven, lanes, rk4
import numba
rng = np.random.default_rng(1)
theta, theta_dot = rng.uniform(-math.pi, math.pi, 4099), rng.uniform(-30.0, 30.0, 4099)
bulk = theta.copy(), theta_dot.copy()
lanes.propagate_lanes(*bulk, 0.1, 1.0, 0.05, 97)
scalar = theta.copy(), theta_dot.copy()
rk4.propagate_straightforward(*scalar, 0.1, 1.0, 0.05, 97)
table = driven.forcing_table(1.66, 1.0, 0.3, 200)
mapped = theta.copy(), theta_dot.copy()
driven.advance(*mapped, 0.1, 1.0, 0.2, table, 2 * math.pi / 200, 3)
labels = driven.label_driven(theta, theta_dot, 0.1, 1.0, 0.0, table, 2 * math.pi / 200,
                             np.array([[-2.408, 0.677]]), np.array([0], np.int16), 0.1, 1, 20)
digest = hashlib.sha256()
for a in (*bulk, *scalar, *mapped, *labels):
    digest.update(np.ascontiguousarray(a).tobytes())
print(json.dumps({"features": numba.config.CPU_FEATURES or "", "digest": digest.hexdigest()}))
"""


def _run(**env) -> dict:
    clean = {k: v for k, v in os.environ.items()
             if k not in ("NUMBA_CPU_FEATURES", "NUMBA_CPU_NAME", "ATLAS_VECTOR_BITS")}
    done = subprocess.run([sys.executable, "-c", SCRIPT], env={**clean, **env},
                          capture_output=True, text=True, check=True, timeout=600)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _avx512() -> bool:
    import llvmlite.binding as ll

    return "+avx512f" in ll.get_host_cpu_features().flatten().split(",")


@pytest.mark.skipif(not _avx512(), reason="needs a CPU with AVX-512 (elsewhere nothing changes)")
def test_wide_vectors_give_the_same_bits_as_llvms_choice():
    wide, narrow = _run(), _run(ATLAS_VECTOR_BITS="256")
    assert wide["features"].endswith(",-prefer-256-bit")
    assert narrow["features"] == ""  # Numba's own choice of features
    assert wide["digest"] == narrow["digest"]


def test_a_users_own_cpu_features_are_left_alone():
    import llvmlite.binding as ll

    own = ll.get_host_cpu_features().flatten()
    assert _run(NUMBA_CPU_FEATURES=own)["features"] == own


def test_nothing_changes_once_numbas_target_exists(monkeypatch):
    """In a process whose Numba target is made (this one: the kernels are compiled), the
    width can no longer change, and the call says so by changing nothing; it never writes
    the environment (which child processes, and jobs on other machines, inherit)."""
    from numba.core import config
    from numba.core.registry import cpu_target

    from atlas.kernels.vector_width import prefer_wide_vectors

    assert cpu_target.target_context is not None  # made, if it was not already
    for name in ("NUMBA_CPU_FEATURES", "NUMBA_CPU_NAME", "ATLAS_VECTOR_BITS"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(config, "CPU_FEATURES", None)
    assert prefer_wide_vectors() is None
    assert config.CPU_FEATURES is None and "NUMBA_CPU_FEATURES" not in os.environ


def test_import_atlas_alone_imports_no_numba():
    """The width is set where kernels are compiled: ``import atlas`` (every command, ``atlas
    info`` too) neither imports Numba nor sets anything."""
    code = ("import sys, os, atlas; print(sorted(m for m in ('numba', "
            "'atlas.kernels.vector_width') if m in sys.modules), "
            "'NUMBA_CPU_FEATURES' in os.environ)")
    clean = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_FEATURES"}
    done = subprocess.run([sys.executable, "-c", code], env=clean, capture_output=True,
                          text=True, check=True, timeout=120)
    assert done.stdout.split() == ["[]", "False"]
