"""``atlas orbit``: one orbit — its label, its certificate, and its pictures (the essay's
Figure 9 phase curve over the basin map, and Figure 6's θ(t), for any initial condition).

:func:`integrate` follows one orbit of θ̈ = −ω0² sin θ − 2αθ̇ + τ with atlas's RK4 step and
certificates (the formulas of :mod:`atlas.kernels.rk4` with ``math.sin``, tested every
``check_every`` steps as the kernels do): the energy trap of the (tilted) wells at the level
:func:`atlas.labels.labelling.energy_cap`, then, with a torque and a :class:`atlas.labels.labelling.RunningBarrier`,
the running certificate; it keeps the whole trajectory. The label itself is also taken from
:func:`atlas.label` and the two must agree. :func:`report` adds the certificate for the exact
equation: the distance to the exact basin boundaries from :class:`atlas.boundaries.certificate.Certifier`
(DOP853 stable manifolds, tilted by the torque where it has one) and the exact side, compared
with the file's ``d_cert``, and the file's stored values at the nearest grid point.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from atlas import defaults
from atlas.errors import AtlasError, InputFileError
from atlas.kernels import NONFINITE, RUNNING, TRAPPED, UNRESOLVED
from atlas.labels.labelling import (
    CHECK_EVERY,
    RunningBarrier,
    check_integration,
    check_running,
    energy_cap,
    n_checks_for,
    resolve_method,
    trap_margin,
)
from atlas.layout import point_group
from atlas.store.validate import STATUS_MEANINGS, file_method

__all__ = ["Orbit", "integrate", "report", "plot_orbit", "parse_number", "running_barrier_for",
           "cycle_from_group"]

TWO_PI = 2.0 * math.pi
INV_TWO_PI = 1.0 / TWO_PI
#: The name of each status code (as the file's CF flag_meanings say).
STATUS_NAMES = STATUS_MEANINGS


@dataclass(frozen=True)
class Orbit:
    """One orbit from (θ0 [rad], θ̇0 [rad s⁻¹]) of θ̈ = −ω0² sin θ − 2αθ̇ + τ: its trajectory
    ``t`` [s], ``theta``, ``theta_dot`` (followed past the certificate until it has nearly
    settled, or for ``turns`` more turns when running), and its label: ``status`` (0 trapped,
    1 unresolved, 2 nonfinite, 4 running), ``k``, ``t_trap`` [s] (the time of the trap or of
    the running certificate), the well energy ``energy`` E_k at the trap against ``cap``
    (:func:`atlas.labels.labelling.energy_cap`: 2ω0²(1 − m) when τ = 0), ``margin`` m, ``trap_index``
    (the trajectory index of the certificate), ``direction`` (sign(τ) when running, else 0),
    the running certificate ``barrier`` that was tested (None: none) and the limit ``cycle``
    (an :class:`atlas.physics.running.LimitCycle`, when known, for the pictures)."""

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

    @property
    def rest_angle(self) -> float:
        """θ* = arcsin(τ/ω0²) [rad] (0 when τ = 0; ±π/2 when |τ| ≥ ω0², where no well is)."""
        return _shift(self.omega0, self.torque)


def _shift(omega0: float, torque: float) -> float:
    """θ* as the kernels compute it (:func:`atlas.kernels.rk4.torque_model`): arcsin(τ/ω0²),
    clamped to ±π/2."""
    return math.asin(min(1.0, max(-1.0, torque / (omega0 * omega0))))


def _step(theta, theta_dot, w2, a2, dt, torque=0.0):
    """One classical RK4 step of θ̈ = τ − ω0² sin θ − 2αθ̇, written as
    :func:`atlas.kernels.rk4.make_rk4_step_torque` (with τ = 0 the terms τ − x are −x
    exactly: the step of :func:`atlas.kernels.rk4.make_rk4_step`)."""
    h2 = 0.5 * dt
    k1t = theta_dot
    k1v = torque - w2 * math.sin(theta) - a2 * theta_dot
    k2t = theta_dot + h2 * k1v
    k2v = torque - w2 * math.sin(theta + h2 * k1t) - a2 * k2t
    k3t = theta_dot + h2 * k2v
    k3v = torque - w2 * math.sin(theta + h2 * k2t) - a2 * k3t
    k4t = theta_dot + dt * k3v
    k4v = torque - w2 * math.sin(theta + dt * k3t) - a2 * k4t
    h6 = dt / 6.0
    return (theta + h6 * (k1t + 2.0 * (k2t + k3t) + k4t),
            theta_dot + h6 * (k1v + 2.0 * (k2v + k3v) + k4v))


def _steps(theta, theta_dot, n, alpha, omega0, dt, torque, method, thetas, speeds):
    """``n`` steps of ``method`` from (θ, θ̇), appended to ``thetas``/``speeds``; returns the
    last state. For "rk4-trigfree" the step is the kernels' own source as plain Python
    (:data:`atlas.kernels.trigfree._TRIGFREE_STEP`, τ ≠ 0 form: τ − x is −x at τ = 0), and
    (cos θ, sin θ) are re-synchronised from θ (libm) first, as the method's scalar form does
    at every trap test."""
    if method == "rk4-trigfree":
        from atlas.kernels.trigfree import trigfree_step_torque

        step = trigfree_step_torque.py_func
        c, s = math.cos(theta), math.sin(theta)
        for _ in range(n):
            theta, theta_dot, c, s = step(theta, theta_dot, c, s, alpha, omega0, dt, torque)
            thetas.append(theta)
            speeds.append(theta_dot)
        return theta, theta_dot
    w2, a2 = omega0 * omega0, 2.0 * alpha
    for _ in range(n):
        theta, theta_dot = _step(theta, theta_dot, w2, a2, dt, torque)
        thetas.append(theta)
        speeds.append(theta_dot)
    return theta, theta_dot


def _well_energy(theta, theta_dot, w2, torque=0.0, shift=0.0, vers=0.0, method="rk4"):
    """(k, E_k) as the kernels of ``method`` compute them: :func:`atlas.kernels.rk4.
    make_well_energy` for τ = 0, :func:`atlas.kernels.rk4.make_well_energy_torque` (θ* =
    ``shift``, 1 − cos θ* = ``vers``) otherwise; for "rk4-trigfree" the re-synchronisation's
    (:func:`atlas.kernels.trigfree.make_sync`, ``make_sync_torque``: 1 − cos θ of the whole
    θ, libm as the method's scalar form)."""
    if method == "rk4-trigfree":
        h = math.sin(0.5 * theta)
        vers_theta = 2.0 * (h * h)
        if torque == 0.0:
            k = math.floor(theta * INV_TWO_PI + 0.5)
            return k, 0.5 * theta_dot * theta_dot + w2 * vers_theta
        k = math.floor((theta + shift) * INV_TWO_PI + 0.5)
        phi = theta - TWO_PI * k
        return k, (0.5 * theta_dot * theta_dot + w2 * (vers_theta - vers)
                   - torque * (phi - shift))
    if torque == 0.0:
        k = math.floor(theta * INV_TWO_PI + 0.5)
        s = math.sin(0.5 * (theta - TWO_PI * k))
        return k, 0.5 * theta_dot * theta_dot + 2.0 * w2 * s * s
    k = math.floor((theta + shift) * INV_TWO_PI + 0.5)
    phi = theta - TWO_PI * k
    s = math.sin(0.5 * phi)
    return k, (0.5 * theta_dot * theta_dot + w2 * (2.0 * (s * s) - vers)
               - torque * (phi - shift))


def _lower(barrier_g, theta0, u):
    """ĝ(u): the barrier's lower curve at u (frame of positive rotation), as the kernels'
    running test interpolates it (:func:`atlas.kernels.rk4.make_running_test`)."""
    m = len(barrier_g) - 1
    x = u - theta0
    x = x - TWO_PI * math.floor(x * INV_TWO_PI)
    t = x * (m * INV_TWO_PI)
    i = min(max(float(math.floor(t)), 0.0), m - 1.0)
    j = int(i)
    return barrier_g[j] + (t - i) * (barrier_g[j + 1] - barrier_g[j])


def _in_band(theta, theta_dot, sign, theta0, g, top) -> bool:
    """The kernels' running test: σθ̇ ≤ top and σθ̇ ≥ ĝ(σθ) (σ = sign(τ))."""
    w = sign * theta_dot
    if not w <= top:
        return False
    return w >= _lower(g, theta0, sign * theta)


def integrate(theta0: float, theta_dot0: float, *, alpha: float, omega0: float,
              torque: float = 0.0, running: RunningBarrier | None = None,
              dt: float = defaults.DT, t_max: float = defaults.T_MAX,
              check_every: int = CHECK_EVERY, settle: float = 1e-3,
              turns: float = 2.0, method: str = defaults.METHOD) -> Orbit:
    """Follow one orbit of θ̈ = −ω0² sin θ − 2αθ̇ + τ (τ = ``torque`` [rad s⁻²]) with atlas's
    RK4 and certificates (module docstring), tested at the kernels' check steps in the
    kernels' order: the energy trap first, then the running certificate ``running`` (a
    :class:`atlas.labels.labelling.RunningBarrier` of direction sign(τ), as :func:`atlas.label` takes;
    None: no orbit is labelled running). After the trap the orbit goes on until
    E_k < ``settle`` times the trap's saddle energy (for the pictures), after the running
    certificate for ``turns`` more turns, either at most to t_max. Raises ValueError for
    settings atlas cannot certify (:func:`atlas.labels.labelling.check_integration`) or a barrier whose
    direction is not sign(τ), TypeError for a ``running`` that is not a RunningBarrier.
    ``method``: the discretisation (:data:`atlas.kernels.METHODS`), as :func:`atlas.label`'s
    straightforward kernel of that method steps it."""
    torque = float(torque)
    check_integration(alpha, omega0, dt, t_max, check_every, torque)
    method = resolve_method("cpu", "straightforward", method)
    check_running(running, torque, method)
    theta0, theta_dot0 = float(theta0), float(theta_dot0)
    w2 = omega0 * omega0
    margin = trap_margin(dt, alpha, omega0)
    cap = energy_cap(dt, alpha, omega0, torque)
    shift = _shift(omega0, torque) if torque else 0.0
    vers = 2.0 * math.sin(0.5 * shift) ** 2
    if running is not None:
        sign, r_theta0, r_g, r_top = (float(running.direction), running.theta0,
                                      running.g.tolist(), running.top)
    n_checks = n_checks_for(t_max, dt, check_every)
    th, v = theta0, theta_dot0
    thetas, speeds = [th], [v]
    result = {"status": UNRESOLVED}
    for j in range(n_checks + 1):
        if not (math.isfinite(th) and math.isfinite(v)):
            result = {"status": NONFINITE}
            break
        k, energy = _well_energy(th, v, w2, torque, shift, vers, method)
        if energy < cap:
            result = {"status": TRAPPED, "k": int(k), "t_trap": j * check_every * dt,
                      "energy": energy, "trap_index": len(thetas) - 1}
            break
        if running is not None and _in_band(th, v, sign, r_theta0, r_g, r_top):
            result = {"status": RUNNING, "t_trap": j * check_every * dt,
                      "trap_index": len(thetas) - 1, "direction": running.direction}
            break
        if j == n_checks:
            break
        th, v = _steps(th, v, check_every, alpha, omega0, dt, torque, method,
                   thetas, speeds)
    limit = n_checks * check_every
    if result["status"] == TRAPPED:
        level = settle * (2.0 * w2 if torque == 0.0 else
                          min(_saddle_energies(alpha, omega0, torque)))
        while (len(thetas) - 1 < limit
               and _well_energy(th, v, w2, torque, shift, vers, method)[1] > level):
            th, v = _steps(th, v, check_every, alpha, omega0, dt, torque, method,
                   thetas, speeds)
    elif result["status"] == RUNNING:
        start = th
        while len(thetas) - 1 < limit and abs(th - start) < turns * TWO_PI:
            th, v = _steps(th, v, check_every, alpha, omega0, dt, torque, method,
                   thetas, speeds)
    theta, theta_dot = np.array(thetas), np.array(speeds)
    return Orbit(theta0, theta_dot0, float(alpha), float(omega0), float(dt), float(t_max),
                 np.arange(theta.size) * dt, theta, theta_dot, cap=cap, margin=margin,
                 torque=torque, barrier=running, **result)


def _saddle_energies(alpha: float, omega0: float, torque: float) -> tuple[float, float]:
    from atlas.physics.pendulum import Pendulum

    return Pendulum(alpha, omega0, torque).saddle_energies


# ---- the running certificate ------------------------------------------------------------

def cycle_from_group(ds):
    """The :class:`atlas.physics.running.LimitCycle` stored in a parameter point's ``/limit_cycle``
    node (the arrays and attributes the sweep wrote; :func:`atlas.pipeline.points.limit_cycle_dataset`)."""
    from atlas.physics.running import LimitCycle

    theta = np.asarray(ds["theta"].values, np.float64)
    return LimitCycle(theta0=float(theta[0]), theta=theta,
                      theta_dot=np.asarray(ds["theta_dot"].values, np.float64),
                      time=np.asarray(ds["time"].values, np.float64),
                      period=float(ds.attrs["period"]), direction=int(ds.attrs["direction"]),
                      error=float(ds.attrs.get("relative_error", math.nan)))


def running_barrier_for(alpha: float, omega0: float, torque: float, dt: float, cycle=None):
    """(running certificate, limit cycle) as the sweep builds them for its kernels:
    :func:`atlas.physics.running.running_barrier` at the RK4 step ``dt`` around ``cycle`` (a
    LimitCycle, or a ``/limit_cycle`` node's dataset; computed by
    :func:`atlas.physics.running.limit_cycle` when None). (None, None) when τ = 0 or there is no
    running cycle. Raises AtlasError where no barrier can be verified (dt too coarse)."""
    from atlas.physics import running

    if torque == 0.0:
        return None, None
    if cycle is None:
        cycle = running.limit_cycle(alpha, omega0, torque)
        if cycle is None:
            return None, None
    elif not isinstance(cycle, running.LimitCycle):
        cycle = cycle_from_group(cycle)
    try:
        barrier = running.running_barrier(alpha, omega0, torque, cycle, dt=dt)
    except (ValueError, RuntimeError) as exc:
        raise AtlasError(f"running certificate: {exc}") from None
    return barrier, cycle


def parse_number(text: str, name: str) -> float:
    """A number or π expression from the command line, or one AtlasError naming it."""
    from atlas.pipeline.config import parse_pi_expression

    try:
        return parse_pi_expression(str(text))
    except ValueError as exc:
        raise AtlasError(f"{name}: {exc}") from None


# ---- the file ---------------------------------------------------------------------------

def _listed(every: list[dict]) -> str:
    with_torque = any(p.get("torque", 0.0) for p in every)
    names = ("alpha", "omega0", "torque") if with_torque else ("alpha", "omega0")
    text = ", ".join("(" + ", ".join(f"{p.get(n, 0.0):g}" for n in names) + ")"
                     for p in every[:12]) + (", …" if len(every) > 12 else "")
    return f"{', '.join(names)} = {text}"


def _point(tree, path: Path, alpha: float | None, omega0: float | None,
           torque: float | None = None):
    """The basin map of the parameter point (α, ω0, τ) asked for (the only one when not
    asked), its parameters, and its indices along the swept dims for
    :func:`atlas.views.plotting.basin_map`."""
    from atlas.layout import at_point, points

    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    listed = _listed(every)
    asked = {"alpha": alpha, "omega0": omega0, "torque": torque}
    if all(value is None for value in asked.values()):
        if len(every) > 1:
            options = ("--alpha, --omega0 and --torque" if "torque" in ds.dims
                       else "--alpha and --omega0")
            raise AtlasError(f"{path}: a parameter atlas of {len(every)} points; choose one "
                             f"with {options} ({listed})")
        fits = every
    else:
        fits = [p for p in every
                if all(value is None
                       or math.isclose(p.get(name, 0.0), value, rel_tol=1e-9, abs_tol=1e-300)
                       for name, value in asked.items())]
        if len(fits) != 1:
            wanted = "".join(f" {name} = {value:g}" for name, value in asked.items()
                             if value is not None)
            raise AtlasError(f"{path}: no single parameter point with{wanted} ({listed})")
    chosen = fits[0]
    index = {name: int(np.flatnonzero(ds[name].values == chosen[name])[0])
             for name in chosen if name in ds.dims}
    return at_point(ds, chosen), chosen, index


def _nearest(point, theta0: float, theta_dot0: float) -> dict:
    th, v = point["theta0"].values, point["theta_dot0"].values
    i, j = int(np.abs(th - theta0).argmin()), int(np.abs(v - theta_dot0).argmin())
    status = int(point["status"].values[j, i])
    out = {"theta0": float(th[i]), "theta_dot0": float(v[j]), "status": status,
           "k": int(point["attractor"].values[j, i]) if status in (TRAPPED, 3) else None,
           "t_trap": float(point["t_trap"].values[j, i]),
           "distance": (float(point["boundary_distance"].values[j, i])
                        if "boundary_distance" in point else math.nan)}
    out["inside"] = bool(th[0] <= theta0 <= th[-1] and v[0] <= theta_dot0 <= v[-1])
    return out


def _exact(orbit: Orbit, window, shift: float, tol: float):
    """(distance to the nearest exact basin boundary, the exact side: k or RUNNING_SIDE,
    d_cert) by :class:`atlas.boundaries.certificate.Certifier` over ``window``; (inf, RUNNING_SIDE, 0)
    for a pendulum without rest states (|τ| > ω0²: no boundary, every orbit runs);
    AtlasError at the saddle-node |τ| = ω0²."""
    from atlas.boundaries.certificate import RUNNING_SIDE, Certifier
    from atlas.physics.pendulum import Pendulum

    p = Pendulum(orbit.alpha, orbit.omega0, orbit.torque)
    if abs(p.torque) > p.omega0**2:
        return math.inf, RUNNING_SIDE, 0.0
    if p.torque != 0.0 and not p.has_rest_states:
        raise AtlasError("|torque| = omega0^2 is the saddle-node bifurcation: atlas certifies "
                         "no basin there; take |torque| below or above omega0^2")
    (t0, t1), (v0, v1) = window
    cert = Certifier(p, [t0, t1], [v0, v1], shift, tol)
    k = np.array([orbit.k if orbit.k is not None else 0])
    status = np.array([orbit.status], np.int8)
    _, dist, side, _ = cert.certify(np.array([orbit.theta0]), np.array([orbit.theta_dot0]),
                                    k, status)
    return float(dist[0]), int(side[0]), cert.d_cert


def _basin_name(side: int) -> str:
    from atlas.boundaries.certificate import RUNNING_SIDE

    return "the running basin" if side == RUNNING_SIDE else f"k = {side:+d}"


def report(theta0: float, theta_dot0: float, *, file: str | Path | None = None,
           alpha: float | None = None, omega0: float | None = None,
           dt: float | None = None, t_max: float | None = None,
           torque: float | None = None):
    """The orbit and the lines ``atlas orbit`` prints: (Orbit, lines, context for
    :func:`plot_orbit`). With ``file``, α, ω0, τ, dt, t_max come from the atlas (α/ω0/τ
    select a parameter point) and the running certificate is rebuilt from its stored limit
    cycle; without, α and ω0 are required, τ defaults to 0 and the limit cycle is computed."""
    import atlas

    tree = point = None
    nearest = None
    method = defaults.METHOD
    shift = tol = math.nan
    index = {}
    stored_cycle = None
    if file is not None:
        from atlas.store.atlasfile import open_atlas

        path = Path(file)
        tree = open_atlas(path)
        ds = tree.to_dataset(inherit=False)
        point, params, index = _point(tree, path, alpha, omega0, torque)
        alpha, omega0 = params["alpha"], params["omega0"]
        torque = params.get("torque", 0.0)
        file_dt, file_t_max = float(ds.attrs["dt"]), float(ds.attrs["t_max"])
        for name, given, stored in (("dt", dt, file_dt), ("t_max", t_max, file_t_max)):
            if given is not None and not math.isclose(given, stored, rel_tol=1e-12):
                raise AtlasError(f"--{name.replace('_', '-')} {given:g}: {path} was computed "
                                 f"with {name} = {stored:g}; drop the option")
        dt, t_max = file_dt, file_t_max
        method = file_method(ds.attrs, path)
        nearest = _nearest(point, theta0, theta_dot0)
        if "boundary_shift" in point:
            shift = float(point["boundary_shift"])
        sep = point_group(tree, "separatrices", params)
        if sep is not None:
            tol = float(sep.attrs.get("tol", math.nan))
        stored_cycle = point_group(tree, "limit_cycle", params)
    elif alpha is None or omega0 is None:
        raise AtlasError("give --alpha and --omega0, or an atlas file: "
                         "atlas orbit [FILE] THETA0 THETA_DOT0")
    torque = 0.0 if torque is None else float(torque)
    dt = defaults.DT if dt is None else dt
    t_max = defaults.T_MAX if t_max is None else t_max
    try:
        check_integration(alpha, omega0, dt, t_max, CHECK_EVERY, torque)
        if file is not None and stored_cycle is None:
            barrier = cycle = None  # the file has no running cycle here: nor had its kernels
        else:
            barrier, cycle = running_barrier_for(alpha, omega0, torque, dt, stored_cycle)
        orbit = integrate(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=torque,
                          running=barrier, dt=dt, t_max=t_max, method=method)
        kernel = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=torque,
                             running=barrier, dt=dt, t_max=t_max, kernel="straightforward",
                             method=method)
    except (ValueError, OverflowError) as exc:
        raise AtlasError(str(exc)) from None
    orbit = dataclasses.replace(orbit, cycle=cycle)

    tilt = f", torque = {torque:g} rad/s^2" if torque else ""
    lines = [f"orbit        from theta0 = {theta0:.10g} rad, theta_dot0 = {theta_dot0:.10g} "
             f"rad/s; alpha = {alpha:g} 1/s, omega0 = {omega0:g} rad/s{tilt}, dt = {dt:g} s, "
             f"t_max = {t_max:g} s, method {method}"]
    same = (int(kernel.status) == orbit.status
            and (orbit.k is None or int(kernel.attractor) == orbit.k))
    kernel_k = ("" if int(kernel.status) != TRAPPED else f", k = {int(kernel.attractor)}")
    agree = "the same as atlas.label" if same else (
        f"atlas.label says status {STATUS_NAMES[int(kernel.status)]}{kernel_k}: a point on a "
        "knife edge, decided by rounding")
    if orbit.status == TRAPPED:
        lines += _trapped_lines(orbit, agree)
    elif orbit.status == RUNNING:
        lines += _running_lines(orbit, agree)
    else:
        why = ("NaN or inf met" if orbit.status == NONFINITE else
               "neither trapped nor certified running by t_max" if barrier is not None else
               "not trapped by t_max")
        lines += [f"label        none: {STATUS_NAMES[orbit.status]} ({why}) ({agree})"]

    if orbit.status in (TRAPPED, RUNNING):
        if nearest is not None:
            window = ((float(point["theta0"][0]), float(point["theta0"][-1])),
                      (float(point["theta_dot0"][0]), float(point["theta_dot0"][-1])))
            if not nearest["inside"]:
                window = _around(orbit, window)
        else:
            window = _around(orbit, None)
        dist, side, d_cert = _exact(orbit, window, shift, tol)
        where = ("Certifier: distance to the exact basin boundaries, the DOP853 stable "
                 "manifolds" + (" of the tilted saddles" if torque else ""))
        from atlas.boundaries.certificate import RUNNING_SIDE

        own = RUNNING_SIDE if orbit.status == RUNNING else orbit.k
        if side != own:
            verdict = (f"the exact equation's side of the boundaries is {_basin_name(side)}, "
                       "not the RK4 label's: certified for the RK4 map only")
        elif d_cert == d_cert:
            verdict = (f"{'>' if dist > d_cert else '<='} d_cert = {d_cert:.2g}: "
                       + ("certified for the exact equation" if dist > d_cert else
                          "certified for the RK4 map only"))
        else:
            verdict = ("on the exact side; d_cert needs the RK4 map's boundary shift, which "
                       "`atlas run` measures (give an atlas file with separatrices) — "
                       "certified for the RK4 map only until then")
        lines.append(f"exact        boundary distance {dist:.4g} ({where}); {verdict}")
    if nearest is not None:
        grid_k = "none" if nearest["k"] is None else f"{nearest['k']:+d}"
        lines.append(
            f"file         nearest grid point theta0 = {nearest['theta0']:.6g}, theta_dot0 = "
            f"{nearest['theta_dot0']:.6g}: stored k = {grid_k}, status "
            f"{STATUS_NAMES.get(nearest['status'], nearest['status'])}, t_trap "
            f"{nearest['t_trap']:.2f} s, boundary distance {nearest['distance']:.4g}"
            + ("" if nearest["inside"] else " (the orbit starts outside the atlas window)"))
    context = {"tree": tree, "index": index, "nearest": nearest}
    return orbit, lines, context


