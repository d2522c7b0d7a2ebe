"""``atlas zoom FILE THETA0 THETA_DOT0 --width W``: the config of a window centred on a point.

:func:`zoom_config` reads the parameter point of an atlas file (the only one, or the one
``alpha``, ``omega0``, ``torque`` select, as ``atlas orbit FILE`` does) and builds the YAML
config of a square window W wide in θ0 [rad] and in θ̇0 [rad s⁻¹], centred on (θ0, θ̇0),
``num`` × ``num`` orbits, at the file's α [s⁻¹], ω0 [rad s⁻¹], τ [rad s⁻²], integrator (dt,
t_max [s], method) and separatrix settings (tol, max_spacing). Every number is written with
full precision (``repr``), and the config is validated (:class:`atlas.pipeline.config.Config`)
before it is returned, so a config this module writes always runs: a window narrower than
the file's ``separatrices.tol`` allows (:func:`atlas.limits.check_separatrix_settings`), or
whose grid step W/(num − 1) is below 64 spacings of doubles at its largest coordinate (its
points would not be distinct doubles), is refused with one AtlasError line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from atlas.errors import AtlasError
from atlas.limits import MIN_TOL_ULPS

__all__ = ["Zoom", "zoom_config", "width_tag", "write_zoom", "DEFAULT_NUM"]

#: Orbits per axis of a zoom window by default: odd, so that the centre is a grid point.
DEFAULT_NUM = 101


@dataclass(frozen=True)
class Zoom:
    """A zoom window's config: ``text`` the YAML, ``config`` the validated
    :class:`atlas.pipeline.config.Config` it loads to."""

    text: str
    config: object


def width_tag(width: float) -> str:
    """A width as a short file-name tag: 1 → "1", 0.02 → "0.02", 1e-3 → "1e-3"."""
    if 1e-2 <= width < 1e4:
        return f"{width:.12g}"
    mantissa, exponent = f"{width:.11e}".split("e")
    mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{int(exponent)}"


def _yaml_number(x: float) -> str:
    """``repr`` of a float, written so that YAML reads it back as the same float (YAML 1.1
    reads 1e-06 as text: it needs a point in the mantissa, 1.0e-06)."""
    text = repr(float(x))
    if "e" in text and "." not in text.split("e")[0]:
        text = text.replace("e", ".0e", 1)
    return text


def _check_window(theta0: float, theta_dot0: float, width: float, num: int) -> None:
    """One AtlasError line unless a ``num`` × ``num`` grid ``width`` wide around
    (``theta0``, ``theta_dot0``) has distinct, well-separated points (the config validator
    then checks the rest: :func:`atlas.limits.check_separatrix_settings`)."""
    if not (math.isfinite(width) and width > 0):
        raise AtlasError(f"--width must be a finite number > 0, got {width:g}")
    if num < 2:
        raise AtlasError(f"--num must be at least 2, got {num}")
    step = width / (num - 1)
    scale = max(abs(theta0), abs(theta_dot0)) + width / 2
    need = MIN_TOL_ULPS * float(np.spacing(scale))
    if step < need:
        raise AtlasError(f"--width {width:g}: too narrow for double precision at |θ|, |θ̇| ≤ "
                         f"{scale:.3g}: its grid step {step:.2g} is below {MIN_TOL_ULPS} "
                         f"spacings of doubles ({need:.2g}); take a width of at least "
                         f"{need * (num - 1):.2g} (or a smaller --num)")


def zoom_config(file: str | Path, theta0: float, theta_dot0: float, width: float, *,
                num: int = DEFAULT_NUM, alpha: float | None = None,
                omega0: float | None = None, torque: float | None = None,
                output: str | Path | None = None, **drive: float | None) -> Zoom:
    """The config of the window ``width`` wide [rad, rad s⁻¹] centred on (``theta0``,
    ``theta_dot0``) at the parameter point of atlas ``file`` that ``alpha``, ``omega0``,
    ``torque`` (and for a driven pendulum's atlas ``drive``: amplitude, frequency, phase)
    select; its output ``output`` (default, next to the file:
    ``<file's stem>-zoom-<width>-at-<θ0>_<θ̇0>.h5``, so that two zooms of one width around
    different points name different atlases). Bad input raises one AtlasError line."""

    from atlas.commands.orbit_file import open_point
    from atlas.store.reader import describe

    path = Path(file)  # a config given for it is refused with a hint by the reader
    if not (math.isfinite(width) and width > 0):  # before the file is opened
        raise AtlasError(f"--width must be a finite number > 0, got {width:g}")
    if _is_driven(path):
        from atlas.commands.zoom_driven import driven_lines

        body = driven_lines(path, _yaml_number, alpha=alpha, omega0=omega0, torque=torque,
                            **drive)
        return _zoom(path, theta0, theta_dot0, width, num, output, body)
    if any(value is not None for value in drive.values()):
        raise AtlasError(f"--{next(k for k, v in drive.items() if v is not None)}: {path} is "
                         "not a driven pendulum's atlas")
    point = open_point(path, alpha=alpha, omega0=omega0, torque=torque)
    try:
        params, dt, t_max, method = point.params, point.dt, point.t_max, point.method
    finally:
        point.tree.close()
    stored = describe(path)["config"] or {}
    sep = {"enabled": True, "tol": point.tol, "max_spacing": None}
    sep.update({k: v for k, v in (stored.get("separatrices") or {}).items() if k in sep})
    enabled = bool(sep["enabled"])
    n = _yaml_number
    body = [
        "pendulum:",
        f"  alpha: {n(params['alpha'])}    # damping α [1/s]",
        f"  omega0: {n(params['omega0'])}    # natural frequency ω0 [rad/s]",
        f"  torque: {n(params.get('torque', 0.0))}    # constant torque τ [rad/s²]",
        "",
        "integrator:",
        f"  dt: {n(dt)}    # RK4 step [s]",
        f"  t_max: {n(t_max)}    # [s]",
        f"  method: {method}",
        "separatrices:",
        f"  enabled: {'true' if enabled else 'false'}",
    ]
    if sep["tol"] is not None and math.isfinite(float(sep["tol"])):
        body.append(f"  tol: {n(sep['tol'])}")
    if sep["max_spacing"] is not None:
        body.append(f"  max_spacing: {n(sep['max_spacing'])}")
    return _zoom(path, theta0, theta_dot0, width, num, output, body)


def _is_driven(path: Path) -> bool:
    """Whether ``path`` is a driven pendulum's atlas (read from its attributes; a file that
    cannot be read is left to the readers, which say why)."""
    from atlas.models.driven.description import DRIVEN_PENDULUM
    from atlas.store.reader import describe

    try:
        return describe(path)["attrs"].get("model") == DRIVEN_PENDULUM.name
    except Exception:  # noqa: BLE001 (the pendulum's reader names the problem)
        return False


def _zoom(path: Path, theta0: float, theta_dot0: float, width: float, num: int,
          output: str | Path | None, body: list[str]) -> Zoom:
    """The zoom config: its head, ``body`` (the model's sections: its parameters, then after
    an empty line the integrator's and the rest) with the grid after the parameters, and the
    output, validated as ``atlas run`` will validate it."""
    import yaml
    from pydantic import ValidationError

    from atlas.pipeline.config import Config, ConfigError, first_error

    _check_window(theta0, theta_dot0, width, num)
    tag = f"{width_tag(width)}-at-{theta0:.10g}_{theta_dot0:.10g}"
    if output is None:
        output = path.with_name(f"{path.stem}-zoom-{tag}.h5")
    half, n = width / 2, _yaml_number
    lines = [
        f"# atlas zoom {_yaml_text(str(path))} {theta0!r} {theta_dot0!r} --width {width!r}",
        "# a square window centred on (θ0, θ̇0), at the parameter point and integrator of "
        "that file",
        f"name: {_yaml_text(f'{path.stem}-zoom-{tag}')}",
        *body[:body.index("")],
        f"grid:    # width {width!r} [rad] × {width!r} [rad/s]",
        f"  theta0: {{start: {n(theta0 - half)}, stop: {n(theta0 + half)}, num: {num}}}"
        f"    # θ0 [rad], centre {theta0!r}",
        f"  theta_dot0: {{start: {n(theta_dot0 - half)}, stop: {n(theta_dot0 + half)}, "
        f"num: {num}}}    # θ̇0 [rad/s], centre {theta_dot0!r}",
        *body[body.index("") + 1:],
        f"output: {_yaml_text(str(output))}",
    ]
    text = "\n".join(lines) + "\n"
    try:  # the config is validated as `atlas run` will validate it
        config = Config.model_validate(yaml.safe_load(text))
    except ValidationError as exc:
        raise ConfigError(f"zoom: {first_error(exc)}") from None
    return Zoom(text=text, config=config)


def _yaml_text(text: str) -> str:
    """A string as a YAML scalar that reads back as the same string (JSON quoting)."""
    import json

    return json.dumps(text, ensure_ascii=False)


def write_zoom(zoom: Zoom, target: str | Path, source: str | Path) -> Path:
    """Write ``zoom``'s YAML to ``target`` (whole or not at all); AtlasError, nothing
    written, where ``target`` is the atlas file ``source``, not a .yaml or .yml name, or
    holds anything but a config that ``atlas zoom`` wrote
    (:func:`atlas.store.outputs.check_output`)."""
    from atlas.store.durable import write_durably
    from atlas.store.outputs import check_output

    target = Path(target)
    check_output(target, "config", inputs=(source,))
    if not target.parent.is_dir():
        raise AtlasError(f"{target.parent}: no such folder")
    write_durably(target, lambda fh: fh.write(zoom.text.encode()))
    return target
