"""``atlas orbit``: one orbit — its label, its certificate, and its pictures (the essay's
Figure 9 phase curve over the basin map, and Figure 6's θ(t), for any initial condition).

:func:`report` follows the orbit (:mod:`atlas.commands.orbit_integrate`) with the
certificate of an atlas file's run, read from the file (:mod:`atlas.commands.orbit_file`;
format 4), or without a file with the running barrier built here
(:func:`running_barrier_for`); takes the label from :func:`atlas.label` too (the two must
agree); adds the certificate for the exact equation (the distance to the exact basin
boundaries from :class:`atlas.boundaries.certificate.Certifier`, DOP853 stable manifolds,
tilted by the torque where it has one, against the file's ``d_cert``) and the file's stored
label at the nearest grid point; and writes it all as lines (:mod:`atlas.commands.
orbit_text`). The figure: :mod:`atlas.commands.orbit_figure`.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from atlas import defaults
from atlas.commands.orbit_file import FilePoint, nearest_grid_point, open_point
from atlas.commands.orbit_integrate import Orbit, integrate
from atlas.commands.orbit_text import (
    exact_line,
    file_line,
    header_line,
    label_lines,
    outside_line,
)
from atlas.errors import AtlasError, InputFileError
from atlas.labels.labelling import check_integration
from atlas.labels.trap import CHECK_EVERY
from atlas.status import RUNNING, TRAPPED

__all__ = ["report", "running_barrier_for", "parse_number", "default_output", "looks_like_file",
           "check_file_argument", "file_model", "plot", "DRIVE_PARAMETERS"]

#: The driven pendulum's parameters that only its atlases have (``atlas orbit`` options that
#: select a point of one).
DRIVE_PARAMETERS = ("amplitude", "frequency", "phase")


def running_barrier_for(alpha: float, omega0: float, torque: float, dt: float):
    """(running certificate, limit cycle) as the sweep builds them for its kernels, from the
    parameters: :func:`atlas.physics.running.running_barrier` at the RK4 step ``dt`` around
    :func:`atlas.physics.running.limit_cycle`. (None, None) when τ = 0 or there is no running
    cycle. Raises AtlasError where no barrier can be verified (dt too coarse)."""
    from atlas.physics.pendulum import Pendulum
    from atlas.physics.running import running_certificate

    try:
        cycle, barrier = running_certificate(Pendulum(alpha, omega0, torque), dt)
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


def _exact(orbit: Orbit, window, shift: float, tol: float):
    """(distance to the nearest exact basin boundary, the exact side: k or RUNNING_SIDE,
    d_cert) by the certifier of the exact boundaries over ``window``
    (:func:`atlas.boundaries.certificate.certifier_for`: for a pendulum without rest states,
    |τ| > ω0², no boundary, every orbit runs: (inf, RUNNING_SIDE, 0)); AtlasError at the
    saddle-node |τ| = ω0²."""
    from atlas.boundaries.certificate import certifier_for
    from atlas.physics.pendulum import Pendulum

    (t0, t1), (v0, v1) = window
    try:
        cert = certifier_for(Pendulum(orbit.alpha, orbit.omega0, orbit.torque), [t0, t1],
                             [v0, v1], shift, tol)
    except ValueError as exc:
        raise AtlasError(f"{exc}; take |torque| below or above omega0^2") from None
    k = np.array([orbit.k if orbit.k is not None else 0])
    status = np.array([orbit.status], np.int8)
    _, dist, side, _ = cert.certify(np.array([orbit.theta0]), np.array([orbit.theta_dot0]),
                                    k, status)
    return float(dist[0]), int(side[0]), cert.d_cert


def _around(orbit: Orbit, window):
    """A window that holds the initial condition (the file's, grown if needed)."""
    (t0, t1), (v0, v1) = window if window is not None else ((-math.pi, math.pi), (-1.0, 1.0))
    return ((min(t0, orbit.theta0 - 1.0), max(t1, orbit.theta0 + 1.0)),
            (min(v0, orbit.theta_dot0 - 1.0), max(v1, orbit.theta_dot0 + 1.0)))


def _follow(theta0: float, theta_dot0: float, source: FilePoint | None, alpha, omega0,
            torque: float, dt: float, t_max: float):
    """(the orbit, atlas.label's label of it): with the certificate of ``source`` (a file's
    point) as its run used it, else with the running barrier built from the parameters."""
    import atlas

    if source is not None:
        cycle, barrier = source.cycle, source.barrier
        method, check_every = source.method, source.check_every
        trap = {"cap": source.cap, "margin": source.margin}
    else:
        method, check_every, trap = defaults.METHOD, CHECK_EVERY, {}
    try:
        check_integration(alpha, omega0, dt, t_max, check_every, torque)
        if source is None:
            barrier, cycle = running_barrier_for(alpha, omega0, torque, dt)
        orbit = integrate(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=torque,
                          running=barrier, dt=dt, t_max=t_max, method=method,
                          check_every=check_every, **trap)
        kernel = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=torque,
                             running=barrier, dt=dt, t_max=t_max, kernel="straightforward",
                             method=method, check_every=check_every)
    except (ValueError, OverflowError) as exc:
        raise AtlasError(str(exc)) from None
    return dataclasses.replace(orbit, cycle=cycle), kernel


