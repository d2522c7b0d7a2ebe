"""The driven pendulum's stroboscopic map on an NVIDIA GPU: :func:`label_driven_cuda`.

The CUDA twin of :func:`atlas.kernels.driven.label_driven` (same arguments, results and
statuses; method, accuracy and reference in :mod:`atlas.kernels.driven`), one orbit per thread,
and :func:`advance_cuda`, the twin of :func:`atlas.kernels.driven.advance`. Nothing of the
method is restated: the RK4 step (:func:`atlas.kernels.driven.make_driven_step`), the choice of
the SHARED or FULL reduction of the stage angles (``orbit_path``), the proximity test and the
decision rule (:func:`atlas.kernels.driven.make_visit_label`) are the CPU kernels' own,
compiled for the device from their Python source as in :mod:`atlas.kernels.cuda`. Only the
device's sin is written here: the polynomial of :mod:`atlas.kernels.fastsin` after the
Cody–Waite step by π, q rounded as in :mod:`atlas.kernels.cuda` (numba-cuda lowers no
np.floor). The forcing table τ + A cos(Ωt_j + φ) and the targets go to the device once per
call, in global memory (every thread of a warp reads the same entry at the same step: one
broadcast); each thread advances its orbit period by period, N steps per period, and stops
when the visitor says it is done. The host side (chunks, two streams, pinned staging) is
:func:`atlas.kernels.cuda_host.run_chunked`; availability: :func:`atlas.kernels.cuda.cuda_status`
(the functions here raise BackendUnavailable, one line, without CUDA). numba.cuda is imported
only when a function here is called.

Accuracy: the device runs the CPU's arithmetic in the CPU's order with the same polynomial
sin. The results differ only by FMA contraction and by the reduction's rounding of θ/π within
an ulp of a half-integer (fastsin's floor(θ/π + ½) against rounding to nearest), last-bit
effects that the map then amplifies like any rounding: states after two periods agree to
~1e-14 relative; labels and deciding periods agree except for an orbit whose return falls
within rounding of a target's radius, or whose transient is long enough for chaos to grow
those last bits. Checked under the simulator (where the states equal a plain-Python
evaluation of the CPU step bit for bit) by tests/kernels/test_driven_cuda.py.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from atlas.kernels import ATTRACTOR_FILL
from atlas.kernels.cuda import (
    ROUND_MAGIC,
    block_size,
    device_function,
    require_cuda,
    row_stack_alias,
)
from atlas.kernels.cuda_host import run_chunked
from atlas.kernels.driven import (
    check_in_place,
    drive,
    label_arrays,
    make_driven_step,
    make_visit_label,
    nearest_attractor,
    orbit_path,
    visit_advance,
)
from atlas.kernels.fastsin import INV_PI, PI_1, PI_2, PI_3, sin_poly
from atlas.kernels.lanes import SHARED

__all__ = ["label_driven_cuda", "advance_cuda", "driven_kernels"]

#: numba.cuda once :func:`driven_kernels` has run. The kernels refer to it as a module global
#: because the simulator substitutes its fake module only among a kernel's globals.
cuda = None


class DrivenKernels(NamedTuple):
    """The compiled kernels and their block sizes (threads per block)."""

    label: object
    advance: object
    label_block: int
    advance_block: int


@functools.cache
def driven_kernels() -> DrivenKernels:
    """Compile (once) ``label(theta0, theta_dot0, alpha, omega0, dt, forcing, accel, targets,
    target_attractor, radius, confirm, max_periods, attractor, periods, status)`` and
    ``advance(theta, theta_dot, alpha, omega0, dt, forcing, accel, periods)`` (in place) on
    device arrays; ``forcing, accel`` as :func:`atlas.kernels.driven.drive` gives them.
    Raises BackendUnavailable (one line) when CUDA cannot be used."""
    global cuda
    cuda = require_cuda()
    with row_stack_alias():
        return _compile()


def _device_steps():
    """The SHARED and FULL RK4 steps as CUDA device functions: the CPU's step factory around
    device versions of fastsin's ``reduce_pi``, ``sin_near`` and ``fast_sin``."""
    poly = device_function(cuda, sin_poly)

    @cuda.jit(device=True)
    def reduce_pi(x):
        q = (x * INV_PI + ROUND_MAGIC) - ROUND_MAGIC
        r = ((x - q * PI_1) - q * PI_2) - q * PI_3
        parity = math.fabs(q - 2.0 * ((0.5 * q + ROUND_MAGIC) - ROUND_MAGIC))
        return r, 1.0 - 2.0 * parity

    @cuda.jit(device=True)
    def sin_near(reduced, delta):
        r, sign = reduced
        return sign * poly(r + delta)

    @cuda.jit(device=True)
    def sin_sum(theta, delta):
        r, sign = reduce_pi(theta + delta)
        return sign * poly(r)

    @cuda.jit(device=True)
    def unreduced(theta):
        return theta

    return (device_function(cuda, make_driven_step(sin_near, reduce_pi)),
            device_function(cuda, make_driven_step(sin_sum, unreduced)))


