"""atlas.physics.linear: the closed forms of essay §2–3 against independent references.

References: scipy's DOP853 at rtol = atol = 1e-13 on the linear ODEs; the ODE residual with θ̈
from a centered difference of θ̇; the essay's own critically damped form (eqs. 11–12), which
has no cancellation; and the underdamped amplitude–phase form (eqs. 8–10, corrected).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from atlas import linear
from atlas.physics.pendulum import Pendulum

EPS = np.finfo(float).eps

# (alpha, omega0): undamped, underdamped (essay Figs. 1 and 10), critical, overdamped, strongly
# overdamped (r2/r1 ≈ 1600: the essay's B, C form is fine here, cosh(ωt) alone is not).
REGIMES = {
    "undamped": (0.0, 1.0),
    "underdamped": (0.4, 2.0),
    "underdamped-weak": (0.1, 1.0),
    "critical": (1.5, 1.5),
    "overdamped": (3.0, 1.0),
    "overdamped-strong": (20.0, 1.0),
}
INITIAL = [(0.5, 0.0), (0.0, 1.0), (-1.0, 2.5), (1.0, -3.0)]


def scale(theta0, theta_dot0, omega0):
    """The size of an orbit's state, for absolute tolerances [rad]."""
    return abs(theta0) + abs(theta_dot0) / omega0


def dop853(stiffness, alpha, y0, t):
    """y'' + 2α y' + stiffness·y = 0 integrated from t[0] by DOP853.

    rtol = atol = 1e-13: at 1e-12 DOP853's dense output (t_eval) is itself off by up to 2e-9
    (overdamped, α = 3), which would blur a 1e-9 comparison.
    """

    def rhs(_, y):
        return [y[1], -2.0 * alpha * y[1] - stiffness * y[0]]

    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=1e-13, atol=1e-13)
    assert sol.success
    return sol.y


@pytest.mark.parametrize("ic", INITIAL)
@pytest.mark.parametrize("regime", REGIMES)
def test_solve_matches_dop853(regime, ic):
    alpha, omega0 = REGIMES[regime]
    t = np.linspace(0.0, 20.0 / omega0, 201)
    theta, theta_dot = linear.solve(*ic, t, alpha=alpha, omega0=omega0)
    ref = dop853(omega0**2, alpha, list(ic), t)
    tol = 1e-9 * scale(*ic, omega0)
    np.testing.assert_allclose(theta, ref[0], rtol=0, atol=tol)
    np.testing.assert_allclose(theta_dot, ref[1], rtol=0, atol=tol * omega0)


@pytest.mark.parametrize("ic", INITIAL)
@pytest.mark.parametrize("regime", REGIMES)
def test_solve_satisfies_the_ode(regime, ic):
    """θ̈ + 2αθ̇ + ω0²θ = 0 with θ̈ from a centered difference of the analytic θ̇, and θ̇
    consistent with a centered difference of θ (θ̇ is derived, not differenced)."""
    alpha, omega0 = REGIMES[regime]
    t = np.linspace(0.0, 20.0 / omega0, 101)
    h = 1e-4 / max(omega0, alpha)
    theta, theta_dot = linear.solve(*ic, t, alpha=alpha, omega0=omega0)
    theta_p, theta_dot_p = linear.solve(*ic, t + h, alpha=alpha, omega0=omega0)
    theta_m, theta_dot_m = linear.solve(*ic, t - h, alpha=alpha, omega0=omega0)
    theta_ddot = (theta_dot_p - theta_dot_m) / (2.0 * h)
    rate = max(omega0, 2.0 * alpha) ** 2  # the size of θ̈ per unit of θ
    tol = 1e-6 * rate * scale(*ic, omega0)
    np.testing.assert_allclose(theta_ddot + 2 * alpha * theta_dot + omega0**2 * theta, 0, atol=tol)
    np.testing.assert_allclose((theta_p - theta_m) / (2.0 * h), theta_dot, atol=tol / omega0)


