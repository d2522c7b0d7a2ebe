"""The SIMD width of the lane kernels: 512-bit vectors on a CPU with AVX-512.

LLVM tunes recent Intel server cores (Skylake-SP to Emerald Rapids) with "prefer-256-bit": its
loop vectoriser then stops at 256-bit vectors (4 doubles) although the core has 512-bit ones
(8 doubles), to spare the lower clock that heavy 512-bit code may run at. The lane loops of
:mod:`atlas.kernels.lanes` and :mod:`atlas.kernels.driven` are long runs of fused
multiply-adds on 32 independent orbits, where 512-bit vectors win: measured on a 2-core Emerald
Rapids machine, the bulk RK4 lanes went from 282 to 419 M steps/s and the driven pendulum's map
from 255 to 383 M steps/s (``atlas bench`` measures it on your machine). The width changes no
bit of any result: each lane's arithmetic is the same IR, in the same order (the kernels'
fast-math flags exclude reassociation), only more lanes go through one instruction
(tests/kernels/test_vector_width.py compares them).

:func:`prefer_wide_vectors` drops the tuning flag from the CPU features Numba compiles for.
It must run before Numba creates its CPU target (at the first ``njit`` of the process):
``atlas.kernels`` calls it on import, before any kernel module. It leaves alone a process
whose Numba target exists already, a user's own ``NUMBA_CPU_NAME`` / ``NUMBA_CPU_FEATURES``,
and any CPU without AVX-512 (where the flag does not exist). ``ATLAS_VECTOR_BITS=256`` keeps
LLVM's choice. Numba's cache keys its machine code by the feature string, so the two widths
never share a cached kernel.
"""

from __future__ import annotations

import os
import sys

__all__ = ["prefer_wide_vectors", "TUNING", "WIDE"]

#: LLVM's subtarget tuning that caps the loop vectoriser at 256 bits.
TUNING = "prefer-256-bit"
#: ``ATLAS_VECTOR_BITS`` value that asks for the wide vectors (the default).
WIDE = "512"


def _host_features() -> str:
    """The host CPU's feature string as Numba would compile for it (LLVM's, flattened)."""
    import llvmlite.binding as ll

    try:
        return ll.get_host_cpu_features().flatten()
    except RuntimeError:  # LLVM cannot read this CPU's features
        return ""


def prefer_wide_vectors() -> str | None:
    """Let LLVM vectorise at 512 bits where the CPU has AVX-512: set Numba's CPU features to
    the host's without the 256-bit preference (the environment variable
    ``NUMBA_CPU_FEATURES`` before Numba is imported, ``numba.config.CPU_FEATURES`` after).
    Returns the features set, or None where nothing was changed (see the module docstring)."""
    if os.environ.get("ATLAS_VECTOR_BITS", WIDE) != WIDE:
        return None
    if os.environ.get("NUMBA_CPU_NAME") or os.environ.get("NUMBA_CPU_FEATURES"):
        return None
    numba = sys.modules.get("numba")
    if numba is not None and _target_exists(numba):
        return None
    features = _host_features()
    if "+avx512f" not in features.split(","):
        return None
    wide = f"{features},-{TUNING}"
    os.environ["NUMBA_CPU_FEATURES"] = wide  # read when numba is imported; child processes too
    if numba is not None:
        from numba.core import config

        config.CPU_FEATURES = wide
    return wide


def _target_exists(numba) -> bool:
    """Whether Numba's CPU target context (and with it the features it compiles for) has
    been made in this process already."""
    try:
        from numba.core.registry import cpu_target
    except ImportError:
        return True
    # a cached property: in the instance's __dict__ once made (getattr would make it)
    return "_toplevel_target_context" in vars(cpu_target)
