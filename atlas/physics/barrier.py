"""The running barrier: the data of the running certificate, as the kernels test it.

A :class:`RunningBarrier` is a band {ĝ(u) ≤ w ≤ top} of the cylinder around the running limit
cycle of θ̈ = −ω0² sin θ − 2αθ̇ + τ, given in the frame of positive rotation (u = σθ,
w = σθ̇, σ = sign(τ)) by M + 1 samples of its lower curve. Here are its data and the checks of
their shape (finite, ĝ ends at or above its start, top above ĝ); that the band is
forward-invariant, holds the cycle and no rest state is proved by its builder,
:func:`atlas.physics.running.running_barrier`, which returns a subclass recording the
verification. The kernels' membership test is the contract of :mod:`atlas.kernels`;
:func:`atlas.label` takes a barrier as ``running``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["RunningBarrier"]


@dataclass(frozen=True)
class RunningBarrier:
    """The running certificate a kernel tests (contract in :mod:`atlas.kernels`), built by
    :mod:`atlas.physics.running` for θ̈ = −ω0² sin θ − 2αθ̇ + τ.

    It is given in the frame of positive rotation (the τ > 0 pendulum of torque |τ|): a
    state (θ, θ̇) is certified running when, with u = σθ, w = σθ̇ and σ = ``direction``,
    w ≤ ``top`` and w ≥ ĝ(u), ĝ the linear interpolation of ``g`` (float64, M + 1 ≥ 2
    samples on the uniform grid u ∈ [theta0, theta0 + 2π], u reduced mod 2π). The kernels
    mirror it for τ < 0 themselves (σ = sign(τ)); :func:`atlas.label` checks that
    ``direction`` is sign(τ).

    theta0:    start of the barrier's period [rad].
    g:         the lower barrier θ̇ = ĝ(θ) [rad s⁻¹], M + 1 finite samples, g[M] ≥ g[0] (the
               region does not shrink across the seam θ0 + 2π ≡ θ0).
    top:       the upper level [rad s⁻¹], finite and above every g (e.g. (|τ| + ω0²)/2α,
               above which θ̇ decreases).
    direction: +1 or −1, the direction of rotation (sign of τ).

    The builder guarantees that the region {ĝ(u) ≤ w ≤ top} is forward-invariant for the
    exact flow (with the margins the RK4 orbit needs), holds the limit cycle and no rest
    state; the kernels only test membership.
    """

    theta0: float
    g: np.ndarray
    top: float
    direction: int

    def __post_init__(self) -> None:
        g = np.array(self.g, dtype=np.float64, copy=True)
        if g.ndim != 1 or g.size < 2:
            raise ValueError(f"RunningBarrier.g must be 1-D with at least 2 samples, got "
                             f"shape {g.shape}")
        if not np.all(np.isfinite(g)):
            raise ValueError("RunningBarrier.g must be finite")
        if not g[-1] >= g[0]:
            raise ValueError(f"RunningBarrier.g must end at or above its start (g[M] = "
                             f"{g[-1]!r} < g[0] = {g[0]!r})")
        for name in ("theta0", "top"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"RunningBarrier.{name} must be finite, got "
                                 f"{getattr(self, name)!r}")
        if not self.top > g.max():
            raise ValueError(f"RunningBarrier.top = {self.top!r} must lie above every g "
                             f"(max {g.max()!r})")
        if self.direction not in (1, -1):
            raise ValueError(f"RunningBarrier.direction must be +1 or -1, got "
                             f"{self.direction!r}")
        g.flags.writeable = False
        object.__setattr__(self, "g", g)
        object.__setattr__(self, "theta0", float(self.theta0))
        object.__setattr__(self, "top", float(self.top))
        object.__setattr__(self, "direction", int(self.direction))

    def kernel_args(self) -> tuple[float, np.ndarray, float]:
        """(running_theta0, running_g, running_top) of the kernel contract."""
        return self.theta0, self.g, self.top