def _device_orbit(visit, path, one_period):
    """``orbit(i, theta0, theta_dot0, alpha, omega0, dt, forcing, accel, args)``: a device
    function that follows orbit i from (θ0[i], θ̇0[i]) period by period until ``visit``
    (the CPU's visitor protocol of :func:`atlas.kernels.driven.make_period_chunk`, one lane)
    says it is done."""

    @cuda.jit(device=True)
    def orbit(i, theta0, theta_dot0, alpha, omega0, dt, forcing, accel, args):
        th = theta0[i]
        v = theta_dot0[i]
        shared = path(th, v, alpha, omega0, dt, accel) == SHARED
        memo = cuda.local.array((1, 2), np.int64)
        memo[0, 0] = ATTRACTOR_FILL
        memo[0, 1] = 0
        p = 0
        while not visit(i, p, th, v, memo, 0, args):
            th, v = one_period(th, v, shared, alpha, omega0, dt, forcing)
            p += 1

    return orbit


def _compile() -> DrivenKernels:
    shared_step, full_step = _device_steps()
    path = device_function(cuda, orbit_path)

    @cuda.jit(device=True)
    def one_period(th, v, shared, alpha, omega0, dt, forcing):
        # the drive at t, t + dt/2, t + dt of step j/2, as in driven.make_period_chunk
        for j in range(0, forcing.size - 1, 2):
            if shared:
                th, v = shared_step(th, v, alpha, omega0, dt, forcing[j], forcing[j + 1],
                                    forcing[j + 2])
            else:
                th, v = full_step(th, v, alpha, omega0, dt, forcing[j], forcing[j + 1],
                                  forcing[j + 2])
        return th, v

    visit_label = make_visit_label(device_function(cuda, nearest_attractor))
    label_orbit = _device_orbit(device_function(cuda, visit_label), path, one_period)
    advance_orbit = _device_orbit(device_function(cuda, visit_advance), path, one_period)
    f8, i8, i4, i2, i1 = "float64", "int64", "int32", "int16", "int8"
    common = f"{f8}, {f8}, {f8}, {f8}[::1], {f8}"  # alpha, omega0, dt, forcing, accel
    label_sig = (f"void({f8}[::1], {f8}[::1], {common}, {f8}[:, ::1], {i2}[::1], {f8}[::1], "
                 f"{i8}[::1], {i8}, {i2}[::1], {i4}[::1], {i1}[::1])")
    advance_sig = f"void({f8}[::1], {f8}[::1], {common}, {i8})"

    @cuda.jit(label_sig)
    def label(theta0, theta_dot0, alpha, omega0, dt, forcing, accel, targets, target_attractor,
              radius, confirm, max_periods, attractor, periods, status):
        i = cuda.grid(1)
        if i < theta0.size:
            label_orbit(i, theta0, theta_dot0, alpha, omega0, dt, forcing, accel,
                        (targets, target_attractor, radius, confirm, max_periods, attractor,
                         periods, status))

    @cuda.jit(advance_sig)
    def advance(theta, theta_dot, alpha, omega0, dt, forcing, accel, periods):
        # each thread reads its initial state before it writes its final one: in place
        i = cuda.grid(1)
        if i < theta.size:
            advance_orbit(i, theta, theta_dot, alpha, omega0, dt, forcing, accel,
                          (periods, theta, theta_dot))

    return DrivenKernels(label, advance, block_size(cuda, label), block_size(cuda, advance))


def label_driven_cuda(theta0, theta_dot0, alpha, omega0, torque, table, dt, targets,
                      target_attractor, radius, confirm, max_periods, *,
                      chunk: int | None = None):
    """:func:`atlas.kernels.driven.label_driven` on the GPU: the same arguments (host arrays)
    and the same (attractor int16, periods int32, status int8). ``chunk`` caps the orbits per
    chunk (default: :func:`atlas.kernels.cuda_host.chunk_orbits` for the device). Raises
    BackendUnavailable (one line) when CUDA cannot be used."""
    k = driven_kernels()
    a = label_arrays(theta0, theta_dot0, targets, target_attractor, radius, confirm,
                     max_periods)
    forcing, accel = drive(omega0, torque, table, dt)
    if a.theta0.size == 0:
        return a.attractor, a.periods, a.status
    # the drive and the targets are the same for every orbit: on the device once, whole
    args = (a.theta0, a.theta_dot0, float(alpha), float(omega0), float(dt),
            cuda.to_device(forcing), accel, cuda.to_device(a.targets),
            cuda.to_device(a.target_attractor), cuda.to_device(a.radius), cuda.to_device(a.confirm),
            int(max_periods), a.attractor, a.periods, a.status)
    # attractor is "inout": the kernel writes it only where an orbit is decided
    modes = ("in", "in") + (None,) * 10 + ("inout", "out", "out")
    run_chunked(cuda, k.label, k.label_block, args, modes, chunk)
    return a.attractor, a.periods, a.status


def advance_cuda(theta, theta_dot, alpha, omega0, torque, table, dt, periods, *,
                 chunk: int | None = None) -> None:
    """:func:`atlas.kernels.driven.advance` on the GPU: P applied ``periods`` times to every
    state, in place (contiguous float64 host arrays)."""
    k = driven_kernels()
    check_in_place(theta, theta_dot, periods)
    forcing, accel = drive(omega0, torque, table, dt)
    if theta.size == 0:
        return
    args = (theta, theta_dot, float(alpha), float(omega0), float(dt), cuda.to_device(forcing),
            accel, int(periods))
    modes = ("inout", "inout") + (None,) * 6
    run_chunked(cuda, k.advance, k.advance_block, args, modes, chunk)
