"""Sweep configs: YAML validated by pydantic v2. Every default is written once, here.

A config names the pendulum (α, ω0, τ — a list for any makes a parameter atlas), the
(θ0, θ̇0) grid, the integrator, the separatrix tracing, the execution backend and the output
path. Numbers may be written as π expressions: ``3pi``, ``-pi/2``, ``2*pi``, ``0.5pi``.
Any problem is raised as :class:`atlas.errors.ConfigError` with one line naming the key (an
unknown key first, with the schema's nearest key: "did you mean num?"). What is valid but
likely a mistake (a θ0 window in degrees) or adjusted (a separatrix tol finer than double
precision resolves) is said in warnings (:attr:`Config.warnings`, logged by
:func:`load_config`); ``check_radians: false`` silences the one about degrees.
"""

from __future__ import annotations

import ast
import difflib
import hashlib
import itertools
import json
import logging
import math
import operator
import re
from fractions import Fraction
from pathlib import Path
from typing import Annotated, Literal, get_args

import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)

from atlas import defaults
from atlas.defaults import BACKEND_WORDS, METHODS
from atlas.errors import ConfigError
from atlas.layout import PARAMETERS
from atlas.limits import MAX_RATE, MIN_RATE

log = logging.getLogger(__name__)

__all__ = ["Config", "load_config", "parse_pi_expression", "ConfigError", "config_hash",
           "first_error"]

# ---------------------------------------------------------------------------- π expressions

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
_IMPLICIT_PI = re.compile(r"(\d|\.)\s*(?=pi\b)")


def _evaluate(node: ast.AST) -> float:
    if isinstance(node, ast.Expression):
        return _evaluate(node.body)
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return float(node.value)
    if isinstance(node, ast.Name) and node.id in ("pi", "π"):
        return math.pi
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        return _BINARY[type(node.op)](_evaluate(node.left), _evaluate(node.right))
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](_evaluate(node.operand))
    raise ValueError("only numbers, pi, + - * / and parentheses are allowed")


def parse_pi_expression(text: str) -> float:
    """Evaluate a number written with π: ``"3pi"`` → 3π, ``"-pi/2"``, ``"2*pi"``, ``"1.5"``.

    Only numbers, ``pi`` (or ``π``), + − × ÷ and parentheses are accepted; implicit
    multiplication is allowed only directly before ``pi``.
    """
    source = _IMPLICIT_PI.sub(r"\1*", text.strip().replace("π", "pi"))
    try:
        value = _evaluate(ast.parse(source, mode="eval"))
    except (SyntaxError, ValueError, ZeroDivisionError) as exc:
        detail = "division by zero" if isinstance(exc, ZeroDivisionError) else str(exc)
        if isinstance(exc, SyntaxError):
            detail = "not a number or π expression (e.g. 3pi, -pi/2, 2*pi)"
        raise ValueError(f"cannot read {text!r}: {detail}") from None
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite number")
    return value


def _number(value):
    """Accept ints, floats and π-expression strings; refuse bools, NaN and infinities."""
    if isinstance(value, bool):
        raise ValueError("expected a number, got a boolean")
    if isinstance(value, str):
        value = parse_pi_expression(value)
    if isinstance(value, (int, float)):
        try:
            value = float(value)
        except OverflowError:  # an integer beyond double precision
            raise ValueError("must be a finite number, got an integer beyond the range of "
                             "double precision") from None
        if not math.isfinite(value):
            raise ValueError(f"must be a finite number, got {value}")
        return value
    raise ValueError(f"expected a number or π expression, got {type(value).__name__}")


#: The most values a range {start, stop, num} of a pendulum parameter may hold.
MAX_RANGE_NUM = 1 << 20