def file_model(file: str | Path) -> str:
    """The name of the model whose atlas ``file`` is (:func:`atlas.models.registry.of_attrs`;
    AtlasError for a model atlas does not know)."""
    from atlas.models.registry import of_attrs
    from atlas.store.reader import open_atlas

    tree = open_atlas(Path(file))
    try:
        return of_attrs(tree.attrs).name
    except ValueError as exc:
        raise InputFileError(f"{file}: {exc}") from None
    finally:
        tree.close()


def _driven_report(theta0: float, theta_dot0: float, file: str | Path, *,
                   dt: float | None = None, t_max: float | None = None,
                   **asked: float | None):
    """:func:`report` of a driven pendulum's atlas: (DrivenOrbit, lines, context: the opened
    ``tree``, which the caller closes, the point's ``index``, the ``nearest`` grid point's
    stored labels and the point's ``/attractors`` node, ``group``)."""
    from atlas.commands.orbit_driven import follow, nearest_stored, open_driven_point
    from atlas.commands.orbit_driven_text import driven_lines

    source = open_driven_point(file, dt=dt, t_max=t_max, **asked)
    try:
        orbit = follow(source.labeller, theta0, theta_dot0, source.t_max)
        nearest = nearest_stored(source.point, theta0, theta_dot0)
        lines = driven_lines(orbit, source.params, source.group, nearest, source.point)
    except BaseException:
        source.tree.close()
        raise
    return orbit, lines, {"tree": source.tree, "index": source.index, "nearest": nearest,
                          "group": source.group}


