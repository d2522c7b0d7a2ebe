"""``atlas bench``'s driven-pendulum kernel row computes the same map as its NumPy reference
(no timing asserted: the row's ratio is whatever this machine gives)."""

from __future__ import annotations

import math
import re

import numpy as np

from atlas.commands import bench_driven
from atlas.kernels import driven


def test_the_numpy_reference_is_the_kernels_map():
    """The reference the kernel is timed against is the same RK4 map: after two periods the
    states agree to rounding (one period of the kernel's table-driven drive against the
    reference's cos at each stage)."""
    theta, theta_dot = np.array([0.3, -2.0, 1.0]), np.array([0.1, 3.0, -1.5])
    ref_theta, ref_dot = theta.copy(), theta_dot.copy()
    bench_driven.numpy_periods(ref_theta, ref_dot, 2)
    table = driven.forcing_table(1.66, 1.0, 0.0, 200)
    driven.advance(theta, theta_dot, 0.1, 1.0, 0.0, table, driven.step_size(1.0, 200), 2)
    np.testing.assert_allclose(theta, ref_theta, rtol=0, atol=1e-11)
    np.testing.assert_allclose(theta_dot, ref_dot, rtol=0, atol=1e-11)


def test_the_kernel_row_says_its_rate_and_the_agreement():
    row = bench_driven._kernel_row(quick=True)
    assert row["wall_s"] > 0 and math.isfinite(row["ratio"]) and row["ratio"] > 0
    agree = float(re.search(r"agree to ([0-9.e+-]+)", row["note"]).group(1))
    assert agree < 1e-9


def test_the_atlas_rows_set_the_run_against_its_kernel():
    """The quick end-to-end row and its share outside the kernel: the kernel alone, labelling
    the file's grid from the file's attractors, gives exactly the stored labels (so it timed
    the same work), and the share is a fraction of the run."""
    run, share = bench_driven._atlas_rows(quick=True)
    assert run["wall_s"] > 0 and share["wall_s"] < run["wall_s"]
    assert 0 < share["ratio"] < 1
    assert "the file's labels at 100.00% of the points" in share["note"], share["note"]
    assert share["against"].startswith("its map phase, ")  # read from the run's -v lines


def test_the_sweep_row_runs_the_study():
    """The quick sweep row: a 3-point amplitude sweep through ``atlas stability`` in a fresh
    interpreter, timed."""
    row, = bench_driven._sweep_rows(quick=True)
    assert row["wall_s"] > 0 and "3 points x 1,000 samples" in row["variant"]


def test_the_width_row_sets_wide_vectors_against_llvms_own_on_the_same_states():
    """The vector-width row runs the kernel in two fresh interpreters, at this machine's
    default width and at LLVM's own (``ATLAS_VECTOR_BITS=256``): a positive ratio, and on a
    CPU with AVX-512 the same states from both (no timing asserted)."""
    import llvmlite.binding as ll

    row = bench_driven._width_row(True)
    assert math.isfinite(row["ratio"]) and row["ratio"] > 0
    if "+avx512f" in ll.get_host_cpu_features().flatten().split(","):
        assert row["variant"].startswith("driven kernel at 512-bit vectors")
        assert row["note"].endswith("the same states: True")
    else:
        assert "both ran alike" in row["note"]
