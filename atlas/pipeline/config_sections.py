"""The sections of a config, as pydantic models with every default written once: the pendulum
(α, ω0, τ: a number, a list or a range each), the grid of initial conditions, the
integrator, the separatrix tracing, the execution backend and the stability study's options.
The whole config (:class:`atlas.pipeline.config.Config`) is made of these; checks that span
sections are its own.
"""

from __future__ import annotations

import itertools
from typing import ClassVar, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    field_validator,
    model_serializer,
    model_validator,
)

from atlas import defaults
from atlas.defaults import BACKEND_WORDS, METHODS
from atlas.limits import MAX_RATE, MIN_RATE
from atlas.models.driven.description import LONGEST_PERIOD, MAX_PERIOD
from atlas.models.pendulum.description import PARAMETERS
from atlas.pipeline.config_numbers import Number, Numbers

__all__ = ["StrictModel", "ParameterSection", "DriveConfig", "PendulumConfig", "Axis",
           "GridConfig",
           "IntegratorConfig", "SeparatricesConfig", "ExecutionConfig", "StabilityConfig",
           "DRIVEN_SAMPLES"]


class StrictModel(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)



class ParameterSection(StrictModel):
    """A model's parameters, each a field: a number, a list or a range (a list or a range
    makes it a dim of a parameter atlas, the others stay scalar coordinates). ``NAMES``:
    the parameters in the model's order (the dims' order)."""

    NAMES: ClassVar[tuple[str, ...]] = ()

    def values(self, name: str) -> list[float]:
        """The values of parameter ``name`` (one unless it is swept)."""
        value = getattr(self, name)
        return value if isinstance(value, list) else [value]

    @property
    def swept(self) -> tuple[str, ...]:
        """The parameters given as lists: the dims of a parameter atlas."""
        return tuple(name for name in self.NAMES if isinstance(getattr(self, name), list))

    @property
    def points(self) -> list[dict[str, float]]:
        """Every parameter point, in C order over the swept dims."""
        return [dict(zip(self.NAMES, combo))
                for combo in itertools.product(*(self.values(n) for n in self.NAMES))]


class SearchWindow(StrictModel):
    """A window of the phase plane, ``theta0`` [lo, hi] [rad] × ``theta_dot0`` [lo, hi]
    [rad s⁻¹], each lo < hi."""

    theta0: tuple[Number, Number]
    theta_dot0: tuple[Number, Number]

    @field_validator("theta0", "theta_dot0")
    @classmethod
    def _ordered(cls, value):
        if not value[0] < value[1]:
            raise ValueError(f"[lo, hi] must have lo < hi, got [{value[0]:g}, {value[1]:g}]")
        return value


class DriveConfig(StrictModel):
    """The periodic torque A cos(Ω t + φ) of the driven pendulum: ``amplitude`` A [rad s⁻²]
    and ``frequency`` Ω [rad s⁻¹] (each a number, a list or a range: dims of a parameter
    atlas), ``phase`` φ [rad] (one number); and ``max_period``, the largest period [drive
    periods] of the stroboscopic map's periodic attractors searched for (a longer one is
    found as a chaotic, recurrent attractor)."""

    amplitude: Numbers
    frequency: Numbers
    phase: Number = 0.0
    max_period: int = MAX_PERIOD
    #: Where the attractors' search spreads its seeds, {theta0: [lo, hi], theta_dot0: [lo,
    #: hi]} [rad, rad s⁻¹]; None: the grid's window. ``atlas zoom`` writes its file's, so that
    #: a small window finds (and numbers) the same attractors as the atlas it zooms into.
    search_window: SearchWindow | None = None

    @field_validator("max_period", mode="before")
    @classmethod
    def _max_period(cls, value):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"must be a whole number of drive periods, got {value!r}")
        if not 1 <= value <= LONGEST_PERIOD:
            raise ValueError(f"must be from 1 to {LONGEST_PERIOD} drive periods, got {value}")
        return value

    @field_validator("amplitude", "frequency")
    @classmethod
    def _drive(cls, value, info):
        def check(x):
            if info.field_name == "frequency" and not MIN_RATE <= x <= MAX_RATE:
                raise ValueError(f"must be between {MIN_RATE:g} and {MAX_RATE:g} rad/s, "
                                 f"got {x:g}")
            if info.field_name == "amplitude" and not 0 <= x <= MAX_RATE**2:
                raise ValueError(f"must be between 0 and {MAX_RATE**2:g} rad/s^2, got {x:g}")

        PendulumConfig._each(value, check)
        return PendulumConfig._nonempty(value)


