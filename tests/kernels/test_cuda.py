"""The CUDA backend against the CPU kernel, without a GPU (numba's CUDA simulator).

Every check runs in a subprocess: NUMBA_ENABLE_CUDASIM must be set before numba.cuda is first
imported, and the no-GPU error path needs a process where it is not set. On a machine with a
CUDA GPU the same comparison also runs on the device ("gpu" case).

Tolerance: labels, status and n_trap must be *identical* to the CPU kernel's
(``label_straightforward``, same check_every). Both sides compute in IEEE double with the same
operation order, but not bit for bit: the simulator runs the kernels as Python float
arithmetic (no FMA), a GPU contracts FMAs and uses libdevice's or the polynomial sin (max
error 1e-15), the CPU kernel libm's sin with LLVM's contractions. Those last-bit differences
can only change the outcome of an orbit within rounding of a separatrix or whose energy is
within ~1e-13 of the trap level at a test, and this grid has none; so any difference is a bug.
Fixed-steps states are compared to 1e-9 rad (rounding only, over 200 steps).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

COMPARE = r"""
import json, sys
import numpy as np
from atlas.kernels.cuda import cuda_status
ok, why = cuda_status()
if not ok:
    print(json.dumps({"skip": why})); sys.exit()
from atlas.kernels import NONFINITE, TRAPPED, UNRESOLVED
from atlas.kernels.cuda import VARIANTS
from atlas.kernels.cuda_host import label_cuda, propagate_cuda
from atlas.kernels.rk4 import label_straightforward, propagate_straightforward
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for

alpha, omega0, dt, t_max = 0.1, 1.0, 0.01, 20.0
th, v = np.meshgrid(np.linspace(-3 * np.pi, 3 * np.pi, 12), np.linspace(-4.0, 4.0, 12))
picked = [(np.nan, 0.0), (0.0, np.inf), (-np.inf, np.nan), (0.0, 0.0), (6 * np.pi, 0.0),
          (np.pi - 1e-12, 0.0), (-np.pi + 1e-12, 0.0), (40.0, 9.0)]
theta0 = np.concatenate([th.ravel(), [p[0] for p in picked]])
theta_dot0 = np.concatenate([v.ravel(), [p[1] for p in picked]])
n = theta0.size
args = (alpha, omega0, dt, n_checks_for(t_max, dt, CHECK_EVERY), CHECK_EVERY,
        energy_cap(dt, alpha, omega0))

def run(kernel, **kw):
    out = (np.full(n, 12345, np.int32), np.full(n, 9, np.int8), np.full(n, 7, np.int32))
    kernel(theta0, theta_dot0, *args, *out, **kw)
    return out

ref = run(label_straightforward)
failures = []
for variant, chunk in [(v, None) for v in VARIANTS] + [("fast", 37)]:
    got = run(label_cuda, variant=variant, chunk=chunk)
    for name, a, b in zip(("attractor", "status", "n_trap"), got, ref):
        bad = np.flatnonzero(a != b)
        if bad.size:
            failures.append(f"{variant}/chunk={chunk}: {name} differs at {bad[:5].tolist()}: "
                            f"{a[bad[:5]].tolist()} vs CPU {b[bad[:5]].tolist()}")
steps = 200
ref_th, ref_v = theta0[:144].copy(), theta_dot0[:144].copy()
propagate_straightforward(ref_th, ref_v, alpha, omega0, dt, steps)
prop_err = {}
for variant in VARIANTS:
    g_th, g_v = theta0[:144].copy(), theta_dot0[:144].copy()
    propagate_cuda(g_th, g_v, alpha, omega0, dt, steps, variant=variant, chunk=50)
    prop_err[variant] = float(max(np.abs(g_th - ref_th).max(), np.abs(g_v - ref_v).max()))
