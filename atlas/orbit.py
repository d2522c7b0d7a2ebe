"""``atlas orbit``: one orbit — its label, its certificate, and its pictures (the essay's
Figure 9 phase curve over the basin map, and Figure 6's θ(t), for any initial condition).

:func:`integrate` follows one orbit with atlas's RK4 step and energy trap (the formulas of
:mod:`atlas.kernels.rk4` with ``math.sin``, the trap tested every ``check_every`` steps as
the kernels do), keeping the whole trajectory; the label itself is also taken from
:func:`atlas.label` and the two must agree. :func:`report` adds the certificate for the exact
equation: the distance to the exact basin boundaries from :class:`atlas.certificate.Certifier`
(DOP853 stable manifolds) compared with the file's ``d_cert``, and the file's stored values at
the nearest grid point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import defaults
from .errors import AtlasError, InputFileError
from .kernels import NONFINITE, TRAPPED, UNRESOLVED
from .labels import CHECK_EVERY, check_integration, n_checks_for, trap_margin
from .layout import point_group
from .validate import STATUS_MEANINGS

__all__ = ["Orbit", "integrate", "report", "plot_orbit", "parse_number"]

TWO_PI = 2.0 * math.pi
#: The name of each status code (as the file's CF flag_meanings say).
STATUS_NAMES = STATUS_MEANINGS


@dataclass(frozen=True)
class Orbit:
    """One orbit from (θ0 [rad], θ̇0 [rad s⁻¹]): its trajectory ``t`` [s], ``theta``,
    ``theta_dot`` (followed past the trap until it has nearly settled), and its label:
    ``status`` (0 trapped, 1 unresolved, 2 nonfinite), ``k``, ``t_trap`` [s], the well energy
    ``energy`` E_k at the trap against ``cap`` = 2ω0²(1 − m), ``margin`` m, and
    ``trap_index`` (the trajectory index of the trap)."""

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


def _step(theta, theta_dot, w2, a2, dt):
    """One classical RK4 step of eq. (1), written as :func:`atlas.kernels.rk4.make_rk4_step`."""
    h2 = 0.5 * dt
    k1t = theta_dot
    k1v = -w2 * math.sin(theta) - a2 * theta_dot
    k2t = theta_dot + h2 * k1v
    k2v = -w2 * math.sin(theta + h2 * k1t) - a2 * k2t
    k3t = theta_dot + h2 * k2v
    k3v = -w2 * math.sin(theta + h2 * k2t) - a2 * k3t
    k4t = theta_dot + dt * k3v
    k4v = -w2 * math.sin(theta + dt * k3t) - a2 * k4t
    h6 = dt / 6.0
    return (theta + h6 * (k1t + 2.0 * (k2t + k3t) + k4t),
            theta_dot + h6 * (k1v + 2.0 * (k2v + k3v) + k4v))


def _well_energy(theta, theta_dot, w2):
    k = math.floor(theta / TWO_PI + 0.5)
    s = math.sin(0.5 * (theta - TWO_PI * k))
    return k, 0.5 * theta_dot * theta_dot + 2.0 * w2 * s * s


def integrate(theta0: float, theta_dot0: float, *, alpha: float, omega0: float,
              dt: float = defaults.DT, t_max: float = defaults.T_MAX,
              check_every: int = CHECK_EVERY, settle: float = 1e-3) -> Orbit:
    """Follow one orbit with atlas's RK4 and energy trap (module docstring); after the trap,
    on until E_k < ``settle``·2ω0² (for the pictures) or t_max. Raises ValueError for
    settings atlas cannot certify (:func:`atlas.labels.check_integration`)."""
    check_integration(alpha, omega0, dt, t_max, check_every)
    theta0, theta_dot0 = float(theta0), float(theta_dot0)
    w2, a2 = omega0 * omega0, 2.0 * alpha
    margin = trap_margin(dt, alpha, omega0)
    cap = 2.0 * w2 * (1.0 - margin)
    n_checks = n_checks_for(t_max, dt, check_every)
    th, v = theta0, theta_dot0
    thetas, speeds = [th], [v]
    result = {"status": UNRESOLVED}
    for j in range(n_checks + 1):
        if not (math.isfinite(th) and math.isfinite(v)):
            result = {"status": NONFINITE}
            break
        k, energy = _well_energy(th, v, w2)
        if energy < cap:
            result = {"status": TRAPPED, "k": int(k), "t_trap": j * check_every * dt,
                      "energy": energy, "trap_index": len(thetas) - 1}
            break
        if j == n_checks:
            break
        for _ in range(check_every):
            th, v = _step(th, v, w2, a2, dt)
            thetas.append(th)
            speeds.append(v)
    if result["status"] == TRAPPED:
        limit = n_checks * check_every
        while len(thetas) - 1 < limit and _well_energy(th, v, w2)[1] > settle * 2.0 * w2:
            for _ in range(check_every):
                th, v = _step(th, v, w2, a2, dt)
                thetas.append(th)
                speeds.append(v)
    theta, theta_dot = np.array(thetas), np.array(speeds)
    return Orbit(theta0, theta_dot0, float(alpha), float(omega0), float(dt), float(t_max),
                 np.arange(theta.size) * dt, theta, theta_dot, cap=cap, margin=margin,
                 **result)


def parse_number(text: str, name: str) -> float:
    """A number or π expression from the command line, or one AtlasError naming it."""
    from .config import parse_pi_expression

    try:
        return parse_pi_expression(str(text))
    except ValueError as exc:
        raise AtlasError(f"{name}: {exc}") from None


# ---- the file ---------------------------------------------------------------------------

def _point(tree, path: Path, alpha: float | None, omega0: float | None):
    """The basin map of the parameter point (α, ω0) asked for (the only one when not asked),
    its parameters, and its indices along the swept dims for :func:`atlas.plotting.basin_map`."""
    from .layout import at_point, points

    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    listed = ", ".join(f"({p['alpha']:g}, {p['omega0']:g})" for p in every[:12]) \
        + (", …" if len(every) > 12 else "")
    if alpha is None and omega0 is None:
        if len(every) > 1:
            raise AtlasError(f"{path}: a parameter atlas of {len(every)} points; choose one "
                             f"with --alpha and --omega0 (alpha, omega0 = {listed})")
        fits = every
    else:
        fits = [p for p in every
                if (alpha is None or math.isclose(p["alpha"], alpha, rel_tol=1e-9))
                and (omega0 is None or math.isclose(p["omega0"], omega0, rel_tol=1e-9))]
        if len(fits) != 1:
            raise AtlasError(f"{path}: no single parameter point with"
                             f"{'' if alpha is None else f' alpha = {alpha:g}'}"
                             f"{'' if omega0 is None else f' omega0 = {omega0:g}'} "
                             f"(alpha, omega0 = {listed})")
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
    """(distance to the nearest exact basin boundary, the exact side k, d_cert) by
    :class:`atlas.certificate.Certifier` over ``window``."""
    from .certificate import Certifier
    from .model import Pendulum

    (t0, t1), (v0, v1) = window
    cert = Certifier(Pendulum(orbit.alpha, orbit.omega0), [t0, t1], [v0, v1], shift, tol)
    k = np.array([orbit.k if orbit.k is not None else 0])
    status = np.array([orbit.status], np.int8)
    _, dist, side, _ = cert.certify(np.array([orbit.theta0]), np.array([orbit.theta_dot0]),
                                    k, status)
    return float(dist[0]), int(side[0]), cert.d_cert


def report(theta0: float, theta_dot0: float, *, file: str | Path | None = None,
           alpha: float | None = None, omega0: float | None = None,
           dt: float | None = None, t_max: float | None = None):
    """The orbit and the lines ``atlas orbit`` prints: (Orbit, lines, context for
    :func:`plot_orbit`). With ``file``, α, ω0, dt, t_max come from the atlas (α/ω0 select a
    parameter point); without, α and ω0 are required."""
    import atlas

    tree = point = None
    nearest = None
    shift = tol = math.nan
    index = {}
    if file is not None:
        from .store import open_atlas

        path = Path(file)
        tree = open_atlas(path)
        ds = tree.to_dataset(inherit=False)
        point, params, index = _point(tree, path, alpha, omega0)
        alpha, omega0 = params["alpha"], params["omega0"]
        file_dt, file_t_max = float(ds.attrs["dt"]), float(ds.attrs["t_max"])
        for name, given, stored in (("dt", dt, file_dt), ("t_max", t_max, file_t_max)):
            if given is not None and not math.isclose(given, stored, rel_tol=1e-12):
                raise AtlasError(f"--{name.replace('_', '-')} {given:g}: {path} was computed "
                                 f"with {name} = {stored:g}; drop the option")
        dt, t_max = file_dt, file_t_max
        nearest = _nearest(point, theta0, theta_dot0)
        if "boundary_shift" in point:
            shift = float(point["boundary_shift"])
        sep = point_group(tree, "separatrices", params)
        if sep is not None:
            tol = float(sep.attrs.get("tol", math.nan))
    elif alpha is None or omega0 is None:
        raise AtlasError("give --alpha and --omega0, or an atlas file: "
                         "atlas orbit [FILE] THETA0 THETA_DOT0")
    dt = defaults.DT if dt is None else dt
    t_max = defaults.T_MAX if t_max is None else t_max
    try:
        orbit = integrate(theta0, theta_dot0, alpha=alpha, omega0=omega0, dt=dt, t_max=t_max)
        kernel = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, dt=dt,
                             t_max=t_max, kernel="straightforward")
    except (ValueError, OverflowError) as exc:
        raise AtlasError(str(exc)) from None

    lines = [f"orbit        from theta0 = {theta0:.10g} rad, theta_dot0 = {theta_dot0:.10g} "
             f"rad/s; alpha = {alpha:g} 1/s, omega0 = {omega0:g} rad/s, dt = {dt:g} s, "
             f"t_max = {t_max:g} s"]
    same = (int(kernel.status) == orbit.status
            and (orbit.k is None or int(kernel.attractor) == orbit.k))
    agree = "the same as atlas.label" if same else (
        f"atlas.label says status {STATUS_NAMES[int(kernel.status)]}, k = "
        f"{int(kernel.attractor)}: a point on a knife edge, decided by rounding")
    if orbit.status == TRAPPED:
        k, phi = orbit.k, orbit.theta[orbit.trap_index] - TWO_PI * orbit.k
        lines += [
            f"label        k = {k:+d}: settles at ({_pi(2 * k)}, 0) ({agree})",
            f"t_trap       {orbit.t_trap:.2f} s",
            f"certificate  energy trap at t_trap: |theta - 2pi k| = {abs(phi):.4f} <= pi and "
            f"E_k = {orbit.energy:.10g} < 2 omega0^2 (1 - m) = {orbit.cap:.10g} "
            f"(m = {orbit.margin:.2g}): the RK4 map's orbit never leaves well {k:+d}",
        ]
    else:
        lines += [f"label        none: {STATUS_NAMES[orbit.status]} "
                  f"({'not trapped by t_max' if orbit.status == UNRESOLVED else 'NaN or inf met'})"
                  f" ({agree})"]

    if orbit.status == TRAPPED:
        if nearest is not None:
            window = ((float(point["theta0"][0]), float(point["theta0"][-1])),
                      (float(point["theta_dot0"][0]), float(point["theta_dot0"][-1])))
            if not nearest["inside"]:
                window = _around(orbit, window)
        else:
            window = _around(orbit, None)
        dist, side, d_cert = _exact(orbit, window, shift, tol)
        where = ("Certifier: distance to the exact basin boundaries, the DOP853 stable "
                 "manifolds")
        if side != orbit.k:
            verdict = (f"the exact equation's side of the boundaries is k = {side:+d}, not the "
                       "RK4 label: certified for the RK4 map only")
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


def _around(orbit: Orbit, window):
    """A window that holds the initial condition (the file's, grown if needed)."""
    (t0, t1), (v0, v1) = window if window is not None else ((-math.pi, math.pi), (-1.0, 1.0))
    return ((min(t0, orbit.theta0 - 1.0), max(t1, orbit.theta0 + 1.0)),
            (min(v0, orbit.theta_dot0 - 1.0), max(v1, orbit.theta_dot0 + 1.0)))


def _pi(n: int) -> str:
    return "0" if n == 0 else f"{'-' if n < 0 else ''}{'' if abs(n) == 1 else abs(n)}pi"


def plot_orbit(orbit: Orbit, output: str | Path, tree=None, index=None) -> Path:
    """Write the orbit's phase curve (over the basin map when ``tree`` is given: essay Figure
    9) and θ(t) (essay Figure 6) side by side to ``output`` (PNG)."""
    import matplotlib.pyplot as plt

    from .model import Pendulum, critical_points
    from .plotting import STYLE, basin_map, critical_point_markers, pi_ticks

    output = Path(output)
    with plt.rc_context(STYLE):
        fig, (ax, ax_t) = plt.subplots(1, 2, figsize=(13, 4.8),
                                       gridspec_kw={"width_ratios": [1.35, 1]})
        if tree is not None:
            basin_map(tree, ax=ax, **(index or {}))
        else:
            lo = min(-math.pi, orbit.theta.min()) - 0.5
            hi = max(math.pi, orbit.theta.max()) + 0.5
            pts = critical_points(Pendulum(orbit.alpha, orbit.omega0), lo, hi)
            critical_point_markers(ax, [p.theta for p in pts], [p.is_saddle for p in pts])
            ax.set_xlim(lo, hi)
            pi_ticks(ax, lo, hi)
            ax.set_xlabel("θ [rad]")
            ax.set_ylabel("θ̇ [rad/s]")
            ax.set_title(f"Phase curve, α = {orbit.alpha:g} s⁻¹, ω0 = {orbit.omega0:g} rad/s")
            ax.legend(loc="upper right")
        ax.plot(orbit.theta, orbit.theta_dot, color="white", lw=3.0, zorder=6)
        ax.plot(orbit.theta, orbit.theta_dot, color="black", lw=1.2, zorder=7, label="orbit")
        ax.plot(orbit.theta0, orbit.theta_dot0, "o", mfc="white", mec="black", ms=7, zorder=8)
        if orbit.trap_index is not None:
            i = orbit.trap_index
            ax.plot(orbit.theta[i], orbit.theta_dot[i], "x", color="black", ms=8, mew=2,
                    zorder=8)
        ax_t.plot(orbit.t, orbit.theta, color="black", lw=1.2)
        lo, hi = orbit.theta.min(), orbit.theta.max()
        for n in range(math.floor(lo / math.pi) - 1, math.ceil(hi / math.pi) + 2):
            ax_t.axhline(n * math.pi, color="red" if n % 2 else "0.5",
                         ls=":" if n % 2 else "--", lw=0.8)
        if orbit.t_trap is not None:
            ax_t.axvline(orbit.t_trap, color="tab:blue", lw=1,
                         label=f"trapped in well {orbit.k:+d} at t = {orbit.t_trap:.2f} s")
            ax_t.legend(loc="best")
        ax_t.set_ylim(lo - 0.5, hi + 0.5)
        ax_t.set_yticks([n * math.pi for n in range(math.ceil((lo - 0.5) / math.pi),
                                                     math.floor((hi + 0.5) / math.pi) + 1)])
        ax_t.set_yticklabels([("−" if n < 0 else "") + ("" if abs(n) == 1 else str(abs(n)))
                              + "π" if n else "0" for n in
                              range(math.ceil((lo - 0.5) / math.pi),
                                    math.floor((hi + 0.5) / math.pi) + 1)])
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
        finally:
            plt.close(fig)
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