@pytest.mark.parametrize(
    "alpha", [0.0, 0.3, 1.0 - 1e-12, 1.0, 1.0 + 1e-12, 1.0 + 1e-4, 7.0, 1e4], ids=str
)
def test_initial_conditions_reproduced_exactly(alpha):
    rng = np.random.default_rng(1)
    theta0, theta_dot0 = rng.normal(size=(2, 50)) * 10.0 ** rng.integers(-8, 4, size=(2, 50))
    theta, theta_dot = linear.solve(theta0, theta_dot0, 0.0, alpha=alpha, omega0=1.0)
    np.testing.assert_array_equal(theta, theta0)
    np.testing.assert_array_equal(theta_dot, theta_dot0)


def essay_critical(theta0, theta_dot0, t, alpha):
    """Essay eqs. (11)–(12): θ = e^{−αt}(B + Ct), θ̇ = e^{−αt}[C − α(B + Ct)]."""
    b, c = theta0, theta_dot0 + alpha * theta0
    return np.exp(-alpha * t) * (b + c * t), np.exp(-alpha * t) * (c - alpha * (b + c * t))


@pytest.mark.parametrize("omega0", [1.0, 2.5])
@pytest.mark.parametrize("ic", INITIAL)
def test_continuous_through_critical_damping(ic, omega0):
    """At α = ω0(1 − ε), ω0, ω0(1 + ε), ε ∈ {1e-4, 1e-8, 1e-12}, over 0 ≤ t ≤ 20/ω0.

    The exact solution is a smooth function of α, so (i) each side agrees with critical damping
    to O(ε) — to ~1e-11 of the orbit's size at ε = 1e-12, where the essay's overdamped B, C
    (∝ 1/ω ≈ 1e6) would lose ~1e-10 to cancellation; (ii) the mean of the two sides agrees
    with it to O(ε²), so the regime switch leaves no jump or kink; and (iii) the central
    difference quotient ∂(θ, θ̇)/∂α is the same at every ε.
    """
    t = np.linspace(0.0, 20.0 / omega0, 401)
    size = scale(*ic, omega0)
    crit = np.array(linear.solve(*ic, t, alpha=omega0, omega0=omega0))
    essay = essay_critical(*ic, t, omega0)
    np.testing.assert_allclose(crit, essay, rtol=0, atol=4 * EPS * size * omega0)
    quotients = []
    for eps in (1e-4, 1e-8, 1e-12):
        above = np.array(linear.solve(*ic, t, alpha=omega0 * (1 + eps), omega0=omega0))
        below = np.array(linear.solve(*ic, t, alpha=omega0 * (1 - eps), omega0=omega0))
        roundoff = 8 * EPS * size * omega0
        for side in (above, below):
            np.testing.assert_allclose(side, crit, rtol=0, atol=5 * eps * size * omega0 + roundoff)
        mean = 0.5 * (above + below)
        np.testing.assert_allclose(mean, crit, rtol=0, atol=5 * eps**2 * size * omega0 + roundoff)
        quotients.append((above - below) / (2 * eps * omega0))
    for q in quotients[1:]:
        np.testing.assert_allclose(q, quotients[0], rtol=0, atol=1e-3 * size)


def test_strongly_overdamped_long_times_do_not_overflow():
    """α ≫ ω0 and ωt ≈ 4e5: cosh(ωt) overflows, e^{−αt}cosh(ωt) must not. Reference: the essay's
    eigenmode form B e^{r1 t} + C e^{r2 t} (eqs. 18–19), well conditioned for ω ≫ 0."""
    alpha, omega0 = 400.0, 1.0
    theta0, theta_dot0 = 0.3, -2.0
    t = np.linspace(0.0, 1000.0, 101)
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        theta, theta_dot = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=omega0)
    r2, r1 = Pendulum(alpha, omega0).attractor_eigenvalues()[::-1]
    r1, r2 = r1.real, r2.real
    b = (theta_dot0 - r2 * theta0) / (r1 - r2)
    c = (r1 * theta0 - theta_dot0) / (r1 - r2)
    modes = np.exp(np.outer([r1, r2], t))
    np.testing.assert_allclose(theta, b * modes[0] + c * modes[1], rtol=1e-13)
    np.testing.assert_allclose(theta_dot, b * r1 * modes[0] + c * r2 * modes[1], rtol=1e-13)


