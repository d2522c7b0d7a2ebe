"""Sweep configs: YAML validated by pydantic v2. Every default is written once, in the
sections (:mod:`atlas.pipeline.config_sections`).

A config names its model (``model``, :mod:`atlas.models`; the pendulum by default) and the
model's parameters (for the pendulum α, ω0, τ — a list for any makes a parameter atlas), the
grid of initial states (for the pendulum θ0, θ̇0), the integrator, the separatrix tracing,
the execution backend and the output path. Numbers may be written as π expressions:
``3pi``, ``-pi/2``, ``2*pi``, ``0.5pi``.
Any problem is raised as :class:`atlas.errors.ConfigError` with one line naming the key (an
unknown key first, with the schema's nearest key: "did you mean num?"). What is valid but
likely a mistake (a θ0 window in degrees) or adjusted (a separatrix tol finer than double
precision resolves) is said in warnings (:attr:`Config.warnings`, logged by
:func:`load_config`); ``check_radians: false`` silences the one about degrees.

This module is the whole config and its loading; its parts are modules of their own: the
numbers (:mod:`~atlas.pipeline.config_numbers`: π expressions, lists, ranges), the sections
(:mod:`~atlas.pipeline.config_sections`), the one-line errors
(:mod:`~atlas.pipeline.config_messages`), the YAML file (:mod:`~atlas.pipeline.config_yaml`)
and the units (:mod:`~atlas.pipeline.config_units`).
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path

from pydantic import Field, PrivateAttr, ValidationError, model_validator

from atlas import defaults
from atlas.defaults import BACKEND_WORDS
from atlas.errors import ConfigError
from atlas.models.base import Model
from atlas.models.registry import DEFAULT as DEFAULT_MODEL
from atlas.models.registry import DRIVEN as DRIVEN_MODEL
from atlas.models.registry import lookup, planner
from atlas.pipeline import config_messages as messages
from atlas.pipeline.config_numbers import parse_pi_expression
from atlas.pipeline.config_sections import (
    Axis,
    ExecutionConfig,
    GridConfig,
    IntegratorConfig,
    PendulumConfig,
    SeparatricesConfig,
    StabilityConfig,
    StrictModel,
)
from atlas.pipeline.config_units import radians_warning
from atlas.pipeline.config_yaml import MAX_CONFIG_BYTES, not_a_config, parse_yaml

log = logging.getLogger(__name__)

__all__ = ["Config", "load_config", "parse_pi_expression", "ConfigError", "config_hash",
           "first_error", "integrator_json", "PendulumConfig", "Axis", "GridConfig",
           "IntegratorConfig", "SeparatricesConfig", "ExecutionConfig", "StabilityConfig"]

class Config(StrictModel):
    """A whole sweep (see ``configs/default.yaml`` for a commented example).

    ``model`` names the equation (:mod:`atlas.models.registry`; "pendulum" by default); a
    model other than the pendulum takes its parameters from the section its description
    names (:attr:`atlas.models.base.Model.section`, validated by its planner's ``Section``)
    and its grid's keys are its axes' names. ``check_radians`` (default true): warn when the
    θ0 window looks like degrees or spans more than :data:`RADIANS_WARNING_TURNS` turns
    (:func:`radians_warning`); ``false`` silences that warning (it changes no result).
    """

    name: str = "default"
    model: str = DEFAULT_MODEL
    pendulum: PendulumConfig = PendulumConfig()
    #: Another model's section, as written (validated into :attr:`section`).
    model_section: dict | None = Field(default=None, exclude=True, repr=False)
    grid: GridConfig = GridConfig()
    integrator: IntegratorConfig = IntegratorConfig()
    separatrices: SeparatricesConfig = SeparatricesConfig()
    execution: ExecutionConfig = ExecutionConfig()
    output: Path = Path(defaults.OUTPUT)
    stability: StabilityConfig | None = None
    check_radians: bool = True
    #: What validation changed: a ``separatrices.tol`` raised to what the window resolves.
    _adjusted: tuple[str, ...] = PrivateAttr(default=())
    #: Another model's parameters, validated (the pendulum's are :attr:`pendulum`).
    _section: object = PrivateAttr(default=None)

    @property
    def description(self) -> Model:
        """The config's model (:class:`atlas.models.base.Model`): the one ``model`` names,
        and for the pendulum with a ``drive`` the driven pendulum."""
        if self.model == DEFAULT_MODEL and self.pendulum.drive is not None:
            return lookup(DRIVEN_MODEL)
        return lookup(self.model)

    @property
    def section(self):
        """The model's parameters: ``values(name)``, ``swept``, ``points``
        (:attr:`pendulum` for the pendulum)."""
        return self.pendulum if self._section is None else self._section

    @model_validator(mode="before")
    @classmethod
    def _model_keys(cls, data):
        """A model other than the pendulum: its section and its grid's axis names taken to
        the places the config holds them (``model_section``; ``grid.theta0`` and
        ``grid.theta_dot0``, the columns and rows). An unknown model is one line, and so is a
        ``model_section`` key written by hand, for any model. Such a model has no default
        window: its grid is given whole."""
        if not isinstance(data, dict):
            return data
        if "model_section" in data:
            raise ValueError("model_section: unknown key")
        if data.get("model", DEFAULT_MODEL) == DEFAULT_MODEL:
            return data
        data = dict(data)
        try:
            model = lookup(data["model"])
        except ValueError as exc:
            raise ValueError(f"model: {exc}") from None
        section = data.pop(model.section, None)
        if "pendulum" in data:
            raise ValueError(f"pendulum: not a section of model {model.name} (its parameters "
                             f"are under {model.section})")
        data["model_section"] = section or {}
        columns, rows = model.axes
        grid = data.get("grid")
        if not isinstance(grid, dict) or not {columns.name, rows.name} <= set(grid):
            raise ValueError(f"grid: model {model.name} has no default window; give "
                             f"grid.{columns.name} and grid.{rows.name}")
        known = {columns.name: "theta0", rows.name: "theta_dot0"}
        for key in grid:
            if key not in known:
                raise ValueError(f"grid.{key}: unknown key (the grid of model "
                                 f"{model.name} is {columns.name} × {rows.name})")
        data["grid"] = {known[key]: value for key, value in grid.items()}
        return data

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

        try:
            device = lookup_backend(BACKEND_WORDS[self.execution.backend][0])
            device.check_method(self.integrator.method)
        except ValueError as exc:
            raise ValueError(f"integrator.{exc}") from None
        model = planner(self.description)
        if self.model_section is not None:
            try:
                section = model.Section.model_validate(self.model_section)
            except ValidationError as exc:
                raise ValueError(f"{self.description.section}."
                                 f"{messages.first_error(exc, model.Section)}") from None
            self._section = section
        model.check(self, bool((info.context or {}).get("study")))
        return self

    def resolve_tol(self) -> None:
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
        default that change no result (``stability`` unset, ``check_radians`` true, ``model``
        the pendulum) are left out, so files keep the config JSON they had before the keys
        existed. Another model's parameters are under its section's key, and its grid's
        axes under their names."""
        exclude = {"stability"} if self.stability is None else set()
        if self.check_radians:
            exclude.add("check_radians")
        if self.model == DEFAULT_MODEL:
            exclude.add("model")
            return json.dumps(self.model_dump(mode="json", exclude=exclude), sort_keys=True)
        return json.dumps(self._other_model_json(exclude), sort_keys=True)

    def _other_model_json(self, exclude: set) -> dict:
        """The config of a model other than the pendulum as its user wrote it (no
        ``pendulum`` or ``separatrices``: the pendulum's; the model's section and grid
        keys)."""
        model = self.description
        data = self.model_dump(mode="json", exclude=exclude | {"pendulum", "separatrices"})
        data[model.section] = self.section.model_dump(mode="json")
        columns, rows = model.axes
        grid = data.pop("grid")
        data["grid"] = {columns.name: grid["theta0"], rows.name: grid["theta_dot0"]}
        return data


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
    if cfg.model != DEFAULT_MODEL:
        data = {key: value for key, value in json.loads(cfg.to_json()).items()
                if key not in ("output", "execution", "name", "stability", "check_radians")}
    else:
        data = cfg.model_dump(mode="json", exclude={"output", "execution", "name",
                                                    "stability", "check_radians", "model"})
    data["integrator"] = integrator_json(cfg.integrator)
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


def first_error(exc: ValidationError) -> str:
    """One line from the errors of validating a :class:`Config`
    (:func:`atlas.pipeline.config_messages.first_error` with the config's schema)."""
    return messages.first_error(exc, Config)


def _in_model_words(message: str, data: dict) -> str:
    """An error about the grid of a model other than the pendulum, with the grid's keys as
    its config writes them (the config holds them as ``grid.theta0`` and ``grid.theta_dot0``:
    :meth:`Config._model_keys`)."""
    try:
        model = lookup(data.get("model", DEFAULT_MODEL))
    except ValueError:
        return message
    columns, rows = model.axes
    return (message.replace("grid.theta_dot0", f"grid.{rows.name}")
            .replace("grid.theta0", f"grid.{columns.name}"))


def load_config(path: str | Path, *, output: str | Path | None = None,
                study: bool = False) -> Config:
    """Read and validate a YAML config; ``output`` overrides its ``output`` key; ``study``:
    validate it for ``atlas stability`` (:class:`Config`'s ``_runnable``).

    Raises :class:`ConfigError` with one line ``<file>: <key>: <problem>``.
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_CONFIG_BYTES:
            raise ConfigError(not_a_config(path) or f"{path}: {path.stat().st_size:,} bytes "
                              f"is too large for a config (at most {MAX_CONFIG_BYTES:,})")
        text = path.read_text()
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such config file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(not_a_config(path) or f"{path}: cannot read config file "
                          f"({exc.__class__.__name__})") from None
    try:
        data = parse_yaml(text)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config must be a mapping of keys, got {type(data).__name__}")
    if output is not None:
        data = {**data, "output": str(output)}
    try:
        cfg = Config.model_validate(data, context={"study": study})
    except ValidationError as exc:
        raise ConfigError(f"{path}: {_in_model_words(first_error(exc), data)}") from None
    for line in cfg.warnings:
        log.warning("warning: %s: %s", path, line)
    return cfg
