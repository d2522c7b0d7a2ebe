"""CUDA backend: the labelling kernel of :mod:`atlas.kernels` on an NVIDIA GPU (numba-cuda).

One orbit per thread. The RK4 step and the trap test are the CPU kernels' own factories of
:mod:`atlas.kernels.rk4`, compiled for the device from the same Python source. Variants:
``"straightforward"`` (libdevice sin, the CPU straightforward kernel line for line) and
``"fast"`` (θ kept near [−π, π] with the winding counted apart, polynomial sin). Method "rk4"
only; :func:`kernels` compiles the τ = 0 kernels, :func:`torque_kernels` the tilted one. The
host side (chunks, streams, pinned staging) is :mod:`atlas.kernels.cuda_host`; numba.cuda is
imported only when a function here is called.

Accuracy: labels, status and n_trap equal the CPU's method "rk4" except for orbits decided by
rounding (within ~1e-12 of a separatrix, or an energy within ~1e-13 of the cap); checked by
tests/kernels/test_cuda.py. Details: docs/design/kernels.md#cuda.
"""

from __future__ import annotations

import contextlib
import functools
import math
from typing import NamedTuple

import numpy as np

from atlas.errors import BackendUnavailable
from atlas.kernels import NONFINITE, RUNNING, TRAPPED, UNRESOLVED
from atlas.kernels.fastsin import INV_PI, PI_1, PI_2, PI_3, sin_poly
from atlas.kernels.rk4 import (
    INV_TWO_PI,
    make_rk4_step,
    make_rk4_step_torque,
    make_running_test,
    make_well_energy,
    make_well_energy_torque,
)

__all__ = ["VARIANTS", "cuda_status", "kernels", "torque_kernels", "require_cuda", "import_cuda",
           "simulator"]

#: Kernel variants: name -> (sin implementation, keep θ wrapped near [−π, π]).
VARIANTS = ("fast", "straightforward")
#: Steps between two wraps of θ in the fast fixed-steps kernel (stage offsets stay < 1 rad).
WRAP_EVERY = 16
#: 1.5·2⁵²: (x + R) − R rounds x to the nearest integer in float arithmetic for |x| < 2⁵¹,
#: with no float→int conversion (NaN stays NaN; a NaN→int conversion would raise in the
#: simulator and is undefined in LLVM).
ROUND_MAGIC = 6755399441055744.0
_INSTALL_HINT = "install pendulum-atlas[cuda] on a machine with an NVIDIA GPU"

#: numba.cuda once imported by import_cuda(). The kernels refer to it as a module global
#: because the simulator substitutes its fake module only among a kernel's globals.
cuda = None


@functools.cache
def import_cuda():
    """Import numba.cuda once; raise BackendUnavailable with one line when it cannot be."""
    global cuda
    try:
        from numba import cuda as module
    except Exception as exc:  # e.g. numba-cuda without a CUDA extra: libcudart not found
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise BackendUnavailable(
            f"backend 'cuda': numba.cuda cannot be imported ({reason}); {_INSTALL_HINT}"
        ) from None
    cuda = module
    return module


@contextlib.contextmanager
def row_stack_alias():
    """numba-cuda 0.30 still calls ``numpy.row_stack``, removed in numpy 2.5; without it
    compiling a kernel fails with "module 'numpy' has no attribute 'row_stack'". The alias
    (``numpy.vstack``) exists only while kernels compile here, and is removed afterwards:
    a library must not change numpy for the whole process."""
    if hasattr(np, "row_stack"):
        yield
        return
    np.row_stack = np.vstack
    try:
        yield
    finally:
        del np.row_stack


def simulator() -> bool:
    from numba import config

    return bool(config.ENABLE_CUDASIM)


def cuda_status() -> tuple[bool, str]:
    """(usable?, device name or why not). Never raises; the simulator counts as usable and
    is reported as "CUDA simulator"."""
    try:
        cuda = import_cuda()
        if simulator():
            return True, "CUDA simulator"
        if not cuda.is_available():
            return False, "no CUDA GPU found (numba.cuda.is_available() is False)"
        name = cuda.get_current_device().name
        return True, name.decode() if isinstance(name, bytes) else str(name)
    except BackendUnavailable as exc:
        return False, str(exc).removeprefix("backend 'cuda': ")
    except Exception as exc:  # a broken driver or toolkit must not escape as a traceback
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return False, f"CUDA unusable ({first})"


def require_cuda():
    ok, reason = cuda_status()
    if not ok:
        hint = "" if _INSTALL_HINT in reason else f"; {_INSTALL_HINT}"
        raise BackendUnavailable(f"backend 'cuda': {reason}{hint}")
    return import_cuda()


class Kernels(NamedTuple):
    """Compiled kernels of one variant and their block sizes (threads per block)."""

    label: object
    propagate: object
    label_block: int
    propagate_block: int