class PendulumConfig(ParameterSection):
    """α [s⁻¹], ω0 [rad s⁻¹] and the constant torque τ [rad s⁻²]; a list for any of them
    makes it a dim of a parameter atlas (the others stay scalar coordinates). With ``drive``
    (:class:`DriveConfig`) it is the driven pendulum, whose parameters go on with A, Ω
    (dims ``amplitude``, ``frequency``, after α, ω0, τ) and φ."""

    NAMES: ClassVar[tuple[str, ...]] = tuple(PARAMETERS)
    #: The driven pendulum's parameters after the pendulum's, read from ``drive``.
    DRIVE_NAMES: ClassVar[tuple[str, ...]] = ("amplitude", "frequency", "phase")

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

    drive: DriveConfig | None = None

    @model_serializer(mode="wrap")
    def _no_drive_no_key(self, handler):
        """Without a drive the section dumps as it did before the key existed (the stored
        config, its hash and the run identity of every undriven config stay the same)."""
        data = handler(self)
        if isinstance(data, dict) and data.get("drive") is None:
            data.pop("drive", None)
        return data

    @property
    def names(self) -> tuple[str, ...]:
        """The parameters of this section's model, in its order (with a drive: the driven
        pendulum's)."""
        return self.NAMES + (self.DRIVE_NAMES if self.drive is not None else ())

    def values(self, name: str) -> list[float]:
        """The values of parameter ``name`` (one unless it is swept; A, Ω, φ from the
        drive)."""
        if name in self.DRIVE_NAMES:
            value = getattr(self.drive, name)
            return value if isinstance(value, list) else [value]
        return super().values(name)

    @property
    def swept(self) -> tuple[str, ...]:
        """The parameters given as lists (the drive's included): the dims of a parameter
        atlas."""
        return tuple(name for name in self.names if isinstance(
            getattr(self.drive if name in self.DRIVE_NAMES else self, name), list))

    @property
    def points(self) -> list[dict[str, float]]:
        """Every parameter point, in C order over the swept dims."""
        return [dict(zip(self.names, combo))
                for combo in itertools.product(*(self.values(n) for n in self.names))]

    @property
    def alphas(self) -> list[float]:
        return self.values("alpha")

    @property
    def omega0s(self) -> list[float]:
        return self.values("omega0")

    @property
    def torques(self) -> list[float]:
        return self.values("torque")



class Axis(StrictModel):
    """``num`` evenly spaced values from ``start`` to ``stop`` inclusive."""

    start: Number
    stop: Number
    num: int = Field(ge=2, le=1 << 20)

    @model_validator(mode="after")
    def _ordered(self):
        if self.start >= self.stop:
            raise ValueError(f"start ({self.start:g}) must be less than stop ({self.stop:g})")
        return self


class GridConfig(StrictModel):
    """The grid of initial conditions θ0 [rad] × θ̇0 [rad s⁻¹]."""

    theta0: Axis = Axis(start=defaults.THETA0_WINDOW[0], stop=defaults.THETA0_WINDOW[1],
                        num=defaults.GRID_NUM)
    theta_dot0: Axis = Axis(start=defaults.THETA_DOT0_WINDOW[0],
                            stop=defaults.THETA_DOT0_WINDOW[1], num=defaults.GRID_NUM)


class IntegratorConfig(StrictModel):
    """Fixed-step RK4: step ``dt`` [s]; orbits not trapped by ``t_max`` [s] are unresolved;
    ``method`` the discretisation (:data:`atlas.defaults.METHODS`: "rk4", classical RK4 on
    (θ, θ̇), or "rk4-trigfree", RK4 on (θ, θ̇, cos θ, sin θ), CPU only)."""

    dt: Number = Field(default=defaults.DT, gt=0)
    t_max: Number = Field(default=defaults.T_MAX, gt=0)
    method: Literal[METHODS] = defaults.METHOD


class SeparatricesConfig(StrictModel):
    """Stable manifolds of the saddles, located by bisection to ``tol`` with vertices at most
    ``max_spacing`` apart in the phase plane. A ``tol`` finer than double precision resolves
    in the window (:func:`atlas.limits.finest_tol`: 1.2e-13 for |θ| ≤ 3π, 1.9e-12 for
    |θ| ≤ 180) is raised to that finest one, with a warning (:attr:`Config.warnings`)."""

    enabled: bool = True
    tol: Number = Field(default=defaults.SEPARATRIX_TOL, gt=0, lt=1e-3)
    max_spacing: Number = Field(default=defaults.MAX_SPACING, gt=0)


class ExecutionConfig(StrictModel):
    """How the sweep runs: ``backend`` and the size of a tile (orbits per task/write; by
    default ``defaults.TILE_ORBITS``, on the GPU ``defaults.TILE_ORBITS_CUDA``)."""

    backend: Literal[tuple(BACKEND_WORDS)] = "cpu"
    tile_orbits: int | None = Field(default=None, ge=1)
    workers: int | None = Field(default=None, ge=1)
    scheduler: str | None = None


#: Initial conditions sampled per parameter point by a driven pendulum's study, by default.
DRIVEN_SAMPLES = 10_000


class StabilityConfig(StrictModel):
    """``atlas stability`` only (a grid run ignores it): the Gaussian perturbation's standard
    deviations ``sigma_theta`` [rad] and ``sigma_theta_dot`` [rad s⁻¹] around each rest state
    (both or neither; none: no Gaussian stability), and whether a 1-D study stores the
    ``tipping`` probabilities between consecutive points. A driven pendulum's study
    (:mod:`atlas.stability.driven`) samples its basin fractions: ``samples`` initial
    conditions per parameter point (default :data:`DRIVEN_SAMPLES`), drawn uniformly in the
    window by the generator seeded with ``seed`` (default 0); the undriven pendulum's study
    is exact and refuses both."""

    sigma_theta: Number | None = Field(default=None, gt=0)
    sigma_theta_dot: Number | None = Field(default=None, gt=0)
    tipping: bool = False
    samples: int | None = Field(default=None, gt=0, le=100_000_000)
    seed: int | None = Field(default=None, ge=0)

    @model_validator(mode="after")
    def _both_sigmas(self):
        if (self.sigma_theta is None) != (self.sigma_theta_dot is None):
            raise ValueError("give both sigma_theta and sigma_theta_dot, or neither")
        return self
