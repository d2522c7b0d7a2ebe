"""The SIMD width of the lane kernels: 512-bit vectors on a CPU with AVX-512.

LLVM tunes recent Intel server cores (Skylake-SP to Emerald Rapids) with "prefer-256-bit": its
loop vectoriser then stops at 256-bit vectors (4 doubles) although the core has 512-bit ones
(8 doubles), to spare the lower clock that heavy 512-bit code may run at. The lane loops of
:mod:`atlas.kernels.lanes` and :mod:`atlas.kernels.driven` are long runs of fused
multiply-adds on 32 independent orbits, where 512-bit vectors win: measured on a 2-core Emerald
Rapids machine, the bulk RK4 lanes went from 282 to 419 M steps/s and the driven pendulum's map
from 255 to 383 M steps/s (``atlas bench`` measures it on your machine). The width changes no
bit of any result: each lane's arithmetic is the same IR, in the same order (the lane
kernels' fast-math flags exclude reassociation), only more lanes go through one instruction;
the scalar kernels of :mod:`atlas.kernels.rk4` do not vectorise at either width
(tests/kernels/test_vector_width.py compares both kinds at both widths).

:func:`prefer_wide_vectors` drops the tuning flag from the CPU features Numba compiles for,
in Numba's configuration of this process (never in the environment, which child processes
and batch jobs on other machines inherit). It must run before Numba creates its CPU target
(at the first ``njit`` decoration of the process): it runs when this module is imported, and
every kernel module that compiles with Numba imports it before its first ``njit`` (and
:func:`atlas.kernels.cached_njit` before its own); ``import atlas`` alone imports neither it nor
Numba. It leaves alone a process whose Numba target exists already, a user's own CPU name or
features (``NUMBA_CPU_NAME`` / ``NUMBA_CPU_FEATURES``, or set in ``numba.config``), and any CPU
without AVX-512 (where the flag does not exist) or with AVX turned off
(``NUMBA_ENABLE_AVX=0``). ``ATLAS_VECTOR_BITS=256`` keeps LLVM's choice. Numba's cache keys
its machine code by the feature string, so the two widths never share a cached kernel.
"""

from __future__ import annotations

import os

__all__ = ["prefer_wide_vectors", "TUNING", "WIDE", "SET_ON_IMPORT"]

#: LLVM's subtarget tuning that caps the loop vectoriser at 256 bits.
TUNING = "prefer-256-bit"
#: ``ATLAS_VECTOR_BITS`` value that asks for the wide vectors (the default).
WIDE = "512"


def prefer_wide_vectors() -> str | None:
    """Let LLVM vectorise at 512 bits where the CPU has AVX-512: set Numba's CPU features
    (``numba.core.config.CPU_FEATURES``, in this process only: a child process, or a job on
    another machine that inherits the environment, decides for its own CPU) to the host's
    as Numba reads them (``NUMBA_ENABLE_AVX`` honoured) without the 256-bit preference.
    Returns the features set, or None where nothing was changed (see the module
    docstring)."""
    if os.environ.get("ATLAS_VECTOR_BITS", WIDE) != WIDE:
        return None
    if "NUMBA_CPU_NAME" in os.environ or "NUMBA_CPU_FEATURES" in os.environ:
        return None  # the user's choice, even an empty one
    from numba.core import codegen, config

    if config.CPU_NAME is not None or config.CPU_FEATURES is not None or _target_exists():
        return None
    features = codegen.get_host_cpu_features()
    if "+avx512f" not in features.split(","):
        return None
    config.CPU_FEATURES = f"{features},-{TUNING}"
    return config.CPU_FEATURES


def _target_exists() -> bool:
    """Whether Numba's CPU target context (and with it the features it compiles for) has
    been made in this process already."""
    try:
        from numba.core.registry import cpu_target
    except ImportError:
        return True
    # a cached property: in the instance's __dict__ once made (getattr would make it)
    return "_toplevel_target_context" in vars(cpu_target)


#: What :func:`prefer_wide_vectors` set when this module was first imported (None: nothing).
SET_ON_IMPORT = prefer_wide_vectors()
