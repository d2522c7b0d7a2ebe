"""The lane-blocked kernel against the straightforward one (same contract, same results up to
the documented separatrix cells), and its independence of threads, chunking and input order."""

import math
import re

import numba as nb
import numpy as np
import pytest

from atlas.kernels import NONFINITE, TRAPPED, UNRESOLVED
from atlas.kernels.fastsin import SIN_FASTMATH
from atlas.kernels.lanes import (
    FULL,
    LANES,
    SCALAR,
    SHARED,
    label_lanes,
    label_trigfree,
    n_chunks,
    propagate_lanes,
    propagate_trigfree,
)
from atlas.kernels.rk4 import label_straightforward, propagate_straightforward
from atlas.labels.trap import energy_cap, n_checks_for
from tests.helpers import boundary_adjacent

ALPHA, OMEGA0, DT, T_MAX = 0.1, 1.0, 0.01, 200.0
CAP = energy_cap(DT, ALPHA, OMEGA0)
SENTINEL = 777


def _grid(n_theta, n_theta_dot):
    th, v = np.meshgrid(np.linspace(-3 * np.pi, 3 * np.pi, n_theta),
                        np.linspace(-4.0, 4.0, n_theta_dot))
    return th.ravel().copy(), v.ravel().copy()


def _run(kernel, theta0, theta_dot0, check_every=16, t_max=T_MAX, alpha=ALPHA, dt=DT):
    n = theta0.size
    attractor = np.full(n, SENTINEL, np.int32)
    status = np.full(n, 99, np.int8)
    n_trap = np.full(n, -99, np.int32)
    kernel(theta0, theta_dot0, alpha, OMEGA0, dt, n_checks_for(t_max, dt, check_every),
           check_every, CAP, attractor, status, n_trap)
    return attractor, status, n_trap


@pytest.mark.parametrize("check_every", [1, 16])
def test_same_labels_as_straightforward_kernel(check_every):
    th, v = _grid(64, 64)
    a_ref, s_ref, n_ref = _run(label_straightforward, th, v, check_every)
    a, s, n = _run(label_lanes, th, v, check_every)
    np.testing.assert_array_equal(s, s_ref)
    differ = a != a_ref
    # a label may differ only on a basin boundary (orbit within ~1e-11 of a separatrix)
    assert differ.sum() <= 0.005 * th.size
    assert not (differ.reshape(64, 64) & ~boundary_adjacent(a_ref.reshape(64, 64))).any()
    # both test at steps 0, c, 2c, …; trajectories differ by ~1e-11, so they trap at the same
    # check unless E_k sits within that of the trap level at a check, which moves it by one c
    same = ~differ
    moved = n[same] != n_ref[same]
    assert moved.sum() <= 2
    assert np.all(np.abs(n[same] - n_ref[same]) <= check_every)


def test_trapping_times_with_sparse_checks_bracket_the_exact_ones():
    th, v = _grid(32, 32)
    _, _, n1 = _run(label_straightforward, th, v, check_every=1)
    a, _, n16 = _run(label_lanes, th, v, check_every=16)
    # the trap is invariant, so checking every 16 steps finds it at the next multiple of 16
    assert np.all(n16 % 16 == 0)
    np.testing.assert_array_equal(n16, 16 * np.ceil(n1 / 16).astype(np.int32))


@pytest.mark.slow
def test_propagate_matches_straightforward():
    th, v = _grid(31, 33)  # 1023 orbits: not a multiple of LANES
    assert th.size % LANES
    ref_th, ref_v = th.copy(), v.copy()
    propagate_straightforward(ref_th, ref_v, ALPHA, OMEGA0, DT, 1000)
    propagate_lanes(th, v, ALPHA, OMEGA0, DT, 1000)
    # sin differs by ≤ 1e-15 per call; over 1000 steps that grows to ~1e-11 on the most
    # sensitive orbits (those passing close to a saddle)
    np.testing.assert_allclose(th, ref_th, rtol=0, atol=1e-10)
    np.testing.assert_allclose(v, ref_v, rtol=0, atol=1e-10)