def _rest(k: int) -> str:
    """"theta*", "theta* + 2pi", "theta* - 4pi": the rest state of well k with a torque."""
    return "theta*" if k == 0 else f"theta* {'-' if k < 0 else '+'} {_pi(abs(2 * k))}"


def _trapped_lines(orbit: Orbit, agree: str) -> list[str]:
    k = orbit.k
    if orbit.torque == 0.0:
        phi = orbit.theta[orbit.trap_index] - TWO_PI * k
        return [
            f"label        k = {k:+d}: settles at ({_pi(2 * k)}, 0) ({agree})",
            f"t_trap       {orbit.t_trap:.2f} s",
            f"certificate  energy trap at t_trap: |theta - 2pi k| = {abs(phi):.4f} <= pi and "
            f"E_k = {orbit.energy:.10g} < 2 omega0^2 (1 - m) = {orbit.cap:.10g} "
            f"(m = {orbit.margin:.2g}): the RK4 map's orbit never leaves well {k:+d}",
        ]
    s = orbit.rest_angle
    phi = orbit.theta[orbit.trap_index] - TWO_PI * k
    lower = min(_saddle_energies(orbit.alpha, orbit.omega0, orbit.torque))
    return [
        f"label        k = {k:+d}: settles at ({_rest(k)}, 0) = ({s + TWO_PI * k:.10g}, 0), "
        f"theta* = asin(torque/omega0^2) = {s:.10g} ({agree})",
        f"t_trap       {orbit.t_trap:.2f} s",
        f"certificate  tilted energy trap at t_trap: theta - 2pi k = {phi:.4f} in "
        f"[-pi - theta*, pi - theta*) (between the well's two saddles) and E_k = "
        f"{orbit.energy:.10g} < dE (1 - m) - rounding = {orbit.cap:.10g} (dE = {lower:.10g}, "
        f"the lower saddle's energy above the rest state; m = {orbit.margin:.2g}): the RK4 "
        f"map's orbit never leaves well {k:+d}",
    ]


