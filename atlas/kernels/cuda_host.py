"""CUDA backend, host side: :func:`label_cuda` and :func:`propagate_cuda` on host numpy arrays.

The batch is cut into chunks sized for the device (:func:`chunk_orbits`) and run on two
streams with pinned staging buffers, so chunk i+1's transfers overlap chunk i's kernel. The
streams, pinned and device arrays are kept from call to call (:class:`_Pool`): a sweep labels
one tile per call, page-locking host memory is slow, and freeing device or pinned memory
synchronises the device. The kernels themselves (one orbit per thread, variants "fast" and
"straightforward") and the availability checks are in :mod:`atlas.kernels.cuda`.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from atlas.kernels import uses_torque
from atlas.kernels.cuda import import_cuda, kernels, simulator, torque_kernels
from atlas.kernels.rk4 import torque_model

__all__ = ["label_cuda", "propagate_cuda", "chunk_orbits", "release_buffers", "CHUNK_CAP",
           "MEMORY_FRACTION", "WAVES"]

#: Orbits per chunk where the device cannot be asked its size (the simulator).
CHUNK_CAP = 1 << 22
#: Fraction of the free device memory the two in-flight chunks may take.
MEMORY_FRACTION = 0.5
#: Waves of resident threads per chunk (see :func:`chunk_orbits`).
WAVES = 4
#: The running barrier passed when there is none: one sample (the kernels test the barrier
#: only with ≥ 2 samples; a device array is kept non-empty).
_NO_BARRIER = np.zeros(1)


def chunk_orbits(resident_threads: int | None, free_bytes: float, bytes_per_orbit: int,
                 block: int, cap: int | None = None) -> int:
    """Orbits per chunk [orbits], the smaller of two bounds:

    * the device: ``WAVES × resident_threads``, where ``resident_threads`` [threads] is
      multiprocessors × resident threads per multiprocessor, the orbits the device runs at
      once (one orbit per thread). A chunk's kernel lasts as long as its slowest block, and
      orbits trap anywhere between t = 0 and t_max; with several waves per chunk the
      multiprocessors that finish early take the chunk's remaining blocks, so the idle tail
      is a small part of the chunk, while a large batch still makes several chunks whose
      copies overlap each other's kernels. (A kernel whose registers allow fewer resident
      threads runs more waves per chunk.) ``None`` (the device cannot be asked: simulator):
      CHUNK_CAP.
    * memory: the two chunks in flight take at most ``MEMORY_FRACTION × free_bytes``
      [B] at ``bytes_per_orbit`` [B orbit⁻¹] each.

    Rounded down to whole blocks of ``block`` threads, at least one block. An explicit
    ``cap`` [orbits] replaces the device bound and is not rounded (tests, benchmarks).
    """
    by_memory = MEMORY_FRACTION * float(free_bytes) / (2 * bytes_per_orbit)
    if cap is not None:
        return max(1, int(min(float(cap), by_memory)))
    by_device = CHUNK_CAP if resident_threads is None else WAVES * resident_threads
    size = int(min(float(by_device), by_memory))
    return max(block, size // block * block)


def _resident_threads(cuda) -> int | None:
    """Threads the current device holds at once (None under the simulator, which has none)."""
    if simulator():
        return None
    dev = cuda.get_current_device()
    return dev.MULTIPROCESSOR_COUNT * dev.MAX_THREADS_PER_MULTIPROCESSOR


class _BufferSet:
    """One stream with its pinned staging arrays and device arrays, one of each per argument
    slot and dtype, grown when a call needs more and reused otherwise. ``pending`` is the
    host range (lo, hi) whose results are still on their way back."""

    def __init__(self, cuda):
        self.stream = cuda.stream()
        self.pinned: dict = {}
        self.device: dict = {}
        self.pending = None

    def ensure(self, cuda, arrays, size: int) -> None:
        for slot, a in arrays:
            key = (slot, a.dtype.str)
            if key not in self.pinned or self.pinned[key].size < size:
                self.pinned[key] = cuda.pinned_array(size, a.dtype)
                self.device[key] = cuda.device_array(size, a.dtype, stream=self.stream)

    def views(self, slot: int, dtype, m: int):
        key = (slot, dtype.str)
        return self.pinned[key][:m], self.device[key][:m]

    @property
    def device_bytes(self) -> int:
        return sum(d.size * d.dtype.itemsize for d in self.device.values())


class _Pool:
    """The two buffer sets, kept across calls for the CUDA context they were made in (a new
    context, after ``cuda.close()`` or on another device, starts afresh). One call uses them
    at a time (``lock``): a sweep may label its next tile from a background thread."""

    def __init__(self):
        self.lock = threading.Lock()
        self.context = None
        self.sets: list[_BufferSet] = []

    def take(self, cuda, count: int) -> list[_BufferSet]:
        # the simulator makes a throwaway context object per call: it owns no memory
        context = None if simulator() else cuda.current_context()
        if context is not self.context:
            self.context, self.sets = context, []
        while len(self.sets) < count:
            self.sets.append(_BufferSet(cuda))
        return self.sets[:count]

    @property
    def device_bytes(self) -> int:
        return sum(s.device_bytes for s in self.sets)


_POOL = _Pool()


def release_buffers() -> None:
    """Free the pooled streams, pinned and device arrays (they are made again on next use)."""
    with _POOL.lock:
        _POOL.context, _POOL.sets = None, []


def _chunk_size(cuda, bytes_per_item: int, block: int, cap: int | None) -> int:
    """:func:`chunk_orbits` for the current device; the pool's own device arrays count as
    free, this call reusing them."""
    free, _total = cuda.current_context().get_memory_info()
    return chunk_orbits(_resident_threads(cuda), float(free) + _POOL.device_bytes,
                        bytes_per_item, block, cap)


def run_chunked(cuda, kernel, block, args, modes, chunk):
    """Launch ``kernel(*args)`` over length-n host arrays in chunks, double-buffered.

    ``modes[i]`` is "in", "out", "inout" for array arguments and None for scalars. Each of the
    pool's two buffer sets owns a stream, pinned staging arrays and device arrays; chunk c
    uses set c % 2 and the host waits for a set only when it reuses it, so one chunk's copies
    overlap the other chunk's kernel. Every set is idle again when this returns.
    """
    arrays = [(i, a) for i, (a, m) in enumerate(zip(args, modes, strict=True)) if m is not None]
    n = arrays[0][1].size
    with _POOL.lock:
        size = min(n, _chunk_size(cuda, sum(a.itemsize for _, a in arrays), block, chunk))
        sets = _POOL.take(cuda, min(2, -(-n // size)))
        try:
            for buf in sets:
                buf.ensure(cuda, arrays, size)
            _launch_chunks(kernel, block, args, modes, arrays, n, size, sets)
        except BaseException:
            # copies may still be queued on these buffers: never hand them out again
            _POOL.sets = []
            raise


def _launch_chunks(kernel, block, args, modes, arrays, n, size, sets):
    def finish(buf):
        if buf.pending is None:
            return
        lo, hi = buf.pending
        buf.stream.synchronize()
        for i, a in arrays:
            if modes[i] != "in":
                a[lo:hi] = buf.views(i, a.dtype, hi - lo)[0]
        buf.pending = None

    for c, lo in enumerate(range(0, n, size)):
        hi = min(n, lo + size)
        m = hi - lo
        buf = sets[c % 2]
        finish(buf)
        call = list(args)
        for i, a in arrays:
            pinned, device = buf.views(i, a.dtype, m)
            if modes[i] != "out":
                pinned[:] = a[lo:hi]
                device.copy_to_device(pinned, stream=buf.stream)
            call[i] = device
        kernel[-(-m // block), block, buf.stream](*call)
        for i, a in arrays:
            if modes[i] != "in":
                pinned, device = buf.views(i, a.dtype, m)
                device.copy_to_host(pinned, stream=buf.stream)
        buf.pending = (lo, hi)
    for buf in sets:
        finish(buf)


def label_cuda(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
               attractor, status, n_trap, torque=0.0, running_theta0=0.0, running_g=None,
               running_top=math.inf, *, variant: str = "fast", chunk: int | None = None):
    """Label orbits on the GPU; the contract of :mod:`atlas.kernels` on host numpy arrays.

    ``variant`` picks the kernel (module doc); ``chunk`` caps the orbits per chunk (default:
    :func:`chunk_orbits` for the device). Raises BackendUnavailable (one line) when CUDA
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
    run_chunked(import_cuda(), k.label, k.label_block, args, modes, chunk)


def _label_cuda_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                       energy_cap, attractor, status, n_trap, torque, running_theta0,
                       running_g, running_top, variant, chunk):
    k = torque_kernels(variant)
    if theta0.size == 0:
        return
    tq, shift, vers, sign, r_theta0, g, r_top, _ = torque_model(
        omega0, torque, running_theta0, running_g, running_top)
    cuda = import_cuda()
    # the barrier goes to the device once, whole (not chunked: it is not per orbit); a
    # 1-sample placeholder keeps the kernel's array argument non-empty, g.size < 2 = none
    g_dev = cuda.to_device(g if g.size else _NO_BARRIER)
    args = (theta0, theta_dot0, float(alpha), float(omega0), float(dt), int(n_checks),
            int(check_every), float(energy_cap), tq, shift, vers, sign, r_theta0, g_dev, r_top,
            attractor, status, n_trap)
    modes = ("in", "in") + (None,) * 13 + ("inout", "out", "out")
    run_chunked(cuda, k.label, k.label_block, args, modes, chunk)


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
    run_chunked(import_cuda(), k.propagate, k.propagate_block, args, modes, chunk)
