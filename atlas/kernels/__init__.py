"""Numba kernels: numerical code only (no I/O, no config objects).

Every labelling kernel follows one contract, so backends are interchangeable:

    kernel(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
           attractor, status, n_trap,
           torque=0.0, running_theta0=0.0, running_g=None, running_top=inf) -> None

for θ̈ = −ω0² sin θ − 2αθ̇ + τ (τ = ``torque`` [rad s⁻²]).

* ``theta0``, ``theta_dot0``: float64 1-D arrays of equal length N [rad, rad s⁻¹].
* each orbit is integrated with classical RK4 at step ``dt`` [s]; at steps
  n = 0, c, 2c, …, n_checks·c (c = ``check_every``) the certificates are tested:

  - the *energy trap*: with θ* = arcsin(τ/ω0²) (0 when τ = 0), k = round((θ + θ*)/2π) is
    the well whose strip between its two saddles, −π − θ* ≤ φ < π − θ* (φ = θ − 2πk), holds
    θ, and E_k = ½θ̇² + 2ω0² sin²(φ/2) − ω0²(1 − cos θ*) − τ(φ − θ*) its energy above the
    rest state (θ* + 2πk, 0) (for τ = 0: k = round(θ/2π), E_k = ½θ̇² + 2ω0² sin²(φ/2)).
    The orbit is *trapped* in well k when E_k < ``energy_cap``, the lower saddle's energy
    relative to the well lowered by the safety margin (2ω0²(1 − m) for τ = 0; see
    :func:`atlas.labels.labelling.energy_cap`; −inf when |τ| ≥ ω0²: there is no well);
  - the *running certificate* (only when ``running_g`` is non-empty): with σ = sign(τ)
    (+1 for τ = 0), u = σθ and w = σθ̇, the orbit is *running* when w ≤ ``running_top`` and
    w ≥ ĝ(u), where ĝ is the linear interpolation of the M + 1 samples ``running_g`` on the
    uniform grid u − ``running_theta0`` ∈ [0, 2π] (u reduced mod 2π; ``running_g[M]`` ≥
    ``running_g[0]``). The barrier is thus always given for positive rotation (the τ > 0
    frame, as built for |τ|): the kernel mirrors it (θ → −θ, θ̇ → −θ̇) for τ < 0. That the
    region is forward-invariant, holds the running limit cycle and no rest state, and has
    the margins the numerical orbit needs is the builder's business (``atlas.physics.running``).

  The energy trap is tested first; the orbit's integration stops at the first check where
  either certificate holds.
* outputs (preallocated, length N): ``attractor`` int32 (k, untouched unless trapped),
  ``status`` int8 (0 trapped, 1 unresolved, 2 nonfinite, 4 running), ``n_trap`` int32 (the
  step count n at trapping or at certified running, −1 otherwise).
* τ = 0 without a running barrier runs the kernels of earlier versions, unchanged (the
  tilted kernels are separate specialisations, compiled only when used): labels at τ = 0
  are bit-identical to theirs.
* the return value is not part of the contract (the lane kernels return how many orbits each
  of their paths took, for logging).

Methods (the discretisation, :data:`METHODS`): ``"rk4"`` (the default; classical RK4 on
(θ, θ̇) with a sin per stage, :mod:`atlas.kernels.rk4`; the CUDA kernels' method) and
``"rk4-trigfree"`` (classical RK4 on (θ, θ̇, cos θ, sin θ), :mod:`atlas.kernels.trigfree`).
Both are of order 4; their trajectories differ by O(dt⁴), so labels differ only on
basin-boundary cells.

Checks before any step and after a non-finite state are part of the contract: an initial
condition already inside a trap has n_trap = 0, and a NaN/inf state is reported at the
first check that sees it.

Numba's on-disk cache (:func:`cached_njit`) lives in a folder named by a hash of every
kernel source file here: Numba itself invalidates a cached kernel only when the kernel's own
file changes, but the lane kernels inline code from ``fastsin.py``, ``rk4.py`` and
``trigfree.py``, so an edit there would otherwise keep running stale machine code.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from atlas.status import (  # noqa: F401 (the kernels' status codes, re-exported)
    ATTRACTOR_FILL,
    NEAR_BOUNDARY,
    NONFINITE,
    RUNNING,
    RUNNING_NEAR_BOUNDARY,
    TRAPPED,
    UNRESOLVED,
)

#: Discretisations the CPU kernels offer (a config's ``integrator.method``; the default is
#: :data:`atlas.defaults.METHOD`, "rk4": the CUDA kernels' method too).
METHODS = ("rk4", "rk4-trigfree")


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

    def decorate(func):
        saved = numba.config.CACHE_DIR
        try:
            path = cache_dir()
            path.mkdir(parents=True, exist_ok=True)
            numba.config.CACHE_DIR = str(path)
        except OSError:
            pass
        try:
            return numba.njit(cache=True, **options)(func)
        finally:
            numba.config.CACHE_DIR = saved

    return decorate