@pytest.mark.slow
@pytest.mark.parametrize("kernel", [label_lanes, label_trigfree])
def test_independent_of_threads_chunking_and_order(kernel):
    th, v = _grid(160, 128)  # 20480 orbits: several chunks
    full = _run(kernel, th, v)
    n_threads = nb.get_num_threads()
    try:
        nb.set_num_threads(1)
        chunks_one = n_chunks(th.size)
        one = _run(kernel, th, v)
    finally:
        nb.set_num_threads(n_threads)
    if n_threads > 1:  # the chunking follows the thread count (and the results do not)
        assert n_chunks(th.size) > chunks_one
    for x, y in zip(full, one):
        np.testing.assert_array_equal(x, y)
    rng = np.random.default_rng(0)
    perm = rng.permutation(th.size)
    shuffled = _run(kernel, th[perm], v[perm])
    for x, y in zip(full, shuffled):
        np.testing.assert_array_equal(x[perm], y)
    for size in (1, 7, 1000):
        idx = rng.choice(th.size, size, replace=False)
        part = _run(kernel, th[idx], v[idx])
        for x, y in zip(full, part):
            np.testing.assert_array_equal(x[idx], y)


@pytest.mark.parametrize("torque", [0.0, 0.5])
@pytest.mark.parametrize("kernel, parallel", [(label_lanes, "_label_lanes"),
                                              (label_trigfree, "_label_trigfree")])
def test_a_single_chunk_runs_serially_with_the_parallel_labels(kernel, parallel, torque,
                                                               monkeypatch):
    """A call of one chunk (the separatrix bisection's small batches) runs the serial twin
    of the parallel kernel, on the calling thread, with the labels and path counts that the
    parallel kernel gives the same orbits within a larger batch; τ = 0 and τ ≠ 0 kernels."""
    from atlas.kernels import lanes

    th, v = _grid(64, 64)
    th = np.concatenate([th, np.linspace(-3.0, 3.0, 32), [np.nan]])
    v = np.concatenate([v, np.linspace(25.0, 90.0, 32), [0.0]])  # + full-reduction lanes
    cap = energy_cap(DT, ALPHA, OMEGA0, torque)
    n_checks = n_checks_for(20.0, DT, 16)

    def run(theta0, theta_dot0):
        n = theta0.size
        out = (np.full(n, SENTINEL, np.int32), np.zeros(n, np.int8), np.zeros(n, np.int32))
        paths = kernel(theta0, theta_dot0, ALPHA, OMEGA0, DT, n_checks, 16, cap, *out,
                       torque=torque)
        return out, paths

    assert n_chunks(th.size) > 1
    whole, whole_paths = run(th, v)

    def not_parallel(*args):
        raise AssertionError("a call of one chunk entered the parallel kernel")

    suffix = "_torque" if torque else ""
    monkeypatch.setattr(lanes, parallel + suffix, not_parallel)
    assert not getattr(lanes, parallel + suffix + "_serial").targetoptions.get("parallel")
    paths = np.zeros(3, np.int64)
    for lo in range(0, th.size, 1000):
        part = slice(lo, lo + 1000)
        assert n_chunks(th[part].size) == 1
        out, counts = run(th[part].copy(), v[part].copy())
        paths += counts
        for name, x, y in zip(("attractor", "status", "n_trap"), whole, out):
            np.testing.assert_array_equal(x[part], y, err_msg=name)
    np.testing.assert_array_equal(paths, whole_paths)
    assert paths[SCALAR] >= 1
    if kernel is label_lanes:
        assert paths[FULL] > 0


@pytest.mark.slow
@pytest.mark.parametrize("propagate", [propagate_lanes, propagate_trigfree])
def test_propagate_independent_of_threads_and_blocks(propagate):
    th, v = _grid(40, 25)
    a_th, a_v = th.copy(), v.copy()
    propagate(a_th, a_v, ALPHA, OMEGA0, DT, 300)
    for sl in (slice(0, 1), slice(3, 10), slice(5, 1000)):
        b_th, b_v = th[sl].copy(), v[sl].copy()
        propagate(b_th, b_v, ALPHA, OMEGA0, DT, 300)
        np.testing.assert_array_equal(b_th, a_th[sl])
        np.testing.assert_array_equal(b_v, a_v[sl])
    n_threads = nb.get_num_threads()
    try:
        nb.set_num_threads(1)
        c_th, c_v = th.copy(), v.copy()
        propagate(c_th, c_v, ALPHA, OMEGA0, DT, 300)
    finally:
        nb.set_num_threads(n_threads)
    np.testing.assert_array_equal(c_th, a_th)
    np.testing.assert_array_equal(c_v, a_v)