def _running_lines(orbit: Orbit, agree: str) -> list[str]:
    b, d = orbit.barrier, orbit.direction
    i = orbit.trap_index
    th, v = float(orbit.theta[i]), float(orbit.theta_dot[i])
    lower = _lower(b.g.tolist(), b.theta0, d * th)
    cycle = ""
    if orbit.cycle is not None:
        cycle = (f", period {orbit.cycle.period:.6g} s, mean theta_dot "
                 f"{orbit.cycle.mean_theta_dot:.6g} rad/s")
    verified = ""
    if getattr(b, "verified_margin", None) is not None:
        step = "" if getattr(b, "dt", None) is None else f" for the RK4 step dt = {b.dt:g} s"
        verified = (f", flow across the lower curve verified >= {b.verified_margin:.3g} "
                    f"rad/s^2{step}")
    frame = "theta_dot" if d > 0 else "-theta_dot"
    where = "g(theta)" if d > 0 else "g(-theta)"
    return [
        f"label        running: converges to the running limit cycle (direction {d:+d}"
        f"{cycle}) ({agree})",
        f"t_trap       {orbit.t_trap:.2f} s (certified running)",
        f"certificate  running barrier at t_trap: (theta, theta_dot) = ({th:.4f}, {v:.4f}) "
        f"with {where} = {lower:.6g} <= {frame} = {d * v:.6g} <= top = {b.top:.6g} rad/s "
        f"(lower curve of {b.g.size - 1} segments{verified}): the RK4 map's orbit stays in "
        f"the band around the limit cycle (direction {d:+d})",
    ]