@pytest.mark.parametrize("alpha", [1.0 + 1e-4, 1.25, 3.0, 400.0])
def test_overdamped_eigendirections(alpha):
    """On an eigendirection θ̇0 = r θ0 the motion is the single mode θ0 e^{rt}: the fast mode
    shows no trace of the slow one (where ωt > 1), and the slow mode decays at its own rate."""
    r2 = -alpha - np.sqrt((alpha - 1.0) * (alpha + 1.0))  # roots of r² + 2αr + 1, to an ulp
    r1 = 1.0 / r2
    t = np.linspace(0.0, 50.0 / (alpha - r1), 201)
    near = (alpha**2 - 1.0) * t**2 <= 1.0  # the series basis, exact only up to ulp of θ0
    for r in (r1, r2):
        theta, theta_dot = linear.solve(0.2, r * 0.2, t, alpha=alpha, omega0=1.0)
        expected = 0.2 * np.exp(r * t)
        assert np.all(np.abs(theta - expected) <= 1e-13 * expected + 4 * EPS * 0.2 * near)
        assert np.all(
            np.abs(theta_dot - r * expected)
            <= 1e-13 * abs(r) * expected + 4 * EPS * alpha * 0.2 * near
        )


def test_broadcast_shapes():
    theta0 = np.array([[0.5], [-1.0], [0.0]])
    t = np.linspace(0.0, 5.0, 7)
    theta, theta_dot = linear.solve(theta0, 1.0, t, alpha=0.2, omega0=1.0)
    assert theta.shape == theta_dot.shape == (3, 7)
    for row, th0 in enumerate(theta0[:, 0]):
        one = linear.solve(th0, 1.0, t, alpha=0.2, omega0=1.0)
        np.testing.assert_array_equal(theta[row], one[0])
        np.testing.assert_array_equal(theta_dot[row], one[1])


# The essay's Φ = cot⁻¹[(θ̇0/θ0 + α)/ω] divides by θ0 = 0 and fixes Φ only modulo π.
AWKWARD = [(0.0, 1.0), (0.0, -1.0), (-0.5, 2.0), (0.5, -2.0), (-0.5, -2.0), (1e-3, 1e3), (0.0, 0.0)]


@pytest.mark.parametrize("alpha, omega0", [(0.4, 2.0), (0.0, 1.0), (0.999, 1.0)])
@pytest.mark.parametrize("theta0, theta_dot0", AWKWARD)
def test_amplitude_phase(theta0, theta_dot0, alpha, omega0):
    """A ≥ 0 and Φ reconstruct the initial conditions via eqs. (9)–(10 corrected), and the
    amplitude–phase form (eq. 8) is the orbit that solve() returns."""
    a, phi = linear.amplitude_phase(theta0, theta_dot0, alpha, omega0)
    omega = np.sqrt(omega0**2 - alpha**2)
    size = scale(theta0, theta_dot0, omega)
    assert a >= 0.0 and -np.pi < phi <= np.pi
    assert abs(a * np.sin(phi) - theta0) <= 4 * EPS * size
    theta_dot_at_0 = a * (omega * np.cos(phi) - alpha * np.sin(phi))  # eq. (10), corrected
    assert abs(theta_dot_at_0 - theta_dot0) <= 8 * EPS * size * omega0
    t = np.linspace(0.0, 20.0 / omega0, 201)
    theta, theta_dot = linear.solve(theta0, theta_dot0, t, alpha=alpha, omega0=omega0)
    envelope = a * np.exp(-alpha * t)
    np.testing.assert_allclose(theta, envelope * np.sin(omega * t + phi), atol=1e-13 * size)
    expected = envelope * (omega * np.cos(omega * t + phi) - alpha * np.sin(omega * t + phi))
    np.testing.assert_allclose(theta_dot, expected, atol=1e-13 * size * omega0)


@pytest.mark.parametrize("alpha", [1.0, 2.0])
def test_amplitude_phase_rejects_non_oscillating_motion(alpha):
    with pytest.raises(ValueError, match="underdamped"):
        linear.amplitude_phase(0.1, 0.0, alpha, 1.0)


SADDLE = [(0.1, 1.0), (0.0, 1.0), (2.0, 1.0), (0.5, 3.0)]