def test_contract_edge_cases():
    # inside a trap at step 0; NaN and inf inputs; an orbit still rotating at t_max;
    # fast rotations outside the shared-reduction domain (handled by the reference path)
    th = np.array([0.1, np.nan, 0.0, np.inf, 0.0, 0.5, -2.0, 1.0])
    v = np.array([0.0, 0.0, np.nan, 0.0, 4.0, 60.0, -80.0, 1e308])
    a, s, n = _run(label_lanes, th, v, t_max=5.0)
    a_ref, s_ref, n_ref = _run(label_straightforward, th, v, t_max=5.0)
    np.testing.assert_array_equal(s, s_ref)
    np.testing.assert_array_equal(n, n_ref)
    np.testing.assert_array_equal(a, a_ref)
    assert s[0] == TRAPPED and n[0] == 0 and a[0] == 0
    assert list(s[1:4]) == [NONFINITE] * 3 and list(n[1:4]) == [-1] * 3
    assert s[4] == UNRESOLVED and n[4] == -1 and a[4] == SENTINEL  # untouched unless trapped
    # a state that overflows mid-orbit is reported at the next check
    assert s[7] == NONFINITE


def test_anti_damping_falls_back_to_reference_path():
    th, v = _grid(12, 10)
    got = _run(label_lanes, th, v, t_max=20.0, alpha=-0.05)
    ref = _run(label_straightforward, th, v, t_max=20.0, alpha=-0.05)
    for x, y in zip(got, ref):
        np.testing.assert_array_equal(x, y)


def _packed_fma_host() -> str | None:
    """Why the x86 assembly check cannot run on this host, or None if it can: it greps
    x86-64 FMA mnemonics on ymm/zmm registers, which only an x86-64 CPU with FMA emits."""
    import platform

    from llvmlite.binding import get_host_cpu_features

    machine = platform.machine()
    if machine.lower() not in ("x86_64", "amd64"):
        return f"greps x86-64 assembly; this machine is {machine or 'unknown'}"
    if not get_host_cpu_features().get("fma"):
        return "this x86-64 CPU has no FMA, so no packed vfmadd instructions to find"
    return None


@pytest.mark.slow
@pytest.mark.parametrize("propagate", [propagate_lanes, propagate_trigfree])
def test_lane_loop_is_vectorised(propagate):
    if reason := _packed_fma_host():
        pytest.skip(reason)
    # the cached dispatcher cannot be inspected: compile an uncached copy of the same code
    fresh = nb.njit(parallel=True, fastmath=SIN_FASTMATH)(propagate.py_func)
    th = np.zeros(LANES)
    fresh(th, th.copy(), ALPHA, OMEGA0, DT, 1)
    asm = fresh.inspect_asm(fresh.signatures[0])
    packed_fma = re.findall(r"vfmadd\w*pd\s[^\n]*%[yz]mm", asm)
    assert len(packed_fma) >= 30, "the RK4 lane loop was not vectorised"
    assert math.isfinite(th[0])


def test_fast_orbits_take_the_full_reduction_lanes_and_say_so(caplog):
    """|θ̇| beyond the shared reduction's reach (≳ 30 rad/s at dt = 0.01) runs in vector lanes
    with a full reduction per stage, not in scalar libm; the same labels as the
    straightforward kernel (no orbit of this grid passes near a separatrix: speeds ≥ 25);
    the paths taken are counted per call and logged at debug level."""
    import logging

    th, v = np.meshgrid(np.linspace(-3.0, 3.0, 9), np.concatenate([np.linspace(-90, -25, 9),
                                                                   np.linspace(25, 90, 9)]))
    th, v = th.ravel().copy(), v.ravel().copy()
    paths = np.zeros(3, np.int64)
    with caplog.at_level(logging.DEBUG, logger="atlas.kernels.lanes"):
        n = th.size
        out = (np.full(n, SENTINEL, np.int32), np.zeros(n, np.int8), np.zeros(n, np.int32))
        paths[:] = label_lanes(th, v, ALPHA, OMEGA0, DT, n_checks_for(T_MAX, DT, 16), 16, CAP,
                               *out)
    assert paths[FULL] > 0.5 * th.size and paths[SCALAR] == 0
    assert paths.sum() == th.size
    assert f"{paths[SHARED]} lanes, {paths[FULL]} full-reduction lanes, 0 scalar" in caplog.text
    ref = _run(label_straightforward, th, v)
    for name, x, y in zip(("attractor", "status", "n_trap"), out, ref):
        np.testing.assert_array_equal(x, y, err_msg=name)
    assert np.all(out[1] == TRAPPED)
