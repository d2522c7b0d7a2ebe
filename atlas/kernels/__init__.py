"""Numba kernels: numerical code only (no I/O, no config objects), one labelling contract.

    kernel(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
           attractor, status, n_trap,
           torque=0.0, running_theta0=0.0, running_g=None, running_top=inf) -> None

integrates each orbit of θ̈ = −ω0² sin θ − 2αθ̇ + τ (θ0 [rad], θ̇0 [rad s⁻¹], dt [s]) with
the method's RK4 step and tests at steps 0, c, 2c, … (c = ``check_every``) the energy trap
(E_k < ``energy_cap`` in the well k of the tilted rest state (θ* + 2πk, 0), θ* = :func:`tilt`)
and then, when ``running_g`` is given, the running barrier; it fills ``attractor`` (k),
``status`` (:mod:`atlas.status`) and ``n_trap`` (the step of the certificate, −1 if none).
Every backend's kernels follow it, so they are interchangeable; τ = 0 without a barrier runs
the kernels of earlier versions unchanged (bit-identical labels). :func:`cached_njit` keys
Numba's on-disk cache by a hash of every kernel source (the lane kernels inline other files).
The full contract, term by term: docs/design/kernels.md#the-kernel-contract.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import weakref
from collections.abc import Callable
from pathlib import Path

from atlas.defaults import METHODS  # noqa: F401 (the discretisations, re-exported)
from atlas.status import (  # noqa: F401 (the kernels' status codes, re-exported)
    ATTRACTOR_FILL,
    NEAR_BOUNDARY,
    NONFINITE,
    RUNNING,
    RUNNING_NEAR_BOUNDARY,
    TRAPPED,
    UNRESOLVED,
)


def tilt(omega0: float, torque: float) -> float:
    """θ* = arcsin(τ/ω0²) [rad] for ω0 [rad s⁻¹] and τ [rad s⁻²]: the angle of the rest state
    of well 0 (0 when τ = 0), by which the wells of the pendulum with torque are tilted.
    Clamped to sign(τ)·π/2 when |τ| ≥ ω0², where the rest state and the saddle would merge
    (there is no well then). The one definition of θ*: the kernels' ``torque_model``, the
    physics (:attr:`atlas.physics.pendulum.Pendulum.rest_angle`) and every other caller use
    it. It lives here, below the physics, because the kernels may import nothing above them;
    :mod:`atlas.physics.pendulum` re-exports it."""
    if torque == 0.0:
        return 0.0  # never −0.0
    return math.asin(min(1.0, max(-1.0, torque / (omega0 * omega0))))


def tilt_versine(shift: float) -> float:
    """1 − cos θ* for the tilt θ* = ``shift`` [rad] (:func:`tilt`), as 2 sin²(θ*/2): no
    cancellation for a small tilt. The one definition the kernels' trap and every caller use."""
    return 2.0 * math.sin(0.5 * shift) ** 2


def uses_torque(torque, running_g) -> bool:
    """Whether a kernel call needs the tilted specialisation: τ ≠ 0 or a running barrier."""
    return torque != 0.0 or (running_g is not None and len(running_g) > 0)


def source_hash() -> str:
    """Digest of the kernel sources (every ``*.py`` of this package)."""
    digest = hashlib.sha256()
    for path in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def cache_dir() -> Path:
    """Where the kernels' machine code is cached: ``<NUMBA_CACHE_DIR>/atlas/<hash>`` if the
    user set NUMBA_CACHE_DIR, else ``~/.cache/atlas/numba/<hash>`` (XDG_CACHE_HOME honoured)."""
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        base = Path(user) / "atlas"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "atlas" / "numba"
    return base / source_hash()


def cached_njit(**options):
    """``numba.njit(cache=True, **options)`` with the cache in :func:`cache_dir` (Numba fixes
    a function's cache folder when it is decorated, so the setting is scoped to that call).
    If the folder cannot be made, Numba's own default place is used."""
    import numba

    import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)

    def decorate(func):
        saved = numba.config.CACHE_DIR
        try:
            path = cache_dir()
            path.mkdir(parents=True, exist_ok=True)
            numba.config.CACHE_DIR = str(path)
        except OSError:
            pass
        try:
            kernel = numba.njit(cache=True, **options)(func)
        finally:
            numba.config.CACHE_DIR = saved
        _CACHED.add(kernel)
        return kernel

    return decorate


#: Every kernel made by :func:`cached_njit`: the ones whose compilation a warm cache spares.
_CACHED = weakref.WeakSet()


@contextlib.contextmanager
def on_cold_compile(callback: Callable[[str], None]):
    """Within the block, call ``callback(name)`` (from whichever thread compiles) each time
    Numba starts compiling one of the kernels of :func:`cached_njit`, named by its Python
    name. Numba compiles such a kernel only where its on-disk cache has no entry for the
    signature, or a stale one (Numba checks the source file's time stamp and size): a warm
    cache only loads machine code and calls nothing. Other jitted functions (inlined helpers
    compiled as part of a kernel, plain ``njit`` functions) are not reported: they are compiled
    in every process, cache or not. Uses Numba's event API (``numba.core.event``,
    the ``"numba:compile"`` event, which Numba raises after a cache miss only)."""
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev):
            kernel = ev.data.get("dispatcher") if ev.data else None
            if kernel is not None and kernel in _CACHED:
                callback(getattr(kernel, "__name__", "kernel"))

        def on_end(self, ev):
            pass

    with event.install_listener("numba:compile", _Listener()):
        yield
