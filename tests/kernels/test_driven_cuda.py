"""The driven pendulum's CUDA kernels (atlas.kernels.driven_cuda) against its CPU kernels, without
a GPU (numba's CUDA simulator, in a subprocess as in tests/kernels/test_cuda.py; on a machine
with a CUDA GPU the same comparison also runs on the device, the "gpu" case).

Tolerance. The device runs the CPU's RK4 step, path choice and decision rule compiled from the
same source, with the same polynomial sin, so it is the CPU's arithmetic in the CPU's order:
under the simulator (plain Python floats, no FMA) its states equal *bit for bit* a plain-Python
evaluation of the CPU's step (``reference`` below). The compiled CPU kernel contracts a·b + c
into FMAs (tests.helpers.host_has_fma), so against it the states agree to rounding grown over
two periods (1e-12 relative), and labels and deciding periods are identical: the orbits here
decide within a few periods, far from rounding of a target's radius. Small on purpose (the
simulator runs ~10⁴ steps/s): N = 32 steps per period (every orbit takes the FULL reduction),
and N = 400 for the SHARED one.
"""

from __future__ import annotations

import pytest

from tests.kernels.test_cuda import _child

COMPARE = r"""
import json, sys
import numpy as np
from atlas.kernels.cuda import cuda_status
ok, why = cuda_status()
if not ok:
    print(json.dumps({"skip": why})); sys.exit()
from atlas.kernels import ATTRACTOR_FILL
from atlas.kernels.driven import (drive, orbit_path, advance, forcing_table, label_driven,
                                  make_driven_step, sample, step_size)
from atlas.kernels.driven_cuda import advance_cuda, label_driven_cuda
from atlas.kernels.fastsin import reduce_pi, sin_poly
from atlas.kernels.lanes import SHARED

ALPHA, OMEGA0, TORQUE, AMP, FREQ = 0.1, 1.0, 0.0, 1.66, 1.0  # the Wada case
out = {"device": why}

# ---- labels: N = 32, targets = the returns of three settled orbits (any period dividing 6)
N = 32
table, dt = forcing_table(AMP, FREQ, 0.0, N), step_size(FREQ, N)
params = (ALPHA, OMEGA0, TORQUE, table, dt)
seeds = sample(np.array([0.5, 2.0, -1.0]), np.array([0.0, 1.0, 0.5]), *params, 60, 6)
targets = seeds.reshape(-1, 2).copy()
targets[:, 0] = (targets[:, 0] + np.pi) % (2 * np.pi) - np.pi
target_attractor = np.repeat(np.array([3, 7, 9], np.int16), 6)
theta0 = np.array([0.5, 2.0, -1.0, 0.3, 2.5, -2.0, 1.2, -0.4])
theta_dot0 = np.array([0.0, 1.0, 0.5, -1.5, -0.5, 1.8, 1.1, -0.8])
labels = (targets, target_attractor, 0.1)
cpu = label_driven(theta0, theta_dot0, *params, *labels, 2, 25)
gpu = label_driven_cuda(theta0, theta_dot0, *params, *labels, 2, 25, chunk=3)
out["labels"] = [a.tolist() for a in cpu]
out["labels_equal"] = [bool(np.array_equal(a, b)) and a.dtype == b.dtype for a, b in zip(cpu, gpu)]
# one count per attractor (ids 0 … 9; 3, 7, 9 have targets): the device reads each its own
confirm = np.ones(10, np.int64)
confirm[[3, 7, 9]] = [1, 4, 2]
per = label_driven(theta0, theta_dot0, *params, *labels, confirm, 25)
per_gpu = label_driven_cuda(theta0, theta_dot0, *params, *labels, confirm, 25, chunk=3)
out["per_attractor"] = [a.tolist() for a in per]
out["per_attractor_equal"] = [bool(np.array_equal(a, b)) for a, b in zip(per, per_gpu)]

# ---- non-finite input (status 2 at period 0), max_periods reached (status 1, the fill)
bad0 = np.concatenate([theta0[:3], [np.nan, 0.0]])
bad1 = np.concatenate([theta_dot0[:3], [0.0, np.inf]])
radius = np.linspace(0.05, 0.2, targets.shape[0])  # one per target
short = label_driven_cuda(bad0, bad1, *params, targets, target_attractor, radius, 3, 2)
out["short"] = [a.tolist() for a in short]
out["short_equal"] = [bool(np.array_equal(a, b)) for a, b in zip(
    short, label_driven(bad0, bad1, *params, targets, target_attractor, radius, 3, 2))]
out["fill"] = int(ATTRACTOR_FILL)

# ---- states after two periods: N = 32 (FULL) and N = 400 (SHARED, and a fast orbit: FULL)
def py_sin_near(reduced, delta):  # fastsin.sin_near, fast_sin without Numba
    r, sign = reduced
    return sign * sin_poly.py_func(r + delta)

def py_sin_sum(theta, delta):
    return py_sin_near(reduce_pi.py_func(theta + delta), 0.0)

py_steps = (make_driven_step(py_sin_near, reduce_pi.py_func).py_func,
            make_driven_step(py_sin_sum, lambda theta: theta).py_func)

def reference(th, v, table, dt, periods):  # the CPU's method as plain Python floats
    forcing, accel = drive(OMEGA0, TORQUE, table, dt)
    shared = orbit_path.py_func(th, v, ALPHA, OMEGA0, dt, accel) == SHARED
    step = py_steps[0 if shared else 1]
    for _ in range(periods):
        for j in range(0, forcing.size - 1, 2):
            th, v = step(th, v, ALPHA, OMEGA0, dt, forcing[j], forcing[j + 1], forcing[j + 2])
    return th, v, shared

out["states"] = {}
for n, extra in ((32, []), (400, [(0.2, 20.0)])):
    table, dt = forcing_table(AMP, FREQ, 0.0, n), step_size(FREQ, n)
    th = np.concatenate([theta0[:4], [p[0] for p in extra]])
    v = np.concatenate([theta_dot0[:4], [p[1] for p in extra]])
    c_th, c_v, g_th, g_v = th.copy(), v.copy(), th.copy(), v.copy()
    advance(c_th, c_v, ALPHA, OMEGA0, TORQUE, table, dt, 2)
    advance_cuda(g_th, g_v, ALPHA, OMEGA0, TORQUE, table, dt, 2, chunk=2)
    ref = [reference(a, b, table, dt, 2) for a, b in zip(th, v)]
    scale = np.maximum(1.0, np.abs(np.concatenate([c_th, c_v])))
    out["states"][n] = {
        "rel_cpu": float(np.max(np.abs(np.concatenate([g_th - c_th, g_v - c_v])) / scale)),
        "python_equal": bool(np.array_equal(g_th, [r[0] for r in ref])
                             and np.array_equal(g_v, [r[1] for r in ref])),
        "shared": [r[2] for r in ref],
    }
print(json.dumps(out))
"""


