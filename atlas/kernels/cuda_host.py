"""CUDA backend, host side: :func:`label_cuda` and :func:`propagate_cuda` on host numpy arrays.

The batch is cut into chunks that fit in free device memory and run on two streams with pinned
staging buffers, so chunk i+1's transfers overlap chunk i's kernel. The kernels themselves
(one orbit per thread, variants "fast" and "straightforward") and the availability checks are
in :mod:`atlas.kernels.cuda`.
"""

from __future__ import annotations

import math

import numpy as np

from . import uses_torque
from .cuda import _import_cuda, kernels, torque_kernels
from .rk4 import torque_model

__all__ = ["label_cuda", "propagate_cuda", "CHUNK_CAP", "MEMORY_FRACTION"]

#: Most orbits per chunk (≈ 25 B each on the device for labelling, two chunks in flight).
CHUNK_CAP = 1 << 22
#: Fraction of the free device memory the two in-flight chunks may take.
MEMORY_FRACTION = 0.5
#: The running barrier passed when there is none: one sample (the kernels test the barrier
#: only with ≥ 2 samples; a device array is kept non-empty).
_NO_BARRIER = np.zeros(1)


def _chunk_size(cuda, bytes_per_item: int, block: int, cap: int | None) -> int:
    """Orbits per chunk: two chunks in flight within MEMORY_FRACTION of free device memory."""
    free, _total = cuda.current_context().get_memory_info()
    fit = MEMORY_FRACTION * float(free) / (2 * bytes_per_item)
    size = int(min(float(cap or CHUNK_CAP), fit))
    return max(block, size // block * block) if cap is None else max(1, size)


def _run_chunked(cuda, kernel, block, args, modes, chunk):
    """Launch ``kernel(*args)`` over length-n host arrays in chunks, double-buffered.

    ``modes[i]`` is "in", "out", "inout" for array arguments and None for scalars. Each of two
    buffer sets owns a stream, pinned staging arrays and device arrays; chunk c uses set c % 2
    and the host waits for a set only when it reuses it, so one chunk's copies overlap the
    other chunk's kernel.
    """
    arrays = [(i, a) for i, (a, m) in enumerate(zip(args, modes, strict=True)) if m is not None]
    n = arrays[0][1].size
    size = min(n, _chunk_size(cuda, sum(a.itemsize for _, a in arrays), block, chunk))
    sets = []
    for _ in range(min(2, -(-n // size))):
        stream = cuda.stream()
        pinned = {i: cuda.pinned_array(size, a.dtype) for i, a in arrays}
        device = {i: cuda.device_array(size, a.dtype, stream=stream) for i, a in arrays}
        sets.append({"stream": stream, "pinned": pinned, "device": device, "pending": None})

    def finish(buf):
        if buf["pending"] is None:
            return
        lo, hi = buf["pending"]
        buf["stream"].synchronize()
        for i, a in arrays:
            if modes[i] != "in":
                a[lo:hi] = buf["pinned"][i][: hi - lo]
        buf["pending"] = None

    for c, lo in enumerate(range(0, n, size)):
        hi = min(n, lo + size)
        m = hi - lo
        buf = sets[c % 2]
        finish(buf)
        stream, pinned, device = buf["stream"], buf["pinned"], buf["device"]
        call = list(args)
        for i, a in arrays:
            view = device[i][:m]
            if modes[i] != "out":
                pinned[i][:m] = a[lo:hi]
                view.copy_to_device(pinned[i][:m], stream=stream)
            call[i] = view
        kernel[-(-m // block), block, stream](*call)
        for i, _ in arrays:
            if modes[i] != "in":
                device[i][:m].copy_to_host(pinned[i][:m], stream=stream)
        buf["pending"] = (lo, hi)
    for buf in sets:
        finish(buf)


def label_cuda(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
               attractor, status, n_trap, torque=0.0, running_theta0=0.0, running_g=None,
               running_top=math.inf, *, variant: str = "fast", chunk: int | None = None):
    """Label orbits on the GPU; the contract of :mod:`atlas.kernels` on host numpy arrays.

    ``variant`` picks the kernel (module doc); ``chunk`` caps the orbits per chunk (default:
    by free device memory, at most CHUNK_CAP). Raises BackendUnavailable (one line) when CUDA
    cannot be used. τ = 0 without a running barrier runs the kernels of earlier versions.
    """
    if uses_torque(torque, running_g):
        _label_cuda_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                           energy_cap, attractor, status, n_trap, torque, running_theta0,
                           running_g, running_top, variant, chunk)
        return
    k = kernels(variant)
    if theta0.size == 0:
        return
    args = (theta0, theta_dot0, float(alpha), float(omega0), float(dt), int(n_checks),
            int(check_every), float(energy_cap), attractor, status, n_trap)
    # attractor is "inout": the contract leaves it untouched where nothing is trapped.
    modes = ("in", "in", None, None, None, None, None, None, "inout", "out", "out")
    _run_chunked(_import_cuda(), k.label, k.label_block, args, modes, chunk)


def _label_cuda_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                       energy_cap, attractor, status, n_trap, torque, running_theta0,
                       running_g, running_top, variant, chunk):
    k = torque_kernels(variant)
    if theta0.size == 0:
        return
    tq, shift, vers, sign, r_theta0, g, r_top, _ = torque_model(
        omega0, torque, running_theta0, running_g, running_top)
    cuda = _import_cuda()
    # the barrier goes to the device once, whole (not chunked: it is not per orbit); a
    # 1-sample placeholder keeps the kernel's array argument non-empty, g.size < 2 = none
    g_dev = cuda.to_device(g if g.size else _NO_BARRIER)
    args = (theta0, theta_dot0, float(alpha), float(omega0), float(dt), int(n_checks),
            int(check_every), float(energy_cap), tq, shift, vers, sign, r_theta0, g_dev, r_top,
            attractor, status, n_trap)
    modes = ("in", "in") + (None,) * 13 + ("inout", "out", "out")
    _run_chunked(cuda, k.label, k.label_block, args, modes, chunk)


def propagate_cuda(theta, theta_dot, alpha, omega0, dt, n_steps, *, variant: str = "fast",
                   chunk: int | None = None):
    """Advance every orbit (θ [rad], θ̇ [rad s⁻¹], float64 1-D host arrays) by ``n_steps`` RK4
    steps of ``dt`` [s] in place, no early exit: the GPU twin of
    :func:`atlas.kernels.rk4.propagate_straightforward` (bulk-throughput benchmark)."""
    k = kernels(variant)
    if theta.size == 0:
        return
    args = (theta, theta_dot, float(alpha), float(omega0), float(dt), int(n_steps))
    modes = ("inout", "inout", None, None, None, None)
    _run_chunked(_import_cuda(), k.propagate, k.propagate_block, args, modes, chunk)
