"""One orbit of atlas's RK4 map, followed with atlas's certificates and kept whole.

:func:`integrate` steps θ̈ = −ω0² sin θ − 2αθ̇ + τ with the scalar form of the method
(:meth:`atlas.labels.methods.Method.scalar_form`: the kernels' own step and trap sources as
plain Python with libm) and tests, every ``check_every`` steps as the kernels do and in their
order, the energy trap of the (tilted) wells at the level :func:`atlas.labels.trap.
energy_cap` (or the level a file's run used), then (with a torque and a running barrier) the
kernels' running test. It keeps the whole trajectory, and follows it on after the
certificate for the pictures: a trapped orbit until it has nearly settled, a running one
until it is on the limit cycle (two successive turns cross the certificate's phase at speeds
that agree to ``settle``). Its labels equal :func:`atlas.label`'s straightforward kernel's
except where rounding decides (``tests/commands/test_orbit.py``). :func:`wrapped` draws an
orbit into a window of the map, a whole number of turns at a time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from atlas import defaults
from atlas.kernels.rk4 import running_test, torque_model
from atlas.labels.backends import resolve_method
from atlas.labels.labelling import check_integration, check_running
from atlas.labels.methods import lookup as lookup_method
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for, trap_margin
from atlas.physics.barrier import RunningBarrier
from atlas.physics.pendulum import Pendulum, tilt
from atlas.status import NONFINITE, RUNNING, TRAPPED, UNRESOLVED

__all__ = ["Orbit", "integrate", "wrapped", "window_period"]

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Orbit:
    """One orbit from (θ0 [rad], θ̇0 [rad s⁻¹]) of θ̈ = −ω0² sin θ − 2αθ̇ + τ: its trajectory
    ``t`` [s], ``theta``, ``theta_dot`` (followed past the certificate until it has nearly
    settled, or, running, for ``turns`` more turns, at least those asked for, until it is on
    the limit cycle; ``settled``: whether it got there before t_max), and its label:
    ``status`` (0 trapped, 1 unresolved, 2 nonfinite, 4 running), ``k``, ``t_trap`` [s] (the
    time of the trap or of the running certificate), the well energy ``energy`` E_k at the
    trap against ``cap`` (:func:`atlas.labels.trap.energy_cap`: 2ω0²(1 − m) when τ = 0),
    ``margin`` m, ``trap_index`` (the trajectory index of the certificate), ``direction``
    (sign(τ) when running, else 0), the running certificate ``barrier`` that was tested
    (None: none), the limit ``cycle`` (an :class:`atlas.physics.running.LimitCycle`, when
    known, for the pictures) and the ``method`` that stepped it."""

    theta0: float
    theta_dot0: float
    alpha: float
    omega0: float
    dt: float
    t_max: float
    t: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    theta_dot: np.ndarray = field(repr=False)
    status: int = UNRESOLVED
    k: int | None = None
    t_trap: float | None = None
    energy: float | None = None
    cap: float = math.nan
    margin: float = math.nan
    trap_index: int | None = None
    torque: float = 0.0
    direction: int = 0
    barrier: RunningBarrier | None = field(default=None, repr=False)
    cycle: object = field(default=None, repr=False)
    method: str = defaults.METHOD
    turns: int = 0
    settled: bool = False

    @property
    def rest_angle(self) -> float:
        """θ* = arcsin(τ/ω0²) [rad] (0 when τ = 0; ±π/2 when |τ| ≥ ω0², where no well is)."""
        return tilt(self.omega0, self.torque)



def _steps(scalar, state, n, alpha, omega0, dt, torque, thetas, speeds):
    """``n`` steps of the method's scalar form from ``state`` (θ, θ̇, cos θ, sin θ), each
    state appended to ``thetas``/``speeds``; returns the last."""
    theta, theta_dot, c, s = state
    for _ in range(n):
        theta, theta_dot, c, s = scalar.step(theta, theta_dot, c, s, alpha, omega0, dt, torque)
        thetas.append(theta)
        speeds.append(theta_dot)
    return theta, theta_dot, c, s


def integrate(theta0: float, theta_dot0: float, *, alpha: float, omega0: float,
              torque: float = 0.0, running: RunningBarrier | None = None,
              dt: float = defaults.DT, t_max: float = defaults.T_MAX,
              check_every: int = CHECK_EVERY, settle: float = 1e-3,
              turns: float = 2.0, method: str = defaults.METHOD, cap: float | None = None,
              margin: float | None = None) -> Orbit:
    """Follow one orbit of θ̈ = −ω0² sin θ − 2αθ̇ + τ (τ = ``torque`` [rad s⁻²]) with atlas's
    RK4 and certificates (module docstring), tested at the kernels' check steps in the
    kernels' order: the energy trap first, then the running certificate ``running`` (a
    :class:`atlas.physics.barrier.RunningBarrier` of direction sign(τ), as :func:`atlas.label`
    takes; None: no orbit is labelled running). After the trap the orbit goes on until
    E_k < ``settle`` times the trap's saddle energy (for the pictures), after the running
    certificate for at least ``turns`` more turns and until two successive turns return to
    the certificate's phase (mod 2π) at speeds within ``settle`` (relative) of each other:
    on the limit cycle; either at most to t_max (``settled`` says which ended it). Raises
    ValueError for settings atlas cannot certify
    (:func:`atlas.labels.labelling.check_integration`) or a barrier whose direction is not
    sign(τ), TypeError for a ``running`` that is not a RunningBarrier.
    ``method``: the discretisation (:data:`atlas.kernels.METHODS`), as :func:`atlas.label`'s
    straightforward kernel of that method steps it. ``cap`` [rad² s⁻²], ``margin``: the
    trap's level and margin a run used (an atlas file's); None: :func:`atlas.labels.trap.
    energy_cap` and :func:`~atlas.labels.trap.trap_margin`, as atlas.label."""
    torque = float(torque)
    check_integration(alpha, omega0, dt, t_max, check_every, torque)
    method = resolve_method("cpu", "straightforward", method)
    check_running(running, torque, method)
    theta0, theta_dot0 = float(theta0), float(theta_dot0)
    scalar = lookup_method(method).scalar_form()
    margin = trap_margin(dt, alpha, omega0) if margin is None else float(margin)
    cap = energy_cap(dt, alpha, omega0, torque) if cap is None else float(cap)
    _, shift, vers, *_ = torque_model(omega0, torque)  # θ*, 1 − cos θ* as the kernels'
    in_band = running_test.py_func  # the kernels' own test, as plain Python
    if running is not None:
        band = (float(running.direction), running.theta0, running.g, running.top)

    def sync(th, v):  # (c, s, k, E_k) at a trap test, as the kernels
        return scalar.sync(th, v, omega0, torque, shift, vers)

    def steps(th, v, c, s):
        return _steps(scalar, (th, v, c, s), check_every, alpha, omega0, dt, torque, thetas,
                      speeds)

    n_checks = n_checks_for(t_max, dt, check_every)
    th, v = theta0, theta_dot0
    thetas, speeds = [th], [v]
    result = {"status": UNRESOLVED}
    for j in range(n_checks + 1):
        if not (math.isfinite(th) and math.isfinite(v)):
            result = {"status": NONFINITE}
            break
        c, s, k, energy = sync(th, v)
        if energy < cap:
            result = {"status": TRAPPED, "k": int(k), "t_trap": j * check_every * dt,
                      "energy": energy, "trap_index": len(thetas) - 1}
            break
        if running is not None and in_band(th, v, *band):
            result = {"status": RUNNING, "t_trap": j * check_every * dt,
                      "trap_index": len(thetas) - 1, "direction": running.direction}
            break
        if j == n_checks:
            break
        th, v, c, s = steps(th, v, c, s)
    limit = n_checks * check_every
    if result["status"] == TRAPPED:
        level = settle * Pendulum(alpha, omega0, torque).saddle_energy
        while len(thetas) - 1 < limit:
            c, s, _, energy = sync(th, v)
            if not energy > level:
                result["settled"] = True
                break
            th, v, c, s = steps(th, v, c, s)
    elif result["status"] == RUNNING:
        # the speeds at which the orbit returns to the certificate's phase, θ_cert + 2πn
        # (linear between steps): on the cycle once two successive ones agree to ``settle``
        # (the return map contracts by e^(−2αT) per turn of period T)
        start, sign, last = th, running.direction, None
        result["turns"] = 0
        while len(thetas) - 1 < limit and not (result["turns"] >= turns
                                               and result.get("settled")):
            first = len(thetas)
            th, v, c, s = steps(th, v, *sync(th, v)[:2])
            for i in range(first, len(thetas)):
                x0, x1 = sign * (thetas[i - 1] - start), sign * (thetas[i] - start)
                while x0 < TWO_PI * (result["turns"] + 1) <= x1:
                    f = (TWO_PI * (result["turns"] + 1) - x0) / (x1 - x0)
                    u = speeds[i - 1] + f * (speeds[i] - speeds[i - 1])
                    result["settled"] = last is not None and abs(u - last) < settle * abs(u)
                    last = u
                    result["turns"] += 1
    theta, theta_dot = np.array(thetas), np.array(speeds)
    return Orbit(theta0, theta_dot0, float(alpha), float(omega0), float(dt), float(t_max),
                 np.arange(theta.size) * dt, theta, theta_dot, cap=cap, margin=margin,
                 torque=torque, barrier=running, method=method, **result)


def window_period(lo: float, hi: float) -> float:
    """The period [rad] an orbit is wrapped with in the θ window [lo, hi]: the whole turns,
    2π each, that fit in its width (0 for a window narrower than one turn)."""
    return TWO_PI * math.floor((hi - lo) / TWO_PI + 1e-9)


def wrapped(theta: np.ndarray, theta_dot: np.ndarray, lo: float, hi: float
            ) -> tuple[np.ndarray, np.ndarray]:
    """An orbit's phase curve (θ [rad], θ̇ [rad s⁻¹]) drawn in the θ window [lo, hi]: θ
    where it lies inside, else shifted by the multiple of :func:`window_period` that brings
    it inside (the phase portrait repeats every 2π in θ, one well further per turn), with a
    NaN row wherever the shift changes, so that a drawn line breaks there instead of
    crossing the window. A window narrower than one turn: the curve unchanged."""
    theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
    period = window_period(lo, hi)
    if period == 0.0:
        return theta, theta_dot
    turns = np.where(theta > hi, -np.ceil((theta - hi) / period),
                     np.where(theta < lo, np.ceil((lo - theta) / period), 0.0))
    cuts = np.flatnonzero(np.diff(turns)) + 1
    return (np.insert(theta + turns * period, cuts, np.nan),
            np.insert(theta_dot, cuts, np.nan))