@pytest.mark.parametrize("ic", [(0.1, 0.0), (0.0, 0.07), (-0.1, 0.0), (0.0, -0.001)])
@pytest.mark.parametrize("alpha, omega0", SADDLE)
def test_saddle_matches_dop853(alpha, omega0, ic):
    """φ̈ + 2αφ̇ − ω0²φ = 0, forward and backward over the essay's Fig. 12 range ±10 s."""
    for t in (np.linspace(0.0, 10.0, 101), np.linspace(0.0, -10.0, 101)):
        phi, theta_dot = linear.solve_saddle(*ic, t, alpha=alpha, omega0=omega0)
        ref = dop853(-(omega0**2), alpha, list(ic), t)
        # relative to the orbit's size, plus what DOP853's atol = 1e-13 accumulates
        tol = 1e-9 * (scale(*ic, omega0) + np.abs(ref[0]) + np.abs(ref[1]) / omega0) + 1e-11
        assert np.all(np.abs(phi - ref[0]) <= tol)
        assert np.all(np.abs(theta_dot - ref[1]) <= tol * omega0)


@pytest.mark.parametrize("alpha, omega0", SADDLE)
def test_saddle_initial_conditions(alpha, omega0):
    rng = np.random.default_rng(2)
    phi0, theta_dot0 = rng.normal(size=(2, 50))
    phi, theta_dot = linear.solve_saddle(phi0, theta_dot0, 0.0, alpha=alpha, omega0=omega0)
    size = np.abs(phi0) + np.abs(theta_dot0) / omega0
    assert np.all(np.abs(phi - phi0) <= 4 * EPS * size)
    assert np.all(np.abs(theta_dot - theta_dot0) <= 4 * EPS * size * omega0)


@pytest.mark.parametrize("alpha, omega0", SADDLE)
def test_saddle_eigendirections(alpha, omega0):
    """Along (1, −u2) the motion is pure decay φ0 e^{−u2 t} — the stable manifold, with no
    trace of the unstable mode even after e^{u1 t} ≈ 1e17 — and along (1, u1) pure growth."""
    u1, minus_u2 = Pendulum(alpha, omega0).saddle_eigenvalues()
    t = np.linspace(0.0, 40.0 / u1, 201)
    phi0 = 0.01
    phi, theta_dot = linear.solve_saddle(phi0, minus_u2 * phi0, t, alpha=alpha, omega0=omega0)
    np.testing.assert_allclose(phi, phi0 * np.exp(minus_u2 * t), rtol=1e-13)
    np.testing.assert_allclose(theta_dot, minus_u2 * phi, rtol=1e-13)
    t = np.linspace(0.0, 10.0, 101)
    phi, theta_dot = linear.solve_saddle(phi0, u1 * phi0, t, alpha=alpha, omega0=omega0)
    np.testing.assert_allclose(phi, phi0 * np.exp(u1 * t), rtol=1e-13)
    np.testing.assert_allclose(theta_dot, u1 * phi, rtol=1e-13)


@pytest.mark.parametrize(
    "alpha, omega0, message",
    [
        (-0.1, 1.0, "alpha"),
        (np.nan, 1.0, "alpha"),
        (np.inf, 1.0, "alpha"),
        (0.1, 0.0, "omega0"),
        (0.1, -1.0, "omega0"),
        (0.1, np.inf, "omega0"),
    ],
)
def test_invalid_parameters_raise(alpha, omega0, message):
    with pytest.raises(ValueError, match=message):
        linear.solve(0.1, 0.0, [0.0, 1.0], alpha=alpha, omega0=omega0)
    with pytest.raises(ValueError, match=message):
        linear.solve_saddle(0.1, 0.0, [0.0, 1.0], alpha=alpha, omega0=omega0)
    with pytest.raises(ValueError, match=message):
        linear.amplitude_phase(0.1, 0.0, alpha, omega0)


def test_the_closed_forms_keep_their_public_name():
    """``atlas.linear`` is the public name of atlas.physics.linear, for every spelling."""
    import atlas.linear
    from atlas.linear import solve

    import atlas.physics.linear

    assert atlas.linear is atlas.physics.linear and solve is atlas.physics.linear.solve