def _parameter_range(value: dict) -> list[float]:
    """A range ``{start, stop, num}`` of a pendulum parameter: ``num`` values evenly spaced
    from ``start`` to ``stop`` inclusive (numpy's linspace: both ends exact), num ≥ 2 and
    start < stop."""
    unknown = sorted(set(value) - {"start", "stop", "num"})
    if unknown:
        raise ValueError(f"a range has the keys start, stop and num; unknown key {unknown[0]!r}")
    missing = [key for key in ("start", "stop", "num") if key not in value]
    if missing:
        raise ValueError(f"a range needs start, stop and num; {missing[0]} is missing")
    start, stop, num = _number(value["start"]), _number(value["stop"]), value["num"]
    if isinstance(num, bool) or not isinstance(num, int):
        raise ValueError(f"range num must be an integer, got {num!r}")
    if not 2 <= num <= MAX_RANGE_NUM:
        raise ValueError(f"range num must be between 2 and {MAX_RANGE_NUM}, got {num}")
    if not start < stop:
        raise ValueError(f"range start ({start:g}) must be less than stop ({stop:g})")
    import numpy as np

    return [float(v) for v in np.linspace(start, stop, num)]


def _number_or_list(value):
    if isinstance(value, dict):
        return _parameter_range(value)
    if isinstance(value, list):
        numbers = []
        for i, item in enumerate(value):
            try:
                numbers.append(_number(item))
            except ValueError as exc:
                raise ValueError(f"item {i}: {exc}") from None
        return numbers
    return _number(value)