def _around(orbit: Orbit, window):
    """A window that holds the initial condition (the file's, grown if needed)."""
    (t0, t1), (v0, v1) = window if window is not None else ((-math.pi, math.pi), (-1.0, 1.0))
    return ((min(t0, orbit.theta0 - 1.0), max(t1, orbit.theta0 + 1.0)),
            (min(v0, orbit.theta_dot0 - 1.0), max(v1, orbit.theta_dot0 + 1.0)))


def _pi(n: int) -> str:
    return "0" if n == 0 else f"{'-' if n < 0 else ''}{'' if abs(n) == 1 else abs(n)}pi"


def _pi_label(n: int) -> str:
    return "0" if n == 0 else ("−" if n < 0 else "") + ("" if abs(n) == 1 else str(abs(n))) + "π"


#: The θ(t) panel marks wells and saddles only while it spans at most this many turns.
MAX_TURNS_MARKED = 24


def _draw_cycle(ax, cycle, lo: float, hi: float) -> None:
    """The limit cycle (dashed), repeated 2π-periodically over θ ∈ [lo, hi]."""
    from atlas.views.plotting import CYCLE_COLOR

    order = np.argsort(cycle.theta)
    theta, speed = np.asarray(cycle.theta)[order], np.asarray(cycle.theta_dot)[order]
    first = math.floor((lo - theta.max()) / TWO_PI)
    last = math.ceil((hi - theta.min()) / TWO_PI)
    for i, n in enumerate(range(first, last + 1)):
        ax.plot(theta + TWO_PI * n, speed, color=CYCLE_COLOR, lw=1.4, ls="--", zorder=4,
                label=f"limit cycle (period {cycle.period:.4g} s)" if i == 0 else None)


