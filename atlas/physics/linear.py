"""Closed-form motion of the linearised pendulum (essay §2 and §3, eqs. 2–19 and 25–26).

Near an attractor (2πk, 0), with θ measured from 2πk, the linearisation of eq. (1) is

    θ̈ + 2αθ̇ + ω0²θ = 0                                          (essay eq. 2)

and near a saddle ((2j+1)π, 0), with φ = θ − (2j+1)π,

    φ̈ + 2αφ̇ − ω0²φ = 0                                          (essay §3, eqs. 22, 24)

Units throughout: θ, φ [rad], θ̇ [rad s⁻¹], t [s], α [s⁻¹], ω0 [rad s⁻¹].

The essay's errata in eqs. (7), (10), §3 and (26), and the quadrant of Φ, are corrected here
(:func:`amplitude_phase` uses atan2): docs/design/essay-errata.md lists them.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.physics.pendulum import Pendulum

__all__ = ["solve", "amplitude_phase", "solve_saddle"]

#: |(α² − ω0²) t²| up to which C(t) and S(t)/t are summed as Taylor series (nine terms:
#: truncation error < 5e-19), so that they pass continuously through critical damping.
_SERIES_MAX = 1.0
_SERIES_TERMS = 9


def _pendulum(alpha, omega0) -> Pendulum:
    """Validated parameters (ValueError unless α ≥ 0 and ω0 > 0 are finite numbers)."""
    return Pendulum(float(alpha), float(omega0))


def _series(y, t):
    """C = Σ yᵏ/(2k)! and S = t·Σ yᵏ/(2k+1)! for y = (α² − ω0²)t², |y| ≤ _SERIES_MAX (Horner).

    One series covers both sides of critical damping: y < 0 gives cos(ωt) and sin(ωt)/ω,
    y > 0 gives cosh(ωt) and sinh(ωt)/ω, and y = 0 gives 1 and t (essay eq. 11).
    """
    c = s = 1.0
    for k in range(_SERIES_TERMS, 0, -1):
        c = 1.0 + c * y / ((2 * k - 1) * (2 * k))
        s = 1.0 + s * y / ((2 * k) * (2 * k + 1))
    return c, t * s


def _eigenmodes(x0, v0, t, r1, r2, gap):
    """x = B e^{r1 t} + C e^{r2 t}, ẋ = B r1 e^{r1 t} + C r2 e^{r2 t} from x(0) = x0, ẋ(0) = v0,
    for distinct real roots r1 > r2 of a characteristic equation, gap = r1 − r2 > 0 passed in
    (computed without cancellation by the caller): B = (v0 − r2 x0)/gap, C = (r1 x0 − v0)/gap.

    Keeps the two modes apart, so an initial condition on one eigendirection (v0 = r x0)
    gives the other coefficient exactly 0 and follows its own exponential to a few ulp.
    """
    b = (v0 - r2 * x0) / gap
    c = (r1 * x0 - v0) / gap
    e1, e2 = np.exp(r1 * t), np.exp(r2 * t)
    return b * e1 + c * e2, b * r1 * e1 + c * r2 * e2


def solve(theta0, theta_dot0, t, *, alpha, omega0):
    """Closed-form solution of θ̈ + 2αθ̇ + ω0²θ = 0 (essay eq. 2), every damping regime.

    Parameters
    ----------
    theta0, theta_dot0 : float or array
        Initial angle θ0 [rad] (from the attractor) and angular velocity θ̇0 [rad s⁻¹] at t = 0.
    t : float or array
        Times [s]; any real value (negative t runs the motion backwards).
    alpha, omega0 : float
        Damping constant α ≥ 0 [s⁻¹] and natural frequency ω0 > 0 [rad s⁻¹].

    Returns
    -------
    (theta, theta_dot) : arrays of shape ``np.broadcast_shapes(θ0, θ̇0, t)``
        θ(t) [rad] and θ̇(t) [rad s⁻¹]. Scalar θ0, θ̇0 with a 1-D ``t`` give one orbit over t;
        ``theta0[:, None]`` with ``t[None, :]`` gives one row per orbit.

    Method
    ------
    With ω² = |ω0² − α²|, formed as |(α − ω0)(α + ω0)| so that it keeps full relative accuracy
    near α = ω0, and C = cos(ωt), S = sin(ωt)/ω (underdamped) or C = cosh(ωt), S = sinh(ωt)/ω
    (overdamped),

        θ(t) = e^{−αt}[θ0 C(t) + (θ̇0 + αθ0) S(t)]
        θ̇(t) = e^{−αt}[θ̇0 C(t) − (ω0²θ0 + αθ̇0) S(t)]   (differentiated analytically, using
                                                          Ċ = ∓ω²S, Ṡ = C).

    Where |ω t| ≤ 1, C and S/t are summed as one Taylor series in (α² − ω0²)t², which is the
    same on both sides of α = ω0 and equals the essay's critically damped form
    e^{−αt}(B + Ct), B = θ0, C = θ̇0 + αθ0 (§2.2, eqs. 11–12) at α = ω0: so the solution is
    continuous and accurate as α → ω0 from either side. Beyond that, underdamped motion uses
    cos/sin — the essay's A e^{−αt} sin(ωt + Φ) (§2.1, eq. 8; see :func:`amplitude_phase`) —
    and overdamped motion the eigenmodes B e^{r1 t} + C e^{r2 t} (§2.3, eqs. 18–19, with
    e^{−αt}e^{±ωt} combined so that cosh/sinh never overflow), r1 = −α + ω evaluated as
    −ω0²/(α + ω) and r2 = −α − ω. There ωt > 1, so the coefficients B, C ∝ 1/ω, which cancel
    catastrophically in the essay's form as ω → 0, cost at most a few ulp. α = 0 is simple
    harmonic motion.

    Accuracy: θ(0) = θ0 and θ̇(0) = θ̇0 exactly; elsewhere a few ulp of the orbit's size
    (|θ0| + |θ̇0|/ω0 times its decay), uniformly in α, including α within rounding of ω0; for
    large ωt the cos/sin phase adds ulp·ωt.
    """
    p = _pendulum(alpha, omega0)
    alpha, omega0 = p.alpha, p.omega0
    theta0, theta_dot0, t = (np.asarray(x, dtype=float) for x in (theta0, theta_dot0, t))
    d = (alpha - omega0) * (alpha + omega0)  # α² − ω0², signed
    omega = math.sqrt(abs(d))
    y = d * t * t
    near = np.abs(y) <= _SERIES_MAX
    # Overdamped, the eigenmodes serve where not near: evaluate the basis there at t = 0 only.
    t_basis = np.where(near, t, 0.0) if d > 0.0 else t
    c, s = _series(np.where(near, y, 0.0), t_basis)
    if d < 0.0:
        c = np.where(near, c, np.cos(omega * t))
        s = np.where(near, s, np.sin(omega * t) / omega)
    decay = np.exp(-alpha * t_basis)
    theta = decay * (theta0 * c + (theta_dot0 + alpha * theta0) * s)
    theta_dot = decay * (theta_dot0 * c - (omega0**2 * theta0 + alpha * theta_dot0) * s)
    if d > 0.0 and not near.all():
        r1 = -(omega0**2) / (alpha + omega)
        far = _eigenmodes(theta0, theta_dot0, t, r1, -(alpha + omega), 2.0 * omega)
        theta, theta_dot = np.where(near, theta, far[0]), np.where(near, theta_dot, far[1])
    return theta, theta_dot


def amplitude_phase(theta0, theta_dot0, alpha, omega0):
    """Amplitude A ≥ 0 [rad] and phase Φ ∈ (−π, π] [rad] of underdamped motion (essay §2.1).

    θ(t) = A e^{−αt} sin(ωt + Φ) and θ̇(t) = A e^{−αt}[ω cos(ωt + Φ) − α sin(ωt + Φ)]
    (eq. 8; eq. 7 drops ω and α), with ω = √(ω0² − α²), requires 0 ≤ α < ω0.

    At t = 0 these give θ0 = A sin Φ (eq. 9) and θ̇0 = A[ω cos Φ − α sin Φ] (eq. 10, which the
    essay misprints as θ(0)), i.e. A cos Φ = (θ̇0 + αθ0)/ω. Hence
    A = hypot(θ0, (θ̇0 + αθ0)/ω) and Φ = atan2(θ0, (θ̇0 + αθ0)/ω): unlike the essay's
    Φ = cot⁻¹[(θ̇0/θ0 + α)/ω], valid for θ0 = 0 and in every quadrant. Accurate to a few ulp.
    ``theta0`` and ``theta_dot0`` broadcast; ValueError unless 0 ≤ α < ω0.
    """
    p = _pendulum(alpha, omega0)
    if p.alpha >= p.omega0:
        raise ValueError(
            f"amplitude_phase needs underdamped motion (alpha < omega0); "
            f"got alpha={p.alpha!r}, omega0={p.omega0!r}"
        )
    omega = np.sqrt((p.omega0 - p.alpha) * (p.omega0 + p.alpha))
    theta0 = np.asarray(theta0, dtype=float)
    cos_part = (np.asarray(theta_dot0, dtype=float) + p.alpha * theta0) / omega
    return np.hypot(theta0, cos_part), np.arctan2(theta0, cos_part)


def solve_saddle(phi0, theta_dot0, t, *, alpha, omega0):
    """Linearised motion near a saddle ((2j+1)π, 0) (essay §3, eqs. 25–26 corrected).

    Solves φ̈ + 2αφ̇ − ω0²φ = 0 for φ = θ − (2j+1)π [rad] from φ(0) = φ0 [rad],
    θ̇(0) = θ̇0 [rad s⁻¹]:

        φ(t) = B e^{u1 t} + C e^{−u2 t}                 (eq. 25)
        θ̇(t) = B u1 e^{u1 t} − C u2 e^{−u2 t}           (eq. 26; the essay writes e^{+u2 t})

    with u1 = −α + √(α² + ω0²) > 0 and −u2 = −α − √(α² + ω0²) < 0 from
    :meth:`Pendulum.saddle_eigenvalues` (§3 misprints "r2 = … = 0"), and
    B = (θ̇0 + u2φ0)/(u1 + u2), C = (u1φ0 − θ̇0)/(u1 + u2).

    The roots never meet (u1 + u2 ≥ 2ω0), so this form is well conditioned for every α, and it
    keeps the modes apart: an initial condition on the stable eigendirection, θ̇0 = −u2φ0,
    gives B = 0 exactly and decays as φ0 e^{−u2 t} with no trace of the unstable mode.
    Accuracy: a few ulp of |B|e^{u1 t} + |C|e^{−u2 t}.

    Shapes and units as :func:`solve`: arrays of shape ``np.broadcast_shapes(φ0, θ̇0, t)``,
    t [s] any real, α ≥ 0 [s⁻¹], ω0 > 0 [rad s⁻¹]; returns (φ, θ̇).
    """
    u1, minus_u2 = _pendulum(alpha, omega0).saddle_eigenvalues()
    phi0, theta_dot0, t = (np.asarray(x, dtype=float) for x in (phi0, theta_dot0, t))
    return _eigenmodes(phi0, theta_dot0, t, u1, minus_u2, u1 - minus_u2)