Number = Annotated[float, BeforeValidator(_number)]
#: A number, or a list of numbers (or a range {start, stop, num}) for a parameter atlas.
Numbers = Annotated[float | list[float], BeforeValidator(_number_or_list)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


# ---------------------------------------------------------------------------- sections


class PendulumConfig(_Strict):
    """α [s⁻¹], ω0 [rad s⁻¹] and the constant torque τ [rad s⁻²]; a list for any of them
    makes it a dim of a parameter atlas (the others stay scalar coordinates)."""

    alpha: Numbers = defaults.ALPHA
    omega0: Numbers = defaults.OMEGA0
    torque: Numbers = 0.0

    @staticmethod
    def _each(value, check) -> None:
        """Apply ``check`` to a value or to every item of a list (naming the bad item)."""
        if not isinstance(value, list):
            check(value)
            return
        for i, item in enumerate(value):
            try:
                check(item)
            except ValueError as exc:
                raise ValueError(f"item {i}: {exc}") from None

    @field_validator("alpha")
    @classmethod
    def _alpha(cls, value):
        def check(a):
            if a < 0:
                raise ValueError(f"damping must be >= 0, got {a:g}")
            if a > MAX_RATE:
                raise ValueError(f"must be at most {MAX_RATE:g} 1/s, got {a:g}")
            if a == 0:
                raise ValueError(
                    "alpha = 0 makes no basin atlas: without damping the energy is conserved "
                    "and no orbit ever settles on an attractor"
                )

        cls._each(value, check)
        return value

    @field_validator("omega0")
    @classmethod
    def _omega0(cls, value):
        def check(w):
            if w <= 0:
                raise ValueError(f"must be > 0, got {w:g}")
            if not MIN_RATE <= w <= MAX_RATE:
                raise ValueError(f"must be between {MIN_RATE:g} and {MAX_RATE:g} rad/s, "
                                 f"got {w:g}")

        cls._each(value, check)
        return value

    @field_validator("torque")
    @classmethod
    def _torque(cls, value):
        def check(t):
            if not abs(t) <= MAX_RATE**2:
                raise ValueError(f"must be between {-MAX_RATE**2:g} and {MAX_RATE**2:g} "
                                 f"rad/s^2, got {t:g}")

        cls._each(value, check)
        return value

    @field_validator("alpha", "omega0", "torque")
    @classmethod
    def _nonempty(cls, value):
        if isinstance(value, list) and not value:
            raise ValueError("an empty list sweeps nothing")
        if isinstance(value, list) and len(set(value)) != len(value):
            twice = next(v for i, v in enumerate(value) if v in value[:i])
            raise ValueError(f"the value {twice:g} is listed twice (each parameter point "
                             "must be named by its values)")
        return value

    def values(self, name: str) -> list[float]:
        """The values of parameter ``name`` (one unless it is swept)."""
        value = getattr(self, name)
        return value if isinstance(value, list) else [value]

    @property
    def swept(self) -> tuple[str, ...]:
        """The parameters given as lists: the dims of a parameter atlas."""
        return tuple(name for name in PARAMETERS if isinstance(getattr(self, name), list))

    @property
    def alphas(self) -> list[float]:
        return self.values("alpha")

    @property
    def omega0s(self) -> list[float]:
        return self.values("omega0")

    @property
    def torques(self) -> list[float]:
        return self.values("torque")

    @property
    def points(self) -> list[dict[str, float]]:
        """Every parameter point, in C order over the swept dims."""
        names = list(PARAMETERS)
        return [dict(zip(names, combo))
                for combo in itertools.product(*(self.values(n) for n in names))]


class Axis(_Strict):
    """``num`` evenly spaced values from ``start`` to ``stop`` inclusive."""

    start: Number
    stop: Number
    num: int = Field(ge=2, le=1 << 20)

    @model_validator(mode="after")
    def _ordered(self):
        if self.start >= self.stop:
            raise ValueError(f"start ({self.start:g}) must be less than stop ({self.stop:g})")
        return self


class GridConfig(_Strict):
    """The grid of initial conditions θ0 [rad] × θ̇0 [rad s⁻¹]."""

    theta0: Axis = Axis(start=defaults.THETA0_WINDOW[0], stop=defaults.THETA0_WINDOW[1],
                        num=defaults.GRID_NUM)
    theta_dot0: Axis = Axis(start=defaults.THETA_DOT0_WINDOW[0],
                            stop=defaults.THETA_DOT0_WINDOW[1], num=defaults.GRID_NUM)


class IntegratorConfig(_Strict):
    """Fixed-step RK4: step ``dt`` [s]; orbits not trapped by ``t_max`` [s] are unresolved;
    ``method`` the discretisation (:data:`atlas.defaults.METHODS`: "rk4", classical RK4 on
    (θ, θ̇), or "rk4-trigfree", RK4 on (θ, θ̇, cos θ, sin θ), CPU only)."""

    dt: Number = Field(default=defaults.DT, gt=0)
    t_max: Number = Field(default=defaults.T_MAX, gt=0)
    method: Literal[METHODS] = defaults.METHOD


class SeparatricesConfig(_Strict):
    """Stable manifolds of the saddles, located by bisection to ``tol`` with vertices at most
    ``max_spacing`` apart in the phase plane. A ``tol`` finer than double precision resolves
    in the window (:func:`atlas.limits.finest_tol`: 1.2e-13 for |θ| ≤ 3π, 1.9e-12 for
    |θ| ≤ 180) is raised to that finest one, with a warning (:attr:`Config.warnings`)."""

    enabled: bool = True
    tol: Number = Field(default=defaults.SEPARATRIX_TOL, gt=0, lt=1e-3)
    max_spacing: Number = Field(default=defaults.MAX_SPACING, gt=0)


class ExecutionConfig(_Strict):
    """How the sweep runs: ``backend`` and the size of a tile (orbits per task/write; by
    default ``defaults.TILE_ORBITS``, on the GPU ``defaults.TILE_ORBITS_CUDA``)."""

    backend: Literal[tuple(BACKEND_WORDS)] = "cpu"
    tile_orbits: int | None = Field(default=None, ge=1)
    workers: int | None = Field(default=None, ge=1)
    scheduler: str | None = None


class StabilityConfig(_Strict):
    """``atlas stability`` only (a grid run ignores it): the Gaussian perturbation's standard
    deviations ``sigma_theta`` [rad] and ``sigma_theta_dot`` [rad s⁻¹] around each rest state
    (both or neither; none: no Gaussian stability), and whether a 1-D study stores the
    ``tipping`` probabilities between consecutive points."""

    sigma_theta: Number | None = Field(default=None, gt=0)
    sigma_theta_dot: Number | None = Field(default=None, gt=0)
    tipping: bool = False

    @model_validator(mode="after")
    def _both_sigmas(self):
        if (self.sigma_theta is None) != (self.sigma_theta_dot is None):
            raise ValueError("give both sigma_theta and sigma_theta_dot, or neither")
        return self


class Config(_Strict):
    """A whole sweep (see ``configs/default.yaml`` for a commented example).

    ``check_radians`` (default true): warn when the θ0 window looks like degrees or spans
    more than :data:`RADIANS_WARNING_TURNS` turns (:func:`radians_warning`); ``false``
    silences that warning (it changes no result).
    """

    name: str = "default"
    pendulum: PendulumConfig = PendulumConfig()
    grid: GridConfig = GridConfig()
    integrator: IntegratorConfig = IntegratorConfig()
    separatrices: SeparatricesConfig = SeparatricesConfig()
    execution: ExecutionConfig = ExecutionConfig()
    output: Path = Path(defaults.OUTPUT)
    stability: StabilityConfig | None = None
    check_radians: bool = True
    #: What validation changed: a ``separatrices.tol`` raised to what the window resolves.
    _adjusted: tuple[str, ...] = PrivateAttr(default=())

    @property
    def warnings(self) -> tuple[str, ...]:
        """What a user should hear about this valid config, one line each (:func:`load_config`
        logs them): a θ0 window that looks like degrees (:func:`radians_warning`), and a
        ``separatrices.tol`` raised to what double precision resolves in the window. Where a
        window in degrees raised the tol, that is one warning, degrees first: the tol follows
        from the window, and is fixed with it."""
        degrees = radians_warning(self)
        if degrees is None:
            return self._adjusted
        if self._adjusted:
            degrees += f"{'' if degrees.endswith('?') else '.'} With this window, " \
                       f"{self._adjusted[0]}"
        return (f"{degrees} (`check_radians: false` silences the warning about radians)",)

    @model_validator(mode="after")
    def _runnable(self, info):
        """Checks across sections, so that a valid config never fails after work began. A
        study (validation context ``{"study": True}``) integrates no grid: it skips the grid
        run's checks of the integrator and the window's reach, and takes the saddle-node."""
        from atlas.labels.backends import lookup as lookup_backend
        from atlas.labels.labelling import check_integration, check_torque_reach
        from atlas.labels.methods import lookup as lookup_method
        from atlas.labels.trap import CHECK_EVERY
        from atlas.limits import check_reach, check_separatrix_settings, check_study_window

        dt, t_max = self.integrator.dt, self.integrator.t_max
        try:
            device = lookup_backend(BACKEND_WORDS[self.execution.backend][0])
            device.check_method(self.integrator.method)
        except ValueError as exc:
            raise ValueError(f"integrator.{exc}") from None
        if not lookup_method(self.integrator.method).running and any(self.pendulum.torques):
            raise ValueError(f"integrator.method: {self.integrator.method!r} is for the "
                             "pendulum without torque (the running certificate is established "
                             "for 'rk4' only); use method: rk4 with a torque")
        if (info.context or {}).get("study"):
            g = self.grid
            try:
                check_study_window((g.theta0.start, g.theta0.stop),
                                   (g.theta_dot0.start, g.theta_dot0.stop))
            except ValueError as exc:
                raise ValueError(f"grid.{exc}") from None
            swept = self.pendulum.swept
            if self.stability is not None and self.stability.tipping and (
                    len(swept) != 1 or len(self.pendulum.values(swept[0])) < 2):
                over = (" and ".join(swept) if len(swept) != 1 else
                        f"one value of {swept[0]}") if swept else "no parameter"
                raise ValueError("stability.tipping: tipping probabilities are between "
                                 "consecutive points of a 1-D study (one swept parameter); "
                                 f"this study sweeps {over}")
            return self
        g = self.grid
        theta_abs = max(abs(g.theta0.start), abs(g.theta0.stop))
        speed_abs = max(abs(g.theta_dot0.start), abs(g.theta_dot0.stop))
        for point in self.pendulum.points:
            a, w, t = point["alpha"], point["omega0"], point["torque"]
            if abs(t) == w * w:
                raise ValueError(
                    f"pendulum.torque: |torque| = omega0^2 = {w * w:g} is the saddle-node "
                    "bifurcation, where the rest state (pi/2, 0) is degenerate and atlas "
                    "certifies no basin; take |torque| below or above omega0^2")
            try:
                check_integration(a, w, dt, t_max, torque=t)
            except ValueError as exc:
                raise ValueError(f"integrator.{exc}") from None
            if t:
                try:
                    check_torque_reach(theta_abs, speed_abs, a, w, t,
                                       t_max + CHECK_EVERY * dt)
                except ValueError as exc:
                    raise ValueError(f"grid: {exc}") from None
        try:
            check_reach(max(abs(g.theta0.start), abs(g.theta0.stop)),
                        max(abs(g.theta_dot0.start), abs(g.theta_dot0.stop)),
                        min(self.pendulum.alphas))
        except ValueError as exc:
            raise ValueError(f"grid: {exc}") from None
        if self.separatrices.enabled:
            self._resolve_tol()
            try:
                check_separatrix_settings((g.theta0.start, g.theta0.stop),
                                          (g.theta_dot0.start, g.theta_dot0.stop),
                                          self.separatrices.tol, self.separatrices.max_spacing)
            except ValueError as exc:
                raise ValueError(f"separatrices.{exc}") from None
        return self

    def _resolve_tol(self) -> None:
        """Raise ``separatrices.tol`` to the finest the window resolves where it asks for a
        finer one (:func:`atlas.limits.finest_tol`), noting it: a window far out (±180, say)
        then runs at 1.9e-12 instead of being refused over a setting its user never chose.
        (The model is frozen; this runs inside its own validation, before anyone sees it.)"""
        from atlas.limits import finest_tol

        g, sep = self.grid, self.separatrices
        ends = (g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop)
        finest = finest_tol(*ends)
        if sep.tol < finest:
            object.__setattr__(self, "separatrices", sep.model_copy(update={"tol": finest}))
            scale = max(abs(x) for pair in ends for x in pair)
            self._adjusted = (f"separatrices.tol = {sep.tol:g} is finer than double precision "
                              f"resolves where |θ0| or |θ̇0| reaches {scale:.3g}; using the "
                              f"finest it resolves there, tol = {finest:.2g}",)

    def to_json(self) -> str:
        """The validated config as canonical JSON (stored in every output file); keys at their
        default that change no result (``stability`` unset, ``check_radians`` true) are left
        out, so files keep the config JSON they had before the keys existed."""
        exclude = {"stability"} if self.stability is None else set()
        if self.check_radians:
            exclude.add("check_radians")
        return json.dumps(self.model_dump(mode="json", exclude=exclude), sort_keys=True)


def integrator_json(integrator: IntegratorConfig) -> dict:
    """The integrator settings as JSON data for digests: without ``method`` when it is "rk4",
    the method of every file written before the key existed, so that their config hashes and
    run identities stay valid."""
    data = integrator.model_dump(mode="json")
    if data["method"] == "rk4":
        del data["method"]
    return data


def config_hash(cfg: Config) -> str:
    """Digest of the config apart from its name, output and execution settings, recorded in the
    file as provenance. (Whether a partial run may be continued is decided by the stricter
    :func:`atlas.pipeline.identity.run_identity`.)"""
    data = cfg.model_dump(mode="json", exclude={"output", "execution", "name", "stability",
                                                "check_radians"})
    data["integrator"] = integrator_json(cfg.integrator)
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


def _key_path(loc: tuple) -> list:
    """The config keys of a pydantic error location, without the tags pydantic inserts for
    unions and validators (``function-before[...]``, ``list[float]``); the last part is
    always kept: it may be a user's unknown key (``theta-dot0``)."""
    keys = [p for p in loc[:-1] if not (isinstance(p, str) and ("[" in p or "-" in p))]
    return keys + list(loc[-1:])


def _section_model(annotation):
    """The config section (a pydantic model) an annotation holds, e.g. ``X | None`` → X."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    return next((m for m in map(_section_model, get_args(annotation)) if m is not None), None)


def _schema_keys(section: list) -> list[str]:
    """The keys the config schema allows in ``section`` (its keys from the top; [] for the
    top level): the field names of its model, [] where ``section`` is no section."""
    model = Config
    for key in section:
        field = model.model_fields.get(key) if isinstance(key, str) else None
        model = None if field is None else _section_model(field.annotation)
        if model is None:
            return []
    return list(model.model_fields)


def _did_you_mean(loc: list, errors: list[dict]) -> str:
    """`` (did you mean KEY?)`` for the unknown key at ``loc``: the required key missing
    beside it that it most resembles (``n`` for ``num``), else the nearest key the schema
    allows there (difflib, as Python's own suggestions); "" where none is close."""
    section, key = loc[:-1], str(loc[-1])
    missing = [str(e["loc"][-1]) for e in errors
               if e["type"] == "missing" and _key_path(e["loc"])[:-1] == section]
    match = (difflib.get_close_matches(key, missing, n=1, cutoff=0.4)
             or difflib.get_close_matches(key, _schema_keys(section), n=1, cutoff=0.6))
    return f" (did you mean {match[0]}?)" if match else ""


def first_error(exc: ValidationError) -> str:
    """One line from pydantic's errors: ``<key>: <problem> (got <value>)``. An unknown key
    comes first, with the key it most likely meant: a misspelt key is what makes the right
    one missing (``n:`` for ``num:`` says "grid.theta0.n: unknown key (did you mean num?)",
    not "grid.theta0.num: missing")."""
    errors = exc.errors()
    err = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])
    loc = _key_path(err["loc"])
    kind = err["type"]
    msg = err["msg"].removeprefix("Value error, ").replace("Input should be", "must be")
    if kind == "extra_forbidden":
        msg = "unknown key" + _did_you_mean(loc, errors)
    elif kind == "missing":
        msg = "missing"
    elif kind != "value_error":
        msg = f"{msg} (got {err.get('input')!r})"
    if isinstance(loc[-1:] and loc[-1], int):  # an item of a list: name it
        msg = f"item {loc.pop()}: {msg}"
    key = ".".join(str(p) for p in loc)
    return f"{key}: {msg}" if key else msg