def plot_orbit(orbit: Orbit, output: str | Path, tree=None, index=None) -> Path:
    """Write the orbit's phase curve (over the basin map when ``tree`` is given: essay Figure
    9, with the running basin and the limit cycle for a torque atlas) and θ(t) (essay
    Figure 6) side by side to ``output`` (PNG). Without a file the (tilted) critical points
    and the limit cycle (when known) are drawn under the curve."""
    import matplotlib
    from matplotlib.figure import Figure  # no pyplot: a file, never a window or a backend

    from atlas.physics.pendulum import Pendulum, critical_points
    from atlas.views.plotting import STYLE, basin_map, critical_point_markers, pi_ticks, point_title

    output = Path(output)
    pendulum = Pendulum(orbit.alpha, orbit.omega0, orbit.torque)
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(13, 4.8))
        ax, ax_t = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.35, 1]})
        if tree is not None:
            basin_map(tree, ax=ax, **(index or {}))
        else:
            lo = min(-math.pi, orbit.theta.min()) - 0.5
            hi = max(math.pi, orbit.theta.max()) + 0.5
            pts = critical_points(pendulum, lo, hi)
            critical_point_markers(ax, [p.theta for p in pts], [p.is_saddle for p in pts],
                                   tilted=orbit.torque != 0.0)
            if orbit.cycle is not None:
                _draw_cycle(ax, orbit.cycle, lo, hi)
            ax.set_xlim(lo, hi)
            pi_ticks(ax, lo, hi)
            ax.set_xlabel("θ [rad]")
            ax.set_ylabel("θ̇ [rad/s]")
            ax.set_title("Phase curve, " + point_title(
                {"alpha": orbit.alpha, "omega0": orbit.omega0, "torque": orbit.torque}))
            ax.legend(loc="upper right")
        ax.plot(orbit.theta, orbit.theta_dot, color="white", lw=3.0, zorder=6)
        ax.plot(orbit.theta, orbit.theta_dot, color="black", lw=1.2, zorder=7, label="orbit")
        ax.plot(orbit.theta0, orbit.theta_dot0, "o", mfc="white", mec="black", ms=7, zorder=8)
        if orbit.trap_index is not None:
            i = orbit.trap_index
            ax.plot(orbit.theta[i], orbit.theta_dot[i], "x", color="black", ms=8, mew=2,
                    zorder=8)
        ax_t.plot(orbit.t, orbit.theta, color="black", lw=1.2)
        lo, hi = float(orbit.theta.min()), float(orbit.theta.max())
        if hi - lo <= MAX_TURNS_MARKED * TWO_PI:
            for p in critical_points(pendulum, lo - math.pi, hi + math.pi):
                ax_t.axhline(p.theta, color="red" if p.is_saddle else "0.5",
                             ls=":" if p.is_saddle else "--", lw=0.8)
            ns = range(math.ceil((lo - 0.5) / math.pi), math.floor((hi + 0.5) / math.pi) + 1)
            ax_t.set_yticks([n * math.pi for n in ns])
            ax_t.set_yticklabels([_pi_label(n) for n in ns])
        if orbit.status == TRAPPED:
            rest = ("" if orbit.torque == 0.0 else
                    f" (rest at θ = {orbit.rest_angle + TWO_PI * orbit.k:.4g})")
            ax_t.axvline(orbit.t_trap, color="tab:blue", lw=1,
                         label=f"trapped in well {orbit.k:+d} at t = {orbit.t_trap:.2f} s{rest}")
            ax_t.legend(loc="best")
        elif orbit.status == RUNNING:
            ax_t.axvline(orbit.t_trap, color="tab:blue", lw=1,
                         label=f"certified running ({orbit.direction:+d}) at t = "
                         f"{orbit.t_trap:.2f} s")
            ax_t.legend(loc="best")
        ax_t.set_ylim(lo - 0.5, hi + 0.5)
        ax_t.set_xlabel("t [s]")
        ax_t.set_ylabel("θ [rad]")
        ax_t.set_title(f"θ(t) from θ0 = {orbit.theta0:.4g}, θ̇0 = {orbit.theta_dot0:.4g} "
                       "(wells dashed, saddles dotted)")
        fig.tight_layout()
        try:
            fig.savefig(output)
        except OSError as exc:
            raise AtlasError(f"{output}: cannot write the figure ({exc.strerror or exc})"
                             ) from None
    return output


def default_output(file: str | Path | None) -> Path:
    """Where ``atlas orbit`` writes its PNG by default: next to the atlas, else outputs/."""
    if file is not None:
        file = Path(file)
        return file.with_name(file.stem + "_orbit.png")
    return Path("outputs") / "orbit.png"


def check_file_argument(text: str) -> None:
    """Refuse a first positional argument that is neither a number nor an existing file."""
    path = Path(text)
    if not path.exists():
        raise InputFileError(f"{text}: no such file (atlas orbit [FILE] THETA0 THETA_DOT0)")