@pytest.fixture(scope="module", params=["simulator", "gpu"])
def compared(request):
    out = _child(COMPARE, simulator=request.param == "simulator")
    if "skip" in out:
        pytest.skip(f"CUDA {request.param} unavailable: {out['skip']}")
    if request.param == "simulator":
        assert out["device"] == "CUDA simulator"
    return request.param, out


@pytest.mark.slow
def test_labels_and_deciding_periods_equal_the_cpu_kernel(compared):
    _, out = compared
    assert out["labels_equal"] == [True, True, True]
    attractor, periods, status = out["labels"]
    # every orbit decides, within 14 periods, and the three seeds' attractors are reached
    assert status == [0] * 8 and max(periods) < 25
    assert attractor[:3] == [3, 7, 9] and set(attractor) == {3, 7, 9}
    # per attractor: the same on the device; an orbit of #7 (4 in a row) decides 2 returns
    # later than with 2 for all, one of #3 (1) a return sooner
    assert out["per_attractor_equal"] == [True, True, True]
    per_attractor, per_periods, _ = out["per_attractor"]
    assert per_attractor == attractor
    shift = {3: -1, 7: 2, 9: 0}
    assert [p - q for p, q in zip(per_periods, periods)] == [shift[a] for a in attractor]


@pytest.mark.slow
def test_nonfinite_input_and_max_periods(compared):
    _, out = compared
    attractor, periods, status = out["short"]
    assert out["short_equal"] == [True, True, True]
    assert status == [1, 1, 1, 2, 2] and periods == [2, 2, 2, 0, 0]
    assert attractor == [out["fill"]] * 5


@pytest.mark.slow
def test_states_after_two_periods_agree_with_the_cpu_kernel(compared):
    mode, out = compared
    full, shared = out["states"]["32"], out["states"]["400"]
    assert full["shared"] == [False] * 4 and shared["shared"] == [True] * 4 + [False]
    for case in (full, shared):
        assert case["rel_cpu"] < 1e-12
        if mode == "simulator":  # no FMA: the CPU's arithmetic exactly
            assert case["python_equal"]