status = ref[1]
print(json.dumps({
    "device": why, "failures": failures, "prop_err": prop_err,
    "picked_status": status[144:].tolist(), "picked_k": ref[0][144:].tolist(),
    "counts": [int(np.sum(status == s)) for s in (TRAPPED, UNRESOLVED, NONFINITE)],
}))
"""


def _child(code: str, simulator: bool) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    if simulator:
        env["NUMBA_ENABLE_CUDASIM"] = "1"
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["simulator", "gpu"])
def test_cuda_kernels_match_cpu_kernel(mode):
    out = _child(COMPARE, simulator=mode == "simulator")
    if "skip" in out:
        pytest.skip(f"CUDA {mode} unavailable: {out['skip']}")
    if mode == "simulator":
        assert out["device"] == "CUDA simulator"
    assert out["failures"] == []
    # the hand-picked orbits cover every status: NaN/inf → nonfinite, the rest of the well
    # and the bottom of well 3 → trapped at once, 1e-12 from a saddle → unresolved at t_max
    assert out["picked_status"][:6] == [2, 2, 2, 0, 0, 1]
    assert out["picked_k"][3:5] == [0, 3]
    assert out["counts"][0] > 100 and out["counts"][1] >= 2
    assert max(out["prop_err"].values()) < 1e-9


@pytest.mark.slow
def test_cpu_path_never_imports_numba_cuda():
    code = ("import json, sys, atlas\n"
            "atlas.label([0.5, 3.0], [0.0, 1.0], alpha=0.1, omega0=1.0, t_max=5.0)\n"
            "print(json.dumps({'imported': 'numba.cuda' in sys.modules}))")
    assert _child(code, simulator=False) == {"imported": False}


@pytest.mark.slow
def test_cuda_unavailable_is_one_clear_line():
    code = r"""
import json
import atlas
from atlas.errors import BackendUnavailable
from atlas.kernels.cuda import cuda_status
ok, why = cuda_status()
try:
    atlas.label([0.5], [0.0], alpha=0.1, omega0=1.0, backend="cuda")
    message = None
except BackendUnavailable as exc:
    message = str(exc)
print(json.dumps({"ok": ok, "why": why, "message": message}))
"""
    out = _child(code, simulator=False)
    if out["ok"]:
        pytest.skip(f"a CUDA GPU is present: {out['why']}")
    message = out["message"]
    assert message is not None and "\n" not in message
    assert message.startswith("backend 'cuda': ") and "pendulum-atlas[cuda]" in message
    assert out["why"] and out["why"] in message


@pytest.mark.slow
def test_gpu_bench_under_simulator():
    code = r"""
import json
from atlas.commands.bench_gpu import format_gpu_rows, run_gpu_bench, sweep_rows
r = run_gpu_bench(n=4, repeats=1, t_max=1.0, bulk_steps=4, allow_simulator=True)
r["sweeps"] = sweep_rows([6], t_max=1.0)
print(json.dumps({"default": run_gpu_bench() is None, "variants": sorted(r["variants"]),
                  "agree": r["labels_agree_fraction"], "cpu": r["cpu_labels"],
                  "sweeps": [s["n"] for s in r["sweeps"]], "table": format_gpu_rows(r),
                  "driven": r["driven"],
                  "skip": format_gpu_rows(None)}))
"""
    out = _child(code, simulator=True)
    assert out["default"]  # simulator timings are meaningless: no result by default
    assert out["variants"] == ["fast", "straightforward"] and out["agree"] == 1.0
    assert out["cpu"]["agree_fraction"] == 1.0 and out["cpu"]["differ"] == 0
    assert out["sweeps"] == [6] and "6x6 default atlas" in out["table"]
    assert "against CPU labels" in out["table"] and "none differs" in out["table"]
    assert "fast" in out["table"] and out["skip"].startswith("GPU benchmark skipped")
    driven = out["driven"]  # the simulator runs the device code in Python: the same labels
    assert driven["orbits"] == 16 and driven["cpu_sample"] == 16
    assert driven["agree_fraction"] == 1.0 and driven["gpu_gsteps_s"] > 0
    assert "driven: the three-basin map (A = 1.66) 4x4 labelled on the GPU" in out["table"]


@pytest.mark.slow
def test_numpy_is_left_as_it_was():
    """The numpy.row_stack alias that numba-cuda's compiler needs exists only while kernels
    compile: with numpy lacking it (numpy ≥ 2.5; removed here to act like one), compiling
    works and numpy lacks it again afterwards; with numpy having it, it stays numpy's."""
    code = r"""
import json
import numpy as np
had = hasattr(np, "row_stack")
original = getattr(np, "row_stack", None)
if had:
    del np.row_stack
from atlas.kernels.cuda import cuda_status, kernels
ok, why = cuda_status()
kernels.cache_clear()
k = kernels("fast")
after_missing = hasattr(np, "row_stack")
np.row_stack = original or np.vstack
kernels.cache_clear()
kernels("straightforward")
print(json.dumps({"ok": ok, "compiled": k.label is not None, "after_missing": after_missing,
                  "kept": np.row_stack is (original or np.vstack)}))
"""
    out = _child(code, simulator=True)
    assert out == {"ok": True, "compiled": True, "after_missing": False, "kept": True}
