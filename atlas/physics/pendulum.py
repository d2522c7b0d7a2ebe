"""The damped pendulum with constant torque θ̈ = −ω0² sin θ − 2αθ̇ + τ: parameters, energy,
critical points.

With τ = 0 this is the essay's eq. (1); with τ ≠ 0 it is the damped driven pendulum of
Josephson junctions (S. H. Strogatz, *Nonlinear Dynamics and Chaos*, §8.5) and the
single-machine swing equation of power grids (P. J. Menck et al., "How basin stability
complements the linear-stability paradigm", Nature Physics 9, 89–92, 2013).

Units throughout: θ [rad], θ̇ [rad s⁻¹], t [s], α [s⁻¹], ω0 [rad s⁻¹], τ [rad s⁻²].

Tilted wells: for |τ| < ω0² the rest states are (θ* + 2πk, 0) with θ* = arcsin(τ/ω0²)
(:func:`tilt`) and the saddles (π − θ* + 2πk, 0); well k is the strip between its two
saddles, so k = round((θ + θ*)/2π). The linearisation has κ = ω0² cos θ* in place of ω0².
For |τ| ≥ ω0² there is no critical point (|τ| = ω0² is the saddle-node, treated as none).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from atlas.kernels import tilt, tilt_versine

__all__ = ["Pendulum", "CriticalPoint", "critical_points", "rk4_stable", "tilt", "tilt_versine",
           "START_DISTANCE"]

#: Distance [rad, in the (θ, θ̇) plane] from a saddle at which its invariant manifolds are
#: started along their eigenvectors (the stable ones in reversed time by
#: :mod:`atlas.boundaries.manifold` and :mod:`atlas.boundaries.tilted`, the unstable one by
#: :mod:`atlas.physics.running`). The neglected curvature of the manifold there is
#: O(START_DISTANCE²) ≈ 1e-14.
START_DISTANCE = 1e-7


@dataclass(frozen=True)
class Pendulum:
    """Parameters of θ̈ = −ω0² sin θ − 2αθ̇ + τ (essay eq. 1 when τ = 0).

    alpha:  damping constant α ≥ 0 [s⁻¹] (the essay's a/m = 2α).
    omega0: natural angular frequency ω0 > 0 [rad s⁻¹] (ω0² = g/l).
    torque: constant torque per unit moment of inertia τ [rad s⁻²], finite, default 0.
    """

    alpha: float
    omega0: float
    torque: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.alpha) and self.alpha >= 0.0):
            raise ValueError(f"alpha must be a finite number >= 0, got {self.alpha!r}")
        if not (math.isfinite(self.omega0) and self.omega0 > 0.0):
            raise ValueError(f"omega0 must be a finite number > 0, got {self.omega0!r}")
        if not math.isfinite(self.torque):
            raise ValueError(f"torque must be a finite number, got {self.torque!r}")

    # ----------------------------------------------------------------- the tilt
    @property
    def has_rest_states(self) -> bool:
        """Whether there are critical points: |τ| < ω0² (the saddle-node |τ| = ω0² counts
        as none, see the module docstring)."""
        return abs(self.torque) < self.omega0**2

    @property
    def rest_angle(self) -> float:
        """θ* = arcsin(τ/ω0²) [rad], the rest state of well 0 (0 when τ = 0). Raises
        ValueError when |τ| ≥ ω0² (no rest state)."""
        self._require_rest_states()
        return tilt(self.omega0, self.torque)

    @property
    def saddle_angle(self) -> float:
        """π − θ* [rad], the right saddle of well 0 (π when τ = 0); well k's saddles are at
        ±π − θ* + 2πk."""
        return math.pi - self.rest_angle

    @property
    def stiffness(self) -> float:
        """κ = ω0² cos θ* = √(ω0⁴ − τ²) [s⁻²]: the linearised restoring rate at the rest states
        (and, with the opposite sign, at the saddles). ω0² when τ = 0."""
        self._require_rest_states()
        w2 = self.omega0**2
        if self.torque == 0.0:
            return w2
        t = abs(self.torque)
        return math.sqrt((w2 - t) * (w2 + t))

    def _require_rest_states(self) -> None:
        if not self.has_rest_states:
            raise ValueError(f"|torque| = {abs(self.torque):g} >= omega0² = "
                             f"{self.omega0**2:g}: no rest state or saddle exists")

    def well(self, theta):
        """Index k of the well (the strip between two saddles) holding θ:
        k = round((θ + θ*)/2π) (int array or int)."""
        k = np.floor((np.asarray(theta) + self.rest_angle) / (2.0 * np.pi) + 0.5)
        return k.astype(np.int64) if np.ndim(k) else int(k)

    def well_bounds(self, k: int = 0) -> tuple[float, float]:
        """(θ_left, θ_right) [rad]: the saddles −π − θ* + 2πk and π − θ* + 2πk bounding well k."""
        s = self.rest_angle
        return -math.pi - s + 2.0 * math.pi * k, math.pi - s + 2.0 * math.pi * k

    @property
    def regime(self) -> str:
        """'undamped', 'underdamped', 'critically damped' or 'overdamped' (essay §2): α
        against √κ, the rest states' natural frequency (ω0 when τ = 0); 'no rest state' when
        |τ| ≥ ω0²."""
        if not self.has_rest_states:
            return "no rest state"
        if self.alpha == 0.0:
            return "undamped"
        omega = self.omega0 if self.torque == 0.0 else math.sqrt(self.stiffness)
        if self.alpha < omega:
            return "underdamped"
        if self.alpha == omega:
            return "critically damped"
        return "overdamped"

    # ----------------------------------------------------------------- energies
    @property
    def saddle_energies(self) -> tuple[float, float]:
        """(E_left, E_right) [rad² s⁻²]: the energies of the two saddles bounding a well,
        relative to its rest state (:meth:`energy`; the same for every well k):
        E_left = 2κ + τ(π + 2θ*), E_right = 2κ − τ(π − 2θ*). Both 2ω0² when τ = 0."""
        if self.torque == 0.0:
            e = 2.0 * self.omega0**2
            return e, e
        s, kappa, tau = self.rest_angle, self.stiffness, self.torque
        return 2.0 * kappa + tau * (math.pi + 2.0 * s), 2.0 * kappa - tau * (math.pi - 2.0 * s)

    @property
    def saddle_energy(self) -> float:
        """The trap level of every well: the lower of the two :attr:`saddle_energies`
        [rad² s⁻²] (2ω0², the top of every potential well, when τ = 0; the saddle on the side
        the torque pushes towards is the lower one). An orbit in well k with
        :meth:`energy` below it never leaves the well."""
        return min(self.saddle_energies)

    # ----------------------------------------------------------------- the vector field
    def _acceleration(self, sin, theta, theta_dot):
        # the one formula of θ̈ for Python callers; evaluated as (τ − ω0² sin θ) − 2αθ̇ (at
        # τ = 0 that is −ω0² sin θ − 2αθ̇ exactly, up to the sign of a zero)
        return self.torque - self.omega0**2 * sin(theta) - 2.0 * self.alpha * theta_dot

    def acceleration(self, theta, theta_dot):
        """θ̈ [rad s⁻²] = τ − ω0² sin θ − 2αθ̇ (scalars or arrays, numpy's sin)."""
        return self._acceleration(np.sin, theta, theta_dot)

    def field(self, theta, theta_dot):
        """The vector field f = (θ̇, θ̈) [rad s⁻¹, rad s⁻²] (scalars or arrays)."""
        return theta_dot, self.acceleration(theta, theta_dot)

    def rhs(self, _t, y) -> list[float]:
        """f(y) = [θ̇, θ̈] for ``scipy.integrate.solve_ivp`` (y = (θ [rad], θ̇ [rad s⁻¹]),
        one state; t [s] unused: the flow is autonomous). Scalar ``math.sin``, which is
        faster than numpy's on one number and rounds as the C library does."""
        return [y[1], self._acceleration(math.sin, y[0], y[1])]

    def reversed_rhs(self, _t, y) -> list[float]:
        """−f(y) for ``solve_ivp`` in reversed time (the stable manifolds are integrated
        backwards from their saddles): [−θ̇, 2αθ̇ + ω0² sin θ − τ] with ``math.sin``. Summed in
        this order (not as −θ̈), which the exact tilted boundaries of stored files were
        computed with; the two differ by rounding only."""
        return [-y[1], 2.0 * self.alpha * y[1] + self.omega0**2 * math.sin(y[0]) - self.torque]

    def theta_ddot(self, theta: float, theta_dot: float) -> float:
        """θ̈ [rad s⁻²] at one state with ``math.sin`` (as :meth:`rhs`): for right-hand sides
        in other coordinates, e.g. dθ̇/dθ = θ̈/θ̇ along a rotating orbit."""
        return self._acceleration(math.sin, theta, theta_dot)

    def field_jet(self, theta, theta_dot):
        """f and its derivative along the flow, df/dt = J·f (J the Jacobian of f):
        ((θ̇, θ̈), (θ̈, d³θ/dt³)). The velocity and acceleration of an orbit, for its curvature
        κ = |f × J·f| / |f|³; in reversed time the velocity is −f and the acceleration J·f.
        (τ is constant, so d³θ/dt³ = −ω0² cos θ·θ̇ − 2αθ̈ with or without it.)"""
        f0, f1 = self.field(theta, theta_dot)
        return (f0, f1), (f1, -self.omega0**2 * np.cos(theta) * f0 - 2.0 * self.alpha * f1)

    def energy(self, theta, theta_dot, k=0):
        """E_k [rad² s⁻²] per unit ml²: the energy above the rest state (θ* + 2πk, 0) of
        well k, E_k = ½θ̇² + ω0²(cos θ* − cos φ) − τ(φ − θ*) with φ = θ − 2πk. It differs
        from :meth:`total_energy` by a constant for each k, so dE_k/dt = −2αθ̇² ≤ 0: a
        Lyapunov function. When τ = 0 it is ½θ̇² + ω0²(1 − cos φ), evaluated as
        ½θ̇² + 2ω0² sin²(φ/2) (no cancellation near the bottom); with τ ≠ 0 the same form
        ½θ̇² + 2ω0² sin²(φ/2) − ω0²(1 − cos θ*) − τ(φ − θ*). When |τ| ≥ ω0² (no rest state) θ*
        is taken as sign(τ)·π/2, the angle where the two would merge."""
        phi = np.asarray(theta) - 2.0 * np.pi * np.asarray(k)
        base = 0.5 * np.asarray(theta_dot) ** 2 + 2.0 * self.omega0**2 * np.sin(0.5 * phi) ** 2
        if self.torque == 0.0:
            return base
        s = tilt(self.omega0, self.torque)
        vers = tilt_versine(s)
        return base - self.omega0**2 * vers - self.torque * (phi - s)

    def total_energy(self, theta, theta_dot):
        """E = ½θ̇² − ω0² cos θ − τθ [rad² s⁻²]: dE/dt = −2αθ̇² along every orbit."""
        return (0.5 * np.asarray(theta_dot) ** 2 - self.omega0**2 * np.cos(theta)
                - self.torque * np.asarray(theta))

    # ----------------------------------------------------------------- linearisation
    def attractor_eigenvalues(self) -> tuple[complex, complex]:
        """Roots of r² + 2αr + κ = 0 at the rest states (θ* + 2πk, 0) (essay eqs. 3–5,
        22–23, with κ = ω0² when τ = 0): r1, r2. Raises ValueError when |τ| ≥ ω0².

        Written to avoid cancellation: r2 = −α − √(α² − κ) is computed directly and
        r1 = κ/r2 (Vieta), so r1 stays accurate for α ≫ √κ.
        """
        kappa = self.stiffness
        disc = complex(self.alpha**2 - kappa)
        root = np.sqrt(disc)
        r2 = -self.alpha - root
        r1 = kappa / r2 if r2 != 0 else complex(0.0)
        return complex(r1), complex(r2)

    def saddle_eigenvalues(self) -> tuple[float, float]:
        """Roots of r² + 2αr − κ = 0 at the saddles (π − θ* + 2πk, 0) (essay eq. 24 when
        τ = 0): (u1, −u2), u1 > 0 > −u2. Raises ValueError when |τ| ≥ ω0².

        u1 = −α + √(α² + κ) is evaluated as κ/(α + √(α² + κ)) to avoid cancellation.
        """
        kappa = self.stiffness
        if self.torque == 0.0:
            s = math.hypot(self.alpha, self.omega0)
        else:
            s = math.hypot(self.alpha, math.sqrt(kappa))
        return kappa / (self.alpha + s), -(self.alpha + s)

    def saddle_stable_direction(self) -> tuple[float, float]:
        """Unit vector (dθ, dθ̇) of the saddle's stable eigenvector, eigenvalue −u2 < 0.

        For the linearisation θ̈ = κφ − 2αθ̇ about a saddle, an eigenvector of eigenvalue λ is
        (1, λ); normalised so that dθ > 0.
        """
        lam = self.saddle_eigenvalues()[1]
        norm = math.hypot(1.0, lam)
        return 1.0 / norm, lam / norm


@dataclass(frozen=True)
class CriticalPoint:
    """A critical point (nπ + offset, 0) with its linearisation (essay §3, eqs. 22–24).

    n: even n = the rest state of well n/2 (near nπ), odd n = a saddle (near nπ).
    offset: θ − nπ [rad]: +θ* for a rest state, −θ* for a saddle (0 when τ = 0).
    """

    n: int
    kind: str
    eigenvalues: tuple[complex, complex]
    offset: float = 0.0

    @property
    def theta(self) -> float:
        """θ = nπ + offset [rad] (nπ when τ = 0)."""
        if self.offset == 0.0:
            return self.n * math.pi
        return self.n * math.pi + self.offset

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
    """All critical points with θ_min ≤ θ ≤ θ_max (to 1e-12·π), ordered by θ.

    Even n: rest states (2πk + θ*, 0) with k = n/2, kind from the damping regime (focus,
    critical node, node; a center when α = 0). Odd n: saddles (nπ − θ*, 0) with real
    eigenvalues u1 > 0 > −u2. θ* = arcsin(τ/ω0²) (0 when τ = 0: the points (nπ, 0)).
    Empty when |τ| ≥ ω0² (no critical point; the saddle-node |τ| = ω0² counts as none).
    """
    if not pendulum.has_rest_states:
        return []
    attractor = pendulum.attractor_eigenvalues()
    u1, minus_u2 = pendulum.saddle_eigenvalues()
    saddle = (complex(u1), complex(minus_u2))
    shift = pendulum.rest_angle
    lo = theta_min / math.pi - 1e-12
    hi = theta_max / math.pi + 1e-12
    points = []
    for n in range(math.ceil(lo) - 1, math.floor(hi) + 2):
        offset = 0.0 - shift if n % 2 else shift  # 0.0, not −0.0, when τ = 0
        if not lo <= n + offset / math.pi <= hi:
            continue
        if n % 2:
            points.append(CriticalPoint(n, "saddle", saddle, offset))
        else:
            points.append(CriticalPoint(n, _ATTRACTOR_KIND[pendulum.regime], attractor, offset))
    return points


def rk4_stable(pendulum: Pendulum, dt: float) -> bool:
    """Whether RK4 with step ``dt`` [s] is linearly stable at every critical point's decaying
    modes of the *untilted* pendulum: |R(dt·λ)| ≤ 1 with R(z) = 1 + z + z²/2 + z³/6 + z⁴/24
    (Hairer & Wanner, *Solving ODEs II*, §IV.2) for the attractor roots r1, r2 and the
    saddle's stable root −u2 of (α, ω0, τ = 0). Beyond it the integrator itself amplifies
    what the physics damps.

    The torque is ignored on purpose: along any orbit the frozen Jacobian has
    −ω0² cos θ with cos θ ∈ [−1, 1], whose extremes are the untilted saddle (the most negative
    real rate −α − √(α² + ω0²), which bounds every tilted point's) and the untilted attractor,
    so the untilted check covers the tilted critical points and the running orbits alike."""
    if pendulum.torque != 0.0:
        pendulum = dataclasses.replace(pendulum, torque=0.0)
    r1, r2 = pendulum.attractor_eigenvalues()
    stable_saddle = complex(pendulum.saddle_eigenvalues()[1])
    for lam in (r1, r2, stable_saddle):
        z = dt * lam
        if abs(1 + z + z * z / 2 + z**3 / 6 + z**4 / 24) > 1.0 + 1e-12:
            return False
    return True