def device_function(cuda, jitted):
    """``jitted`` (a factory's CPU dispatcher, or a plain function) compiled as a CUDA device
    function from its Python source (``py_func``), with CUDA's own floating-point options
    (called directly, numba would retarget it with the CPU fast-math set, which the CUDA
    compiler turns into fastmath=True: all fast flags, nnan included, and approximate
    division)."""
    return cuda.jit(device=True)(getattr(jitted, "py_func", jitted))


def _device_sin(cuda, variant: str):
    """The variant's ``(sin, sin_near, identity)`` as CUDA device functions: sin (libdevice's
    for "straightforward", Cody–Waite by π and the polynomial for "fast"),
    sin_near(θ, δ) = sin(θ + δ) and the identity, given to the rk4 step factories as
    ``sin`` and ``reduce`` so that the step calls these device functions instead of the
    factory's CPU helper."""
    if variant == "straightforward":

        @cuda.jit(device=True)
        def sin(x):
            return math.sin(x)

    else:
        poly = device_function(cuda, sin_poly)

        # Cody–Waite by π as in fastsin.reduce_pi, restated because numba-cuda has no device
        # lowering of np.floor (reduce_pi's): q is rounded with ROUND_MAGIC instead.
        @cuda.jit(device=True)
        def sin(x):
            q = (x * INV_PI + ROUND_MAGIC) - ROUND_MAGIC
            r = ((x - q * PI_1) - q * PI_2) - q * PI_3
            parity = math.fabs(q - 2.0 * ((0.5 * q + ROUND_MAGIC) - ROUND_MAGIC))
            return (1.0 - 2.0 * parity) * poly(r)

    @cuda.jit(device=True)
    def sin_near(theta, delta):
        return sin(theta + delta)

    @cuda.jit(device=True)
    def identity(theta):
        return theta

    return sin, sin_near, identity


def _device_functions(cuda, variant: str):
    """The variant's (step, well_energy) as CUDA device functions built by the rk4 factories
    (:func:`_device`, :func:`_device_sin`)."""
    sin, sin_near, identity = _device_sin(cuda, variant)
    return (device_function(cuda, make_rk4_step(sin_near, reduce=identity)),
            device_function(cuda, make_well_energy(sin)))


def _device_functions_torque(cuda, variant: str):
    """The variant's (step, well_energy, running) for τ ≠ 0 as CUDA device functions, built
    like :func:`_device_functions` from the τ ≠ 0 factories."""
    sin, sin_near, identity = _device_sin(cuda, variant)

    @cuda.jit(device=True)
    def floor(x):  # a float floor (numba-cuda lowers math.floor, not np.floor)
        return float(math.floor(x))

    return (device_function(cuda, make_rk4_step_torque(sin_near, reduce=identity)),
            device_function(cuda, make_well_energy_torque(sin)),
            device_function(cuda, make_running_test(floor)))