#: Largest config file read [bytes]: a config is a few hundred bytes, a long parameter list a
#: few kilobytes.
MAX_CONFIG_BYTES = 1 << 20


class _StrictLoader(yaml.SafeLoader):
    """YAML's safe loader that refuses a key given twice in one mapping (naming the key and
    both lines) instead of letting the last one win silently."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            try:
                hash(key)
            except TypeError:  # SafeLoader itself refuses an unhashable key, with its line
                continue
            if key in seen:
                raise ConfigError(f"line {line}: key {key!r} given twice (first on line "
                                  f"{seen[key]})")
            seen[key] = line
        return super().construct_mapping(node, deep=deep)


def _parse_yaml(text: str):
    """The YAML document in ``text``. Anchors and aliases are refused before anything is
    built (configs never need them, and nested aliases expand exponentially: the "billion
    laughs"), so reading takes time linear in the file's size."""
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
            line = event.start_mark.line + 1
            raise ConfigError(f"line {line}: YAML anchors and aliases (&, *) are not "
                              "allowed in a config")
    return yaml.load(text, Loader=_StrictLoader)  # noqa: S506 (a SafeLoader subclass)


def load_config(path: str | Path, *, output: str | Path | None = None,
                study: bool = False) -> Config:
    """Read and validate a YAML config; ``output`` overrides its ``output`` key; ``study``:
    validate it for ``atlas stability`` (:class:`Config`'s ``_runnable``).

    Raises :class:`ConfigError` with one line ``<file>: <key>: <problem>``.
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_CONFIG_BYTES:
            raise ConfigError(_not_a_config(path) or f"{path}: {path.stat().st_size:,} bytes "
                              f"is too large for a config (at most {MAX_CONFIG_BYTES:,})")
        text = path.read_text()
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such config file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(_not_a_config(path) or f"{path}: cannot read config file "
                          f"({exc.__class__.__name__})") from None
    try:
        data = _parse_yaml(text)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or "invalid YAML"
        raise ConfigError(f"{path}: {where}YAML syntax error: {problem}") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config must be a mapping of keys, got {type(data).__name__}")
    if output is not None:
        data = {**data, "output": str(output)}
    try:
        cfg = Config.model_validate(data, context={"study": study})
    except ValidationError as exc:
        raise ConfigError(f"{path}: {first_error(exc)}") from None
    for line in cfg.warnings:
        log.warning("warning: %s: %s", path, line)
    return cfg


def _not_a_config(path: Path) -> str | None:
    """The hint for an atlas file given where a config is expected (``atlas run OUT.h5``),
    or None where ``path`` is no atlas file: asked only once the file failed to read as a
    config, so a config is read without importing the store."""
    from atlas.store.reader import is_atlas_file
    from atlas.store.study import is_study_file

    if is_atlas_file(path):
        return (f"{path}: an atlas file, not a config; look at it with `atlas info {path}` "
                "(`atlas run` reads a YAML config such as configs/default.yaml)")
    if is_study_file(path):
        return (f"{path}: a stability study, not a config; look at it with "
                f"`atlas info {path}` (`atlas stability` reads a YAML config such as "
                "configs/swing_stability.yaml)")
    from atlas.store.formats import FORMATS

    fmt = next((fmt for fmt in FORMATS.values() if fmt.recognises(path)), None)
    return f"{path}: {fmt.kind}, not a YAML config" if fmt is not None else None


# ---------------------------------------------------------------------------- units

#: A θ0 window [rad] wider than this many turns (2π rad each) gets a warning that θ0 is in
#: radians: the default window spans 3 turns, an essay figure at most 2.
RADIANS_WARNING_TURNS = 8
#: Window ends [rad] that look like degrees: a quarter, a half, three quarters, one and two
#: turns in degrees.
DEGREE_LIKE_ENDS = (90.0, 180.0, 270.0, 360.0, 720.0)


def _in_pi(degrees: float) -> str:
    """``degrees`` (a whole number) in radians as a π expression where it is a simple
    fraction of π (90 → "pi/2", -180 → "-pi", 360 → "2pi"), else as a number [rad]."""
    ratio = Fraction(round(degrees), 180)
    if ratio.denominator > 12:
        return f"{math.radians(degrees):.6g}"
    if ratio == 0:
        return "0"
    factor = {1: "", -1: "-"}.get(ratio.numerator, str(ratio.numerator))
    return f"{factor}pi" + (f"/{ratio.denominator}" if ratio.denominator > 1 else "")


def radians_warning(cfg: Config) -> str | None:
    """The warning, if any, that ``cfg``'s θ0 window may have been written in degrees: it
    spans more than :data:`RADIANS_WARNING_TURNS` turns, or an end is one of
    :data:`DEGREE_LIKE_ENDS` (±90, ±180, …); with the window in radians as a hint ("did you
    mean -pi/2 … pi/2?") where both ends are whole numbers. None where ``check_radians``
    is false. A warning, not an error: such a window is valid, only unlikely.
    (:attr:`Config.warnings` adds how to silence it.)"""
    start, stop = cfg.grid.theta0.start, cfg.grid.theta0.stop
    turns = (stop - start) / (2 * math.pi)
    looks_like_degrees = any(abs(end) in DEGREE_LIKE_ENDS for end in (start, stop))
    if not cfg.check_radians or (turns <= RADIANS_WARNING_TURNS and not looks_like_degrees):
        return None
    hint = ""
    if float(start).is_integer() and float(stop).is_integer():
        hint = f"; did you mean {_in_pi(start)} … {_in_pi(stop)}?"
    return (f"grid.theta0: θ0 is in radians: the window {start:g} … {stop:g} spans "
            f"{turns:.1f} turns (a turn is 2pi = 6.283 rad){hint}")
