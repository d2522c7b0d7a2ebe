"""The damped pendulum θ̈ = −ω0² sin θ − 2αθ̇ (essay eq. 1): parameters, energy, critical points.

Units throughout: θ [rad], θ̇ [rad s⁻¹], t [s], α [s⁻¹], ω0 [rad s⁻¹].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Pendulum", "CriticalPoint", "critical_points", "rk4_stable"]


@dataclass(frozen=True)
class Pendulum:
    """Parameters of θ̈ = −ω0² sin θ − 2αθ̇ (essay eq. 1).

    alpha:  damping constant α ≥ 0 [s⁻¹] (the essay's a/m = 2α).
    omega0: natural angular frequency ω0 > 0 [rad s⁻¹] (ω0² = g/l).
    """

    alpha: float
    omega0: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.alpha) and self.alpha >= 0.0):
            raise ValueError(f"alpha must be a finite number >= 0, got {self.alpha!r}")
        if not (math.isfinite(self.omega0) and self.omega0 > 0.0):
            raise ValueError(f"omega0 must be a finite number > 0, got {self.omega0!r}")

    @property
    def regime(self) -> str:
        """'undamped', 'underdamped', 'critically damped' or 'overdamped' (essay §2)."""
        if self.alpha == 0.0:
            return "undamped"
        if self.alpha < self.omega0:
            return "underdamped"
        if self.alpha == self.omega0:
            return "critically damped"
        return "overdamped"

    @property
    def saddle_energy(self) -> float:
        """E at the saddles ((2j+1)π, 0): 2ω0² [rad² s⁻²], the top of every potential well."""
        return 2.0 * self.omega0**2

    def acceleration(self, theta, theta_dot):
        """θ̈ [rad s⁻²] from eq. (1)."""
        return -self.omega0**2 * np.sin(theta) - 2.0 * self.alpha * theta_dot

    def field(self, theta, theta_dot):
        """The vector field f = (θ̇, θ̈) of eq. (1) [rad s⁻¹, rad s⁻²] (scalars or arrays)."""
        return theta_dot, self.acceleration(theta, theta_dot)

    def field_jet(self, theta, theta_dot):
        """f and its derivative along the flow, df/dt = J·f (J the Jacobian of f):
        ((θ̇, θ̈), (θ̈, d³θ/dt³)). The velocity and acceleration of an orbit, for its curvature
        κ = |f × J·f| / |f|³; in reversed time the velocity is −f and the acceleration J·f."""
        f0, f1 = self.field(theta, theta_dot)
        return (f0, f1), (f1, -self.omega0**2 * np.cos(theta) * f0 - 2.0 * self.alpha * f1)

    def energy(self, theta, theta_dot, k=0):
        """E_k = ½θ̇² + ω0²(1 − cos(θ − 2πk)) [rad² s⁻²] per unit ml²: the energy above the
        bottom of well k. dE/dt = −2αθ̇² ≤ 0, so E is a Lyapunov function."""
        phi = np.asarray(theta) - 2.0 * np.pi * np.asarray(k)
        return 0.5 * np.asarray(theta_dot) ** 2 + 2.0 * self.omega0**2 * np.sin(0.5 * phi) ** 2

    def attractor_eigenvalues(self) -> tuple[complex, complex]:
        """Roots of r² + 2αr + ω0² = 0 at (2πk, 0) (essay eqs. 3–5, 22–23): r1, r2.

        Written to avoid cancellation: r2 = −α − √(α² − ω0²) is computed directly and
        r1 = ω0²/r2 (Vieta), so r1 stays accurate for α ≫ ω0.
        """
        disc = complex(self.alpha**2 - self.omega0**2)
        root = np.sqrt(disc)
        r2 = -self.alpha - root
        r1 = self.omega0**2 / r2 if r2 != 0 else complex(0.0)
        return complex(r1), complex(r2)

    def saddle_eigenvalues(self) -> tuple[float, float]:
        """Roots of r² + 2αr − ω0² = 0 at ((2j+1)π, 0) (essay eq. 24): (u1, −u2), u1 > 0 > −u2.

        u1 = −α + √(α² + ω0²) is evaluated as ω0²/(α + √(α² + ω0²)) to avoid cancellation.
        """
        s = math.hypot(self.alpha, self.omega0)
        return self.omega0**2 / (self.alpha + s), -(self.alpha + s)

    def saddle_stable_direction(self) -> tuple[float, float]:
        """Unit vector (dθ, dθ̇) of the saddle's stable eigenvector, eigenvalue −u2 < 0.

        For the linearisation θ̈ = ω0²φ − 2αθ̇ about a saddle, an eigenvector of eigenvalue λ is
        (1, λ); normalised so that dθ > 0.
        """
        lam = self.saddle_eigenvalues()[1]
        norm = math.hypot(1.0, lam)
        return 1.0 / norm, lam / norm


@dataclass(frozen=True)
class CriticalPoint:
    """A rest state (nπ, 0) of eq. (1) with its linearisation (essay §3, eqs. 22–24)."""

    n: int
    kind: str
    eigenvalues: tuple[complex, complex]

    @property
    def theta(self) -> float:
        """θ = nπ [rad]."""
        return self.n * math.pi

    @property
    def is_saddle(self) -> bool:
        return self.n % 2 != 0


_ATTRACTOR_KIND = {
    "undamped": "center",
    "underdamped": "attractor focus",
    "critically damped": "attractor critical node",
    "overdamped": "attractor node",
}


def critical_points(pendulum: Pendulum, theta_min: float, theta_max: float) -> list[CriticalPoint]:
    """All critical points (nπ, 0) with θ_min ≤ nπ ≤ θ_max, ordered by θ.

    Even n: attractors (2πk, 0) with k = n/2, kind from the damping regime (focus, critical
    node, node; a center when α = 0). Odd n: saddles with real eigenvalues u1 > 0 > −u2.
    """
    attractor = pendulum.attractor_eigenvalues()
    u1, minus_u2 = pendulum.saddle_eigenvalues()
    saddle = (complex(u1), complex(minus_u2))
    n_lo = math.ceil(theta_min / math.pi - 1e-12)
    n_hi = math.floor(theta_max / math.pi + 1e-12)
    points = []
    for n in range(n_lo, n_hi + 1):
        if n % 2:
            points.append(CriticalPoint(n, "saddle", saddle))
        else:
            points.append(CriticalPoint(n, _ATTRACTOR_KIND[pendulum.regime], attractor))
    return points


def rk4_stable(pendulum: Pendulum, dt: float) -> bool:
    """Whether RK4 with step ``dt`` [s] is linearly stable at every critical point's decaying
    modes: |R(dt·λ)| ≤ 1 with R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (Hairer & Wanner, *Solving
    ODEs II*, §IV.2) for the attractor roots r1, r2 and the saddle's stable root −u2.
    Beyond it the integrator itself amplifies what the physics damps."""
    r1, r2 = pendulum.attractor_eigenvalues()
    stable_saddle = complex(pendulum.saddle_eigenvalues()[1])
    for lam in (r1, r2, stable_saddle):
        z = dt * lam
        if abs(1 + z + z * z / 2 + z**3 / 6 + z**4 / 24) > 1.0 + 1e-12:
            return False
    return True