def block_size(cuda, kernel) -> int:
    """Threads per block maximising resident threads per SM given the kernel's registers
    (CUDA occupancy rules: registers allocated per warp in units of 256); ties go to the
    smaller block, which balances the uneven work of early exits better. 128 when the
    device cannot be queried (simulator)."""
    try:
        regs = max(1, kernel.get_regs_per_thread())
        dev = cuda.get_current_device()
        regs_sm = dev.MAX_REGISTERS_PER_MULTIPROCESSOR
        threads_sm = dev.MAX_THREADS_PER_MULTIPROCESSOR
        blocks_sm = dev.MAX_BLOCKS_PER_MULTIPROCESSOR
    except Exception:
        return 128
    warps_by_regs = regs_sm // (-(-regs * 32 // 256) * 256)

    def resident(block):
        return min(blocks_sm, threads_sm // block, warps_by_regs // (block // 32)) * block

    return max((64, 128, 256, 512, 1024), key=lambda b: (resident(b), -b))


@functools.cache
def kernels(variant: str = "fast") -> Kernels:
    """Compile (once) the labelling and fixed-steps kernels of ``variant`` (see module doc).

    ``label(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
    attractor, status, n_trap)`` follows the contract of :mod:`atlas.kernels` on device
    arrays; ``propagate(theta, theta_dot, alpha, omega0, dt, n_steps)`` advances in place.
    """
    if variant not in VARIANTS:
        raise ValueError(f"CUDA variant must be one of {VARIANTS}, got {variant!r}")
    require_cuda()  # binds the global `cuda` the kernels below refer to
    with row_stack_alias():
        return _compile(variant)


def _compile(variant: str) -> Kernels:
    step, well_energy = _device_functions(cuda, variant)
    wrap = variant == "fast"
    f8, i8, i4, i1 = "float64", "int64", "int32", "int8"
    label_sig = (f"void({f8}[::1], {f8}[::1], {f8}, {f8}, {f8}, {i8}, {i8}, {f8}, "
                 f"{i4}[::1], {i1}[::1], {i4}[::1])")
    propagate_sig = f"void({f8}[::1], {f8}[::1], {f8}, {f8}, {f8}, {i8})"

    @cuda.jit(label_sig)
    def label(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
              attractor, status, n_trap):
        i = cuda.grid(1)
        if i >= theta0.size:
            return
        theta = theta0[i]
        theta_dot = theta_dot0[i]
        winding = 0
        status[i] = UNRESOLVED
        n_trap[i] = -1
        for j in range(n_checks + 1):
            if not (math.isfinite(theta) and math.isfinite(theta_dot)):
                status[i] = NONFINITE
                return
            k, energy = well_energy(theta, theta_dot, omega0)
            if energy < energy_cap:
                attractor[i] = winding + k
                status[i] = TRAPPED
                n_trap[i] = j * check_every
                return
            if j == n_checks:
                return
            if wrap:  # a closure constant: compiled out of the straightforward variant
                theta = ((theta - k * (2.0 * PI_1)) - k * (2.0 * PI_2)) - k * (2.0 * PI_3)
                winding += k
            for _ in range(check_every):
                theta, theta_dot = step(theta, theta_dot, alpha, omega0, dt)

    @cuda.jit(propagate_sig)
    def propagate(theta, theta_dot, alpha, omega0, dt, n_steps):
        i = cuda.grid(1)
        if i >= theta.size:
            return
        th = theta[i]
        v = theta_dot[i]
        winding = 0.0  # float: a NaN θ must not meet a float→int conversion
        for s in range(n_steps):
            th, v = step(th, v, alpha, omega0, dt)
            if wrap and s % WRAP_EVERY == WRAP_EVERY - 1:
                k = (th * INV_TWO_PI + ROUND_MAGIC) - ROUND_MAGIC
                th = ((th - k * (2.0 * PI_1)) - k * (2.0 * PI_2)) - k * (2.0 * PI_3)
                winding += k
        if wrap:
            th = ((th + winding * (2.0 * PI_1)) + winding * (2.0 * PI_2)) + winding * (2.0 * PI_3)
        theta[i] = th
        theta_dot[i] = v

    return Kernels(label, propagate, block_size(cuda, label), block_size(cuda, propagate))


class TorqueKernel(NamedTuple):
    """The compiled τ ≠ 0 labelling kernel of one variant and its block size."""

    label: object
    label_block: int


@functools.cache
def torque_kernels(variant: str = "fast") -> TorqueKernel:
    """Compile (once) the τ ≠ 0 labelling kernel of ``variant``:
    ``label(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap, torque,
    shift, vers_shift, sign, running_theta0, running_g, running_top, attractor, status,
    n_trap)`` on device arrays (``running_g`` a device array, empty for none; shift, vers_shift
    and sign as in :func:`atlas.kernels.rk4.torque_model`)."""
    if variant not in VARIANTS:
        raise ValueError(f"CUDA variant must be one of {VARIANTS}, got {variant!r}")
    require_cuda()
    with row_stack_alias():
        return _compile_torque(variant)


def _compile_torque(variant: str) -> TorqueKernel:
    step, well_energy, running = _device_functions_torque(cuda, variant)
    wrap = variant == "fast"
    f8, i8, i4, i1 = "float64", "int64", "int32", "int8"
    sig = (f"void({f8}[::1], {f8}[::1], {f8}, {f8}, {f8}, {i8}, {i8}, {f8}, {f8}, {f8}, {f8}, "
           f"{f8}, {f8}, {f8}[::1], {f8}, {i4}[::1], {i1}[::1], {i4}[::1])")

    # Written out beside _compile's label, not shared with it: that τ = 0 kernel stays the code
    # of earlier versions, and a loop shared through a device function over a model tuple
    # would restructure it, which only a real GPU (not the simulator) could check.
    @cuda.jit(sig)
    def label(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap, torque,
              shift, vers_shift, sign, running_theta0, running_g, running_top, attractor,
              status, n_trap):
        i = cuda.grid(1)
        if i >= theta0.size:
            return
        theta = theta0[i]
        theta_dot = theta_dot0[i]
        winding = 0
        status[i] = UNRESOLVED
        n_trap[i] = -1
        for j in range(n_checks + 1):
            if not (math.isfinite(theta) and math.isfinite(theta_dot)):
                status[i] = NONFINITE
                return
            k, energy = well_energy(theta, theta_dot, omega0, torque, shift, vers_shift)
            if energy < energy_cap:
                attractor[i] = winding + k
                status[i] = TRAPPED
                n_trap[i] = j * check_every
                return
            if running(theta, theta_dot, sign, running_theta0, running_g, running_top):
                status[i] = RUNNING
                n_trap[i] = j * check_every
                return
            if j == n_checks:
                return
            if wrap:
                theta = ((theta - k * (2.0 * PI_1)) - k * (2.0 * PI_2)) - k * (2.0 * PI_3)
                winding += k
            for _ in range(check_every):
                theta, theta_dot = step(theta, theta_dot, alpha, omega0, dt, torque)

    return TorqueKernel(label, block_size(cuda, label))