def report(theta0: float, theta_dot0: float, *, file: str | Path | None = None,
           alpha: float | None = None, omega0: float | None = None,
           dt: float | None = None, t_max: float | None = None,
           torque: float | None = None, **drive: float | None):
    """The orbit and the lines ``atlas orbit`` prints: (Orbit, lines, context for
    :func:`plot`: the opened ``tree`` or None, which the caller closes, and the point's
    ``index``). With ``file``, α, ω0, τ, dt, t_max come from the atlas (α/ω0/τ select a
    parameter point) and so does the certificate its run used (format 4; a file of format 3
    is refused with one line); without, α and ω0 are required, τ defaults to 0 and the limit
    cycle and its barrier are computed. A driven pendulum's atlas is followed by
    :func:`_driven_report` (``drive``: amplitude, frequency, phase select
    one of its points, with α, ω0 and τ); its orbit is a DrivenOrbit."""
    from atlas.models.registry import DRIVEN

    given = [name for name in DRIVE_PARAMETERS if drive.get(name) is not None]
    if set(drive) - set(DRIVE_PARAMETERS):
        raise TypeError(f"report() got unexpected options {sorted(set(drive))}")
    if file is not None and file_model(file) == DRIVEN:
        return _driven_report(theta0, theta_dot0, file, dt=dt, t_max=t_max, alpha=alpha,
                              omega0=omega0, torque=torque, **drive)
    if given:
        raise AtlasError(f"--{given[0]} selects a point of a driven pendulum's atlas; "
                         + ("give one" if file is None else f"{file} is not one"))
    source = None
    if file is not None:
        source = open_point(file, alpha, omega0, torque, dt, t_max)
        alpha, omega0 = source.params["alpha"], source.params["omega0"]
        torque, dt, t_max = source.params.get("torque", 0.0), source.dt, source.t_max
    elif alpha is None or omega0 is None:
        raise AtlasError("give --alpha and --omega0, or an atlas file: "
                         "atlas orbit [FILE] THETA0 THETA_DOT0")
    try:
        torque = 0.0 if torque is None else float(torque)
        dt = defaults.DT if dt is None else dt
        t_max = defaults.T_MAX if t_max is None else t_max
        orbit, kernel = _follow(theta0, theta_dot0, source, alpha, omega0, torque, dt, t_max)
        lines = [header_line(orbit), *label_lines(orbit, int(kernel.status),
                                                  int(kernel.attractor))]
        nearest = None if source is None else nearest_grid_point(source.point, theta0,
                                                                 theta_dot0)
        if orbit.status in (TRAPPED, RUNNING):
            window = None
            if nearest is not None:
                th, v = source.point["theta0"].values, source.point["theta_dot0"].values
                window = ((float(th[0]), float(th[-1])), (float(v[0]), float(v[-1])))
            if nearest is None or not nearest["inside"]:
                window = _around(orbit, window)
            shift, tol = (math.nan, math.nan) if source is None else (source.shift, source.tol)
            lines.append(exact_line(orbit, *_exact(orbit, window, shift, tol)))
        if nearest is not None:
            lines.append(file_line(nearest))
            if not nearest["inside"]:
                lines.insert(0, outside_line(source.point))
    except BaseException:
        if source is not None:
            source.tree.close()
        raise
    context = {"tree": None if source is None else source.tree,
               "index": {} if source is None else source.index, "nearest": nearest}
    return orbit, lines, context


def plot(orbit, output: str | Path, context: dict) -> Path:
    """Write the figure of an orbit :func:`report` returned, with its ``context``: the
    pendulum's (:func:`atlas.commands.orbit_figure.plot_orbit`) or a driven pendulum's
    (:func:`atlas.commands.orbit_driven_figure.plot_driven_orbit`)."""
    if "group" in context:  # a driven pendulum's orbit: its point's /attractors node
        from atlas.commands.orbit_driven_figure import plot_driven_orbit

        return plot_driven_orbit(orbit, output, context["tree"], context["index"],
                                 context["group"])
    from atlas.commands.orbit_figure import plot_orbit

    return plot_orbit(orbit, output, context["tree"], context["index"])


def default_output(file: str | Path | None, theta0: float, theta_dot0: float,
                   parameters: dict[str, float | None] | None = None) -> Path:
    """Where ``atlas orbit`` writes its PNG by default: next to the atlas, else in outputs/,
    named by the orbit's initial condition and the parameters given on the command line
    (``default_orbit_-1_2.5.png``, ``orbit_alpha_0.2_omega0_1_-1.571_3.3.png``), so that the
    orbits of different points keep their own figures."""
    given = [f"{name}_{value:.6g}" for name, value in (parameters or {}).items()
             if value is not None]
    tag = "_".join([*given, f"{theta0:.6g}", f"{theta_dot0:.6g}"])
    if file is not None:
        file = Path(file)
        return file.with_name(f"{file.stem}_orbit_{tag}.png")
    return Path("outputs") / f"orbit_{tag}.png"


def looks_like_file(text: str) -> bool:
    """Whether a positional argument of ``atlas orbit`` is meant as the atlas file: not a
    number or π expression, and an existing path or a name with a suffix or a folder."""
    from atlas.pipeline.config import parse_pi_expression

    try:
        parse_pi_expression(str(text))
    except ValueError:
        path = Path(text)
        return path.exists() or bool(path.suffix) or len(path.parts) > 1
    return False


def check_file_argument(text: str) -> None:
    """Refuse a first positional argument that is neither a number nor an existing file (the
    output of an interrupted run, not written yet, is left to the reader, whose message says
    how to finish it)."""
    from atlas.store.reader import interrupted_run

    path = Path(text)
    if not path.exists() and interrupted_run(path) is None:
        raise InputFileError(f"{text}: no such file (atlas orbit [FILE] THETA0 THETA_DOT0)")
