"""The running limit cycle of the pendulum with constant torque, and its certificate.

For θ̈ = τ − ω0² sin θ − 2αθ̇ (α > 0) a rotating limit cycle exists for |τ| above the
homoclinic torque (:func:`homoclinic_threshold`; ≈ 8αω0/π for small α, Strogatz, *Nonlinear
Dynamics and Chaos*, §8.5) and is unique (Levi, Hoppensteadt & Miranker, Q. Appl. Math. 36,
167–198, 1978). :func:`limit_cycle` finds it as the fixed point of the Poincaré map θ̇(θs) ↦
θ̇(θs + 2π) by Brent's method on DOP853 (compiled, :mod:`atlas.kernels.dop853`; about 1e-11
relative). :func:`running_barrier`
builds a band around it that is forward-invariant for the exact flow and for the RK4 step
(margins: :func:`rk4_allowance`, measured), holds the cycle and no rest state, so every orbit
entering it converges to the cycle; :func:`check_barrier` verifies such a band from its stored
numbers alone (Poincaré–Bendixson and Bendixson's criterion), and the result, a
:class:`RunningCertificate`, is the :class:`atlas.physics.barrier.RunningBarrier` that
:func:`atlas.label` takes as ``running``. Everything is computed for |τ| and mirrored
((θ, θ̇, τ) → (−θ, −θ̇, −τ)). Units: θ [rad], θ̇ [rad s⁻¹], t [s]. The derivations:
``docs/design/running.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from atlas.physics.barrier import RunningBarrier
from atlas.physics.pendulum import START_DISTANCE, Pendulum, tilt

__all__ = ["running_certificate", "LimitCycle", "RunningCertificate", "BarrierCheck", "limit_cycle",
           "cycle_section", "cycle_escapes",
           "homoclinic_threshold", "running_barrier", "check_barrier", "contains",
           "rk4_allowance", "CYCLE_SAMPLES", "BARRIER_SAMPLES", "TOP_MARGIN"]

#: Samples of the cycle over one turn (the curve stored and drawn), θ uniform.
CYCLE_SAMPLES = 1024
#: Segments M of the barrier's lower polyline (M + 1 samples over one turn, θ uniform).
BARRIER_SAMPLES = 4096
#: The least relative margin q of the barrier's upper line θ̇ = top = (1 + q)(|τ| + ω0²)/(2α):
#: strictly above the speed beyond which θ̈ < 0 everywhere.
TOP_MARGIN = 1e-3
#: Distance φ = θ − π/2 [rad] from the saddle-node (τ = ω0²) of the start on its centre
#: manifold.
_CENTRE_START = 1e-3
#: Fractions of the cycle's slowest speed tried, lowest first, as the barrier's start value.
_START_FRACTIONS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95)


def _brentq(f, a: float, b: float, *, xtol: float = 2e-12, rtol: float = 8.881784197001252e-16,
            maxiter: int = 100) -> float:
    """A root of ``f`` in [a, b] (f(a), f(b) of opposite signs) to |x − root| ≤ xtol +
    rtol·|x|: Brent's method (Brent, *Algorithms for Minimization without Derivatives*, 1973,
    ch. 4), transcribed from scipy's ``brentq`` (``zeros/brentq.c``: the same steps, the same
    doubles; tests/physics/test_brentq.py), so that the run path needs no scipy."""
    xpre, xcur = float(a), float(b)
    fpre, fcur = f(xpre), f(xcur)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if (fpre > 0.0) == (fcur > 0.0):
        raise ValueError("f(a) and f(b) must have different signs")
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre != 0.0 and fcur != 0.0 and (math.copysign(1.0, fpre)
                                            != math.copysign(1.0, fcur)):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre, scur = scur, stry  # a good short step
            else:
                spre = scur = sbis  # bisect
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = f(xcur)
    raise RuntimeError(f"Brent's method did not converge in {maxiter} iterations")


def _check(alpha: float, omega0: float) -> None:
    if not (math.isfinite(alpha) and alpha > 0.0):
        raise ValueError(f"alpha must be a finite number > 0, got {alpha!r}")
    if not (math.isfinite(omega0) and omega0 > 0.0):
        raise ValueError(f"omega0 must be a finite number > 0, got {omega0!r}")


def _ceiling(alpha: float, omega0: float, torque: float) -> float:
    """(|τ| + ω0²)/(2α) [rad s⁻¹]: at and above this speed θ̈ ≤ 0 (in the canonical frame)."""
    return (abs(torque) + omega0**2) / (2.0 * alpha)


def _section(omega0: float, torque: float):
    """(θs, k) for τ ≥ 0: the Poincaré section θs [rad] (the saddle angle π − arcsin(τ/ω0²)
    while τ < ω0², else π/2, where the saddle-node was born) and k = ω0²|cos θs| [s⁻²], the
    linearisation φ̈ = kφ − 2αφ̇ at the saddle (0 from τ = ω0² on)."""
    r = min(torque / omega0**2, 1.0)
    return math.pi - tilt(omega0, torque), omega0**2 * math.sqrt((1.0 - r) * (1.0 + r))


class _Turn:
    """One turn of the flow (canonical frame, τ ≥ 0) by DOP853 at tolerance ``rtol``."""

    def __init__(self, alpha: float, omega0: float, torque: float, rtol: float):
        self.alpha, self.omega0, self.torque, self.rtol = alpha, omega0, torque, rtol
        self.w2 = omega0**2
        self.scale = _ceiling(alpha, omega0, torque)
        self.t_max = 1e4 * (1.0 / alpha + 1.0 / omega0)

    def solution(self, theta, theta_dot, theta_end):
        """The DOP853 solution (:class:`atlas.kernels.dop853.Solution`, with its dense
        output) from (θ, θ̇) until θ = theta_end or θ̇ falls to 0 (compiled,
        :func:`atlas.kernels.dop853.integrate`, scipy's method step for step)."""
        from atlas.kernels.dop853 import FLOW, TURN, solve

        return solve(FLOW, (self.alpha, self.omega0, self.torque, 0.0), TURN, (theta_end,),
                     (theta, theta_dot), self.t_max, self.rtol,
                     (self.rtol * 2 * math.pi, self.rtol * self.scale), dim=2)

    @staticmethod
    def outcome(sol, theta_end):
        """(reached, θ, θ̇, t) at the end of ``sol``: reached where it got to theta_end,
        not where θ̇ fell to 0 (turned back)."""
        from atlas.kernels.dop853 import EVENT

        theta, theta_dot = sol.y[-1, 0], sol.y[-1, 1]
        reached = sol.status == EVENT and theta - theta_end >= -theta_dot
        return reached, theta, theta_dot, sol.t[-1]

    def run(self, theta, theta_dot, theta_end):
        """Integrate from (θ, θ̇) until θ = theta_end (→ reached) or θ̇ falls to 0 (→ turned
        back): (reached, θ, θ̇, t) at the end (:meth:`solution`)."""
        return self.outcome(self.solution(theta, theta_dot, theta_end), theta_end)

    def escape(self, omega0: float) -> float:
        """Signed outcome of the orbit that leaves (θs, 0) in +θ, one turn later: its speed
        at θs + 2π if it gets there (> 0), else −ω0 times the angle it still lacked where θ̇
        fell to 0 or where it stalled (< 0) — P(0⁺) of the module docstring. Continuous in τ
        across the homoclinic torque, where it vanishes. It starts
        - τ < ω0²: START_DISTANCE along the saddle's unstable eigenvector (eigenvalue
          u1 = k/(α + √(α² + k)); the neglected curvature is O(START_DISTANCE²));
        - τ = ω0²: on the saddle-node's centre manifold θ̇ ≈ ω0²φ²/(4α) at φ = θ − π/2 =
          _CENTRE_START (O(φ³) off it: only the sign is used, to bracket);
        - τ > ω0²: at (π/2, 0), not a rest state."""
        theta_s, k = _section(omega0, self.torque)
        if self.torque < self.w2:
            u1 = k / (self.alpha + math.sqrt(self.alpha**2 + k))
            norm = math.hypot(1.0, u1)
            start = (theta_s + START_DISTANCE / norm, START_DISTANCE * u1 / norm)
        elif self.torque == self.w2:
            start = (theta_s + _CENTRE_START, self.w2 * _CENTRE_START**2 / (4.0 * self.alpha))
        else:
            start = (theta_s, 0.0)
        end = theta_s + 2.0 * math.pi
        reached, theta, theta_dot, _ = self.run(*start, end)
        return theta_dot if reached else -omega0 * (end - theta)


@dataclass(frozen=True)
class LimitCycle:
    """The running limit cycle (steady rotation), in the actual coordinates.

    theta0:    θs [rad], where the samples start (canonical frame: the saddle angle
               π − arcsin(|τ|/ω0²) for |τ| < ω0², else π/2; times ``direction``).
    theta:     θ [rad], CYCLE_SAMPLES + 1 samples uniform over one turn, from θs to
               θs + 2π·direction.
    theta_dot: θ̇ [rad s⁻¹] at those samples (sign = direction, never 0).
    time:      t [s] from θs to each sample (time[-1] = period).
    period:    T [s], the time to advance one turn (from DOP853's event, not from ``time``).
    direction: +1 (τ > 0, rotation in +θ) or −1 (τ < 0).
    error:     estimated relative error of the start speed and of T: the larger change of
               either from rtol·10 to rtol.
    """

    theta0: float
    theta: np.ndarray
    theta_dot: np.ndarray
    time: np.ndarray
    period: float
    direction: int
    error: float

    @property
    def mean_theta_dot(self) -> float:
        """Mean angular velocity 2π·direction/T [rad s⁻¹]."""
        return self.direction * 2.0 * math.pi / self.period


#: Half-width, relative, of the bracket around a fixed point already found at another
#: tolerance (:func:`_fixed_point`'s ``near``).
_NEAR = 1e-6


def _fixed_point(turn: _Turn, omega0: float, near: float | None = None,
                 p0: float | None = None):
    """(θs, v, T, turn): the fixed point v of P, the period and the DOP853 solution of the
    turn from (θs, v) (canonical frame), or None.
    ``near``: the fixed point found at another tolerance; P contracts, so v·(1 ∓ _NEAR)
    brackets this one too, and Brent's method needs a few turns instead of some twelve (the
    whole bracket (0, scale) is taken where it does not). ``p0``: ``turn.escape(omega0)``
    if known."""
    p0 = turn.escape(omega0) if p0 is None else p0
    if not p0 > 0.0:
        return None
    theta_s = _section(omega0, turn.torque)[0]
    end = theta_s + 2.0 * math.pi

    turns = {}  # speed → its turn: Brent's method returns a speed it has evaluated

    def excess(v):  # P(v) − v; orbits that turn back (or stall) count as P = 0
        if v == 0.0:
            return p0
        turns[v] = turn.solution(theta_s, v, end)
        reached, _, theta_dot, _ = turn.outcome(turns[v], end)
        return (theta_dot if reached else 0.0) - v

    lo, hi = 0.0, turn.scale
    if near is not None:
        a, b = near * (1.0 - _NEAR), near * (1.0 + _NEAR)
        if excess(a) > 0.0 > excess(b):
            lo, hi = a, b
    v = _brentq(excess, lo, hi, xtol=1e-15 * turn.scale, rtol=1e-15)
    sol = turns[v] if v in turns else turn.solution(theta_s, v, end)
    reached, _, _, period = turn.outcome(sol, end)
    if not reached:  # cannot happen: P(v) = v > 0 means the orbit got round
        raise RuntimeError("the limit cycle's orbit did not complete a turn")
    return theta_s, float(v), float(period), sol


def cycle_escapes(alpha: float, omega0: float, torque: float, *, rtol: float = 1e-12
                  ) -> tuple[float, float]:
    """P(0⁺) of the module docstring at ``rtol`` and at rtol·10 (:meth:`_Turn.escape`): the
    running cycle exists (:func:`limit_cycle` finds it) where both are > 0 — two DOP853
    turns instead of some twenty; (0, 0) without torque. Give them to
    :func:`cycle_section` to spare it the same two turns."""
    _check(alpha, omega0)
    if torque == 0.0:
        return 0.0, 0.0
    return tuple(_Turn(alpha, omega0, abs(torque), r).escape(omega0)
                 for r in (rtol, 10.0 * rtol))


def cycle_section(alpha: float, omega0: float, torque: float, *, rtol: float = 1e-12,
                  escapes: tuple[float, float] | None = None, turn: bool = False):
    """The running limit cycle's crossing of its Poincaré section, without sampling it:
    (θs [rad], v [rad s⁻¹], period [s], error) in the canonical frame (τ > 0: θs the saddle's
    angle, v > 0 the cycle's speed there; mirrored for τ < 0 by (θ, θ̇) → (−θ, −θ̇)), or None
    where there is no cycle. ``error``: the relative change of v and of the period from
    rtol·10 (the fixed point at rtol·10, bracketed around the first: P contracts).
    ``escapes``: :func:`cycle_escapes` at this ``rtol``, if known. ``turn``: append the
    DOP853 solution (:class:`atlas.kernels.dop853.Solution`, dense output included) of the
    cycle's turn from (θs, v) to θs + 2π at ``rtol``, which the fixed point ended on."""
    _check(alpha, omega0)
    if torque == 0.0:
        return None
    p0, p0_check = (None, None) if escapes is None else escapes
    found = [_fixed_point(_Turn(alpha, omega0, abs(torque), rtol), omega0, p0=p0)]
    if found[0] is None:
        return None
    found.append(_fixed_point(_Turn(alpha, omega0, abs(torque), 10.0 * rtol), omega0,
                              near=found[0][1], p0=p0_check))
    if found[1] is None:
        return None
    (theta_s, v, period, sol), (_, v_check, period_check, _) = found
    error = float(max(abs(v - v_check) / v, abs(period - period_check) / period))
    return (theta_s, v, period, error, sol) if turn else (theta_s, v, period, error)


def limit_cycle(alpha: float, omega0: float, torque: float, *, rtol: float = 1e-12,
                samples: int = CYCLE_SAMPLES) -> LimitCycle | None:
    """The running limit cycle of θ̈ = τ − ω0² sin θ − 2αθ̇, or None where there is none
    (τ = 0, or 0 < |τ| ≤ :func:`homoclinic_threshold`); exists for every |τ| > ω0².

    The fixed point of the Poincaré map θ̇(θs) ↦ θ̇(θs + 2π) by Brent's method on the bracket
    of the module docstring, each map evaluation a DOP853 run at ``rtol`` (atol ``rtol``
    times 2π and (|τ| + ω0²)/(2α)); then ``samples`` + 1 points uniform in θ from DOP853 on
    dθ̇/dθ = θ̈/θ̇, dt/dθ = 1/θ̇ (regular: θ̇ > 0 on the cycle). Accuracy: ``error`` (the
    change from rtol·10), about 1e-11 relative at the default rtol.
    """
    section = cycle_section(alpha, omega0, torque, rtol=rtol)
    if section is None:
        return None
    theta_s, v, period, error = section
    direction = 1 if torque > 0 else -1
    tau = abs(torque)
    theta = theta_s + np.linspace(0.0, 2.0 * math.pi, samples + 1)
    y = _along_theta(alpha, omega0, tau, 0.0, theta, (v, 0.0), rtol,
                     (rtol * _ceiling(alpha, omega0, tau), rtol * period))
    return LimitCycle(theta0=direction * theta_s, theta=direction * theta,
                      theta_dot=direction * y[0], time=y[1], period=period,
                      direction=direction, error=error)


def running_certificate(pendulum: Pendulum, dt: float):
    """(limit cycle, running barrier) of ``pendulum`` for the RK4 map at step ``dt`` [s]: the
    running limit cycle (:func:`limit_cycle`) and the forward-invariant region around it
    (:func:`running_barrier`) that the kernels test; (None, None) where there is no cycle.
    ValueError (one line) where no barrier can be verified at ``dt``. The one place a sweep,
    a trace and ``atlas orbit`` build it."""
    cycle = limit_cycle(pendulum.alpha, pendulum.omega0, pendulum.torque)
    if cycle is None:
        return None, None
    return cycle, running_barrier(pendulum.alpha, pendulum.omega0, pendulum.torque, cycle,
                                  dt=dt)


def homoclinic_threshold(alpha: float, omega0: float, *, rtol: float = 1e-12) -> float:
    """τ_c [rad s⁻²]: the running cycle exists for |τ| > τ_c and not for 0 < |τ| < τ_c.

    At τ_c the saddle's unstable manifold runs into the next saddle (a homoclinic orbit of
    the cylinder). Brent's method on the signed outcome of that manifold one turn later
    (``_Turn.escape``, P(0⁺) of the module docstring), which changes sign there, over
    0 ≤ τ ≤ ω0². Where it is still negative at τ = ω0² (strong damping, α ≳ 0.59ω0: the
    saddle-node's centre manifold does not get round either) the cycle is born from the
    saddle-node's homoclinic loop at τ = ω0², and the result is ω0²: the cycle exists for
    |τ| > ω0² only. The error is that of the manifold (DOP853 at ``rtol``), about 1e-11
    relative (the change from rtol·10).

    For small damping, energy balance along the undamped homoclinic orbit
    θ̇ = 2ω0 cos(θ/2) (Melnikov's method; Strogatz, *Nonlinear Dynamics and Chaos*, §8.5,
    gives 4β/π for θ̈ + βθ̇ + sin θ = γ): the energy gained per turn, 2πτ, equals the energy
    lost, 2α∮θ̇ dθ = 2α·8ω0, so τ_c ≈ 8αω0/π as α → 0. Scaling t → ω0t shows
    τ_c(α, ω0) = ω0²·τ_c(α/ω0, 1).
    """
    _check(alpha, omega0)

    def outcome(torque):
        return _Turn(alpha, omega0, torque, rtol).escape(omega0)

    if not outcome(omega0**2) > 0.0:
        return omega0**2
    return _brentq(outcome, 0.0, omega0**2, xtol=1e-15 * omega0**2, rtol=1e-13)


@dataclass(frozen=True, kw_only=True)
class RunningCertificate(RunningBarrier):
    """A :class:`atlas.physics.barrier.RunningBarrier` (what the kernels test, and what
    :func:`atlas.label` takes as ``running``) with the record of its verification.

    The region, in the canonical frame (τ > 0), is the band {g(θ) ≤ θ̇ ≤ top} of the cylinder,
    g the polyline through the samples ``g`` at θ = theta0 + 2πi/M (i = 0…M, linear in
    between), continued 2π-periodically (it drops from g[M] to g[0] at theta0 + 2πj); for
    direction −1 its mirror image: (θ, θ̇) is in it when (−θ, −θ̇) is in the band
    (:func:`contains`).

    theta0:          θa [rad], canonical frame: where the cycle is slowest.
    g:               float64 [rad s⁻¹], M + 1 samples of the lower curve, all > 0, g[M] ≥ g[0].
    top:             the upper line [rad s⁻¹], > (|τ| + ω0²)/(2α).
    direction:       +1 or −1, the sign of τ.
    epsilon:         ε [rad s⁻²] of the construction dg/dθ = (θ̈(θ, g) − ε)/g.
    verified_margin: the certified lower bound of d/dt(θ̇ − g(θ)) on the lower curve, less the
                     RK4 allowance when ``dt`` is set [rad s⁻²] (:func:`check_barrier`), > 0.
    dt:              the RK4 step [s] whose map the region is also invariant under, or None
                     (the exact flow only).
    """

    epsilon: float
    verified_margin: float
    dt: float | None = None


@dataclass(frozen=True)
class BarrierCheck:
    """Outcome of :func:`check_barrier`: ``ok``, the ``reason`` when not, and ``margin``, the
    certified lower bound of d/dt(θ̇ − g(θ)) over the whole lower curve, less the RK4
    allowance when a step is given [rad s⁻²]."""

    ok: bool
    reason: str
    margin: float


def rk4_allowance(alpha: float, omega0: float, torque: float, dt: float, speed, slope=0.0):
    """The rate [rad s⁻²] at which the flow must cross a boundary piece (at speeds up to
    ``speed`` [rad s⁻¹], slope ``slope`` [s⁻¹]; arrays broadcast) for the RK4 step of ``dt``
    [s] to cross it inward as well: (ω0² + |τ|)(Λ·dt)⁴(1 + |s|/Λ)/50, Λ = speed + ω0 + 2α.

    RK4's local error per step is dt⁵ times fifth derivatives of the solution, with
    coefficients of about 1/120 (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.3). Along
    θ̈ = τ − ω0² sin θ − 2αθ̇ each time derivative brings a factor of at most Λ
    (d/dt sin θ = θ̇ cos θ; ω0 and 2α bound the linear rates), and |θ̈| ≤ 2(ω0² + |τ|) below
    top; so a step moves θ̇ off the exact flow by O((ω0² + |τ|)Λ⁴dt⁵), θ by one factor Λ
    less, and θ̇ − g(θ) by the first plus |s| times the second. Like
    :func:`atlas.labels.trap.trap_margin` the constant is measured, not proven:
    ``tests/physics/test_running.py`` finds RK4's local error per unit time below 1/20 of the
    allowance (in θ̇, and in θ times Λ) throughout the regions of its cases, for dt up to
    0.1 s; a boundary crossed faster than the allowance is crossed inward by the step too.
    """
    lam = np.asarray(speed) + omega0 + 2.0 * alpha
    return (omega0**2 + abs(torque)) * (lam * dt) ** 4 * (1.0 + np.abs(slope) / lam) / 50.0


def check_barrier(alpha: float, omega0: float, torque: float, barrier, *,
                  dt: float | None = None) -> BarrierCheck:
    """Verify that ``barrier`` (anything with theta0, g, top, direction) is forward invariant
    for θ̈ = τ − ω0² sin θ − 2αθ̇, from its stored numbers alone (not from its construction),
    and with ``dt`` [s] under the RK4 step of dt too.

    Checks, in the canonical frame (τ > 0; for τ < 0 the mirror image, direction −1):

    1. g > 0 at every sample, so g > 0 everywhere: the region holds no rest state (θ̇ = 0).
    2. top > (τ + ω0²)/(2α): on and above θ̇ = top, θ̈ ≤ τ + ω0² − 2α·top < 0, the flow
       crosses the upper line downward, into the region; and max g < top.
    3. g[M] ≥ g[0]: at θ = theta0 (mod 2π) the boundary has a vertical piece from g[0] up to
       g[M], the region lies on its +θ side, and the flow crosses it in +θ (θ̇ ≥ g > 0).
    4. On the lower curve θ̇ = g(θ) the flow crosses upward. On a segment of slope s,
       d/dt(θ̇ − g(θ)) = θ̈ − s·θ̇ = Φ(θ) := τ − ω0² sin θ − (2α + s)·g(θ) (with θ̇ > 0 the
       +θ derivative s is the one that counts at a vertex). g is linear there, so
       Φ'' = ω0² sin θ, |Φ''| ≤ ω0², and on a segment of length h Φ lies at most ω0²h²/8
       below the chord between its end values (the interpolation error bound; sharper than
       the Lipschitz bound (ω0² + (2α + |s|)|s|)·h/2 and as rigorous). So
       min Φ ≥ min(Φ(a), Φ(b)) − ω0²h²/8 − (rounding: 64 ulp of the terms), which must be > 0
       on every segment; ``margin`` is the least such bound.

    With ``dt``, the margins of 2 and 4 must also exceed :func:`rk4_allowance` (at the
    speed top, and at each segment's highest g and its slope): then the RK4 step, too, moves
    states on or near the boundary inward. The vertical piece needs nothing more: a step
    advances θ by about θ̇·dt ≥ g·dt, far more than its error.

    Then the closed region is positively invariant: the flow points strictly inward across
    every piece of its boundary (the upper line, the lower curve, the vertical piece). It is
    compact on the cylinder and holds no rest state, so by Poincaré–Bendixson (the cylinder
    band maps onto a plane annulus by (θ, θ̇) ↦ e^θ̇(cos θ, sin θ)) the ω-limit set of every
    orbit in it is a periodic orbit in it; contractible ones are excluded (div f = −2α < 0,
    Bendixson), and the only rotating one is the limit cycle (module docstring). Hence every
    orbit that enters the region converges to the limit cycle.
    """
    _check(alpha, omega0)
    direction = 1 if torque > 0 else -1
    tau, w2 = abs(torque), omega0**2
    g = np.asarray(barrier.g, dtype=np.float64)
    if torque == 0.0 or barrier.direction != direction:
        return BarrierCheck(False, "direction must be sign(torque) (torque != 0)", -math.inf)
    if g.ndim != 1 or g.size < 2 or not np.all(np.isfinite(g)):
        return BarrierCheck(False, "g must hold at least 2 finite samples", -math.inf)
    if not np.all(g > 0.0):
        return BarrierCheck(False, "g must be > 0 (a rest state would lie in the region)",
                            -math.inf)
    if not barrier.top > _ceiling(alpha, omega0, tau):
        return BarrierCheck(False, "top must exceed (|torque| + omega0^2)/(2 alpha)", -math.inf)
    if dt is not None and not (2.0 * alpha * barrier.top - tau - w2
                               > rk4_allowance(alpha, omega0, tau, dt, barrier.top)):
        return BarrierCheck(False, f"top is too close to (|torque| + omega0^2)/(2 alpha) for "
                            f"the RK4 step dt = {dt:g}", -math.inf)
    if not g.max() < barrier.top:
        return BarrierCheck(False, "max g must be below top", -math.inf)
    if not g[-1] >= g[0]:
        return BarrierCheck(False, "g[M] < g[0]: the flow would leave across the jump at "
                            "theta0", -math.inf)
    m = g.size - 1
    h = 2.0 * math.pi / m
    theta = barrier.theta0 + h * np.arange(m + 1)
    s = np.diff(g) / h
    c = 2.0 * alpha + s
    sin = np.sin(theta)
    phi_a = tau - w2 * sin[:-1] - c * g[:-1]
    phi_b = tau - w2 * sin[1:] - c * g[1:]
    size = tau + w2 * (1.0 + np.abs(theta[1:])) + np.abs(c) * g[1:]
    bound = np.minimum(phi_a, phi_b) - w2 * h * h / 8.0 - 64.0 * np.finfo(float).eps * size
    if dt is not None:
        bound = bound - rk4_allowance(alpha, omega0, tau, dt, np.maximum(g[:-1], g[1:]), s)
    margin = float(bound.min())
    if not margin > 0.0:
        i = int(bound.argmin())
        step = "" if dt is None else f" with the RK4 step dt = {dt:g}"
        return BarrierCheck(False, f"the flow is not certified to cross the lower curve "
                            f"upward{step} on segment {i} (bound {margin:.3g})", margin)
    return BarrierCheck(True, "", margin)


def _along_theta(alpha, omega0, tau, epsilon, theta, y0, rtol, atol, low=None):
    """(θ̇, t) at the angles ``theta`` (increasing) of the curve dθ̇/dθ = (θ̈(θ, θ̇) − ε)/θ̇,
    dt/dθ = 1/θ̇ from (θ̇, t) = ``y0`` at theta[0] (an orbit for ε = 0), by DOP853 at
    ``rtol``, ``atol`` (one per component given; compiled, scipy's method step for step, the
    samples from its dense output as scipy's ``t_eval``), or None where θ̇ falls to ``low``
    first."""
    from atlas.kernels.dop853 import ALONG_THETA, BELOW, EVENT, NONE, solve

    event, level = (NONE, 0.0) if low is None else (BELOW, low)
    sol = solve(ALONG_THETA, (alpha, omega0, tau, epsilon), event, (level,), y0, theta[-1],
                rtol, atol, dim=len(y0), t0=theta[0])
    if sol.status == EVENT:
        return None
    if sol.t[-1] != theta[-1]:
        raise RuntimeError(f"DOP853 along theta stopped early (status {sol.status})")
    return sol.at(theta)[:len(y0)]


def _lower_curve(alpha, omega0, tau, theta_a, v0, epsilon, m, rtol=1e-10):
    """g on θa + 2πi/m (i = 0…m) from dg/dθ = (θ̈(θ, g) − ε)/g, g(θa) = v0 (DOP853), or
    None where g falls below v0/1000."""
    theta = theta_a + np.linspace(0.0, 2.0 * math.pi, m + 1)
    g = _along_theta(alpha, omega0, tau, epsilon, theta, (v0,), rtol, (rtol * v0,),
                     low=1e-3 * v0)
    return None if g is None else g[0]


def _margin_for(alpha, omega0, tau, theta_a, v0):
    """3/4 of the largest ε [rad s⁻²] for which the lower curve from v0 still returns to at
    least v0 after one turn (Brent's method, 1e-3 relative), or None where even ε = 0 (an
    orbit) does not gain speed over the turn: v0 lies outside the running basin."""
    def gain(epsilon):
        g = _lower_curve(alpha, omega0, tau, theta_a, v0, epsilon, 1)
        return -v0 if g is None else g[-1] - v0

    gain0 = gain(0.0)
    if not gain0 > 0.0:
        return None
    hi = gain0 * v0 / (2.0 * math.pi)  # ε·(time of a turn) ≈ lost speed; grown until lost
    while gain(hi) > 0.0:
        hi *= 4.0
    return 0.75 * _brentq(gain, 0.0, hi, rtol=1e-3)


def running_barrier(alpha: float, omega0: float, torque: float, cycle: LimitCycle | None = None,
                    *, dt: float | None = None,
                    samples: int = BARRIER_SAMPLES) -> RunningCertificate | None:
    """A verified :class:`RunningCertificate` around the running limit cycle (pass it to
    :func:`atlas.label` as ``running``), or None where there is no cycle. ``cycle``:
    :func:`limit_cycle`'s result, computed here if not given. ``dt`` [s]: the RK4 step of
    the kernels that will test it; the region is then verified to be invariant under that
    step too (:func:`check_barrier`). Without it, under the exact flow only.

    Construction (canonical frame, τ > 0): θa is the cycle sample where it is slowest and
    v0 = c·min θ̇ of the cycle, c from 0.01 up (a lower curve certifies more orbits, and
    sooner). The lower curve solves dg/dθ = (θ̈(θ, g) − ε)/g from g(θa) = v0 over one turn;
    on it d/dt(θ̇ − g(θ)) = θ̈ − g'·θ̇ = ε > 0: the flow crosses upward with a constant
    acceleration margin. (A margin ε·g, i.e. dg/dθ = θ̈/g − ε, fails near the saddles: the
    polyline's chord error in Φ is about g·h·|g''|/2, and where the curve passes slowly over
    a saddle it is hyperbola-like with g·g'' bounded, g'' itself ~ 1/g.) ε = 0 would follow
    an orbit, which below the cycle gains speed over a turn, P(v0) > v0; ε is 3/4 of the
    largest value that still returns g(θa + 2π) ≥ v0.

    The top is (1 + q)(|τ| + ω0²)/(2α), above the cycle (at the cycle's fastest point θ̈ = 0,
    so its speed there is at most (|τ| + ω0²)/(2α)); there θ̈ ≤ −q(|τ| + ω0²). q is
    TOP_MARGIN, or with ``dt`` twice what :func:`rk4_allowance` asks at speed 1.1·(|τ| +
    ω0²)/(2α) if more; ValueError where that exceeds 0.1 (dt too coarse for the speeds of
    the rotation: Λ·dt ≳ 0.5 rad per step).

    The first candidate that :func:`check_barrier` accepts is returned, trying each c with
    M = ``samples``, then 4× and 16× as many segments (the chord error shrinks like h; close
    to the homoclinic torque the curve needs them); RuntimeError if none is accepted.
    """
    _check(alpha, omega0)
    if cycle is None:
        cycle = limit_cycle(alpha, omega0, torque)
    if cycle is None:
        return None
    direction, tau = cycle.direction, abs(torque)
    ceiling = _ceiling(alpha, omega0, tau)
    q = TOP_MARGIN
    if dt is not None:
        q = max(q, 2.0 * float(rk4_allowance(alpha, omega0, tau, dt, 1.1 * ceiling))
                / (tau + omega0**2))
        if q > 0.1:
            raise ValueError(f"dt = {dt:g} s is too coarse for the running speeds "
                             f"~{ceiling:.3g} rad/s (RK4's error near the top)")
    top = (1.0 + q) * ceiling
    speed = direction * cycle.theta_dot  # canonical frame
    if not speed.max() < top:
        raise RuntimeError("the limit cycle lies above the barrier's top")
    slowest = int(speed.argmin())
    theta_a = float(direction * cycle.theta[slowest])
    reasons = []
    for c in _START_FRACTIONS:
        v0 = c * speed[slowest]
        epsilon = _margin_for(alpha, omega0, tau, theta_a, v0)
        if epsilon is None:
            continue
        for m in (samples, 4 * samples, 16 * samples):
            g = _lower_curve(alpha, omega0, tau, theta_a, v0, epsilon, m)
            if g is None:
                break
            candidate = SimpleNamespace(theta0=theta_a, g=g, top=top, direction=direction)
            check = check_barrier(alpha, omega0, torque, candidate, dt=dt)
            if check.ok:
                return RunningCertificate(theta0=theta_a, g=g, top=top, direction=direction,
                                          epsilon=epsilon, verified_margin=check.margin,
                                          dt=dt)
            reasons.append(f"c = {c}, M = {m}: {check.reason}")
    raise RuntimeError("no running barrier verified: " + "; ".join(reasons))


def contains(barrier, theta, theta_dot) -> np.ndarray:
    """True where (θ [rad], θ̇ [rad s⁻¹]) (arrays, broadcast) lies in the certified region of
    ``barrier`` (closed: its boundary included): g(θ') ≤ θ̇' ≤ top with (θ', θ̇') = direction
    × (θ, θ̇), g the stored polyline continued 2π-periodically from theta0."""
    d = barrier.direction
    g = np.asarray(barrier.g, dtype=np.float64)
    m = g.size - 1
    u = np.mod(d * np.asarray(theta, dtype=np.float64) - barrier.theta0, 2.0 * math.pi)
    x = u * (m / (2.0 * math.pi))
    i = np.clip(np.floor(x).astype(np.int64), 0, m - 1)
    lower = g[i] + (x - i) * (g[i + 1] - g[i])
    v = d * np.asarray(theta_dot, dtype=np.float64)
    return (v >= lower) & (v <= barrier.top)
