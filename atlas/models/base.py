"""What atlas knows of an equation it maps: the :class:`Model` description, and the contract
of the per-point plan that labels and certifies its tiles.

atlas maps the basins of a planar flow ẋ = f(x, v; p), v̇ = g(x, v; p) over a grid of
initial states (x0, v0), for every point p of a grid of physical parameters. Everything atlas
does that does not depend on which equation it is (the config's grid, integrator and
execution sections, the layout and tiling, the schedulers, the partial runs and the file
formats, the lock, the progress, the views, the CLI) reaches the equation through one
:class:`Model`, found by its name in the registry (:mod:`atlas.models.registry`; a config's
``model`` key, a file's ``model`` attribute; "pendulum" where absent).

A model is two parts, in two layers:

- its **description** (this class; data only, importable by every layer, the store and the
  views included): its parameters with their units, the grid's two axes, its config section,
  the codes of ``status`` and what they mean, the variables of the basin map and of the
  summary it stores, and its words for ``atlas info``;
- its **planner**, a module named by :attr:`Model.planner` and imported only by the pipeline
  (it may import the physics, kernels and boundaries the description must not): it validates
  the model's config section and prepares, per parameter point, a picklable
  :class:`PointPlan` that labels and certifies tiles. The functions it defines are listed in
  :class:`Planner`.

The analogues elsewhere: diffrax's ``ODETerm`` apart from its solver; Attractors.jl's
``DynamicalSystem`` that every mapper wraps (Datseris & Wagemakers, *Chaos* 32, 023104,
2022). How to add a model: ``docs/design/models.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

__all__ = ["LABELS", "units_text", "Axis", "MapVariable", "Model", "Planner", "PointPlan",
           "Plan", "status_flags"]

#: The map variables of every model: the label of each orbit and how it was decided.
LABELS = ("attractor", "status")


def units_text(units: str) -> str:
    """CF units (UDUNITS strings) as a text writes them: "rad s-1" → "rad/s", "s-1" →
    "1/s", "rad s-2" → "rad/s^2"."""
    words = units.split()
    over = [w[:-2] + ("^" + w[-1] if w[-1] != "1" else "") for w in words if w[-2:-1] == "-"]
    over = [w.replace("^1", "") for w in over]
    top = " ".join(w for w in words if w[-2:-1] != "-") or ("1" if over else units)
    return top + "".join(f"/{w}" for w in over)


def status_flags(statuses: dict[int, str], in_file: dict[int, str]) -> dict:
    """``status``'s CF attributes: ``flag_values`` and ``flag_meanings`` from ``statuses``
    (code → word), and a ``comment`` saying what each means in a file (``in_file``)."""
    return {"flag_values": np.array(list(statuses), np.int8),
            "flag_meanings": " ".join(statuses.values()),
            "comment": "; ".join(f"{statuses[code]}: {text}" for code, text in in_file.items())}


@dataclass(frozen=True)
class Axis:
    """One axis of the grid of initial states: the name of its dim and config key, its CF
    units and long name, and its symbol in figures and texts."""

    name: str
    units: str
    long_name: str
    symbol: str

    @property
    def unit_text(self) -> str:
        """The units as a text writes them: "rad s-1" → "rad/s", "s-1" → "1/s"."""
        return units_text(self.units)

    @property
    def label(self) -> str:
        """"θ0 [rad]": an axis label of a figure."""
        return f"{self.symbol} [{self.unit_text}]"


@dataclass(frozen=True)
class MapVariable:
    """One variable of the basin map: its stored dtype, its ``_FillValue`` (None: none),
    the value that pads a tile's edge chunk, and its CF attributes."""

    dtype: type
    fill: object
    padding: object
    attrs: dict


@dataclass(frozen=True, eq=False)
class Model:
    """The description of an equation atlas maps (see the module's docstring).

    ``parameters``: name → (CF units, long name), in the order of a parameter atlas's
    leading dims. ``axes``: the grid's (column, row) axes, the position x0 then the velocity
    v0. ``section``: the config key of the parameters. ``statuses``: ``status`` code → the
    word of its CF ``flag_meanings``; ``in_file``: code → what it means in a file.
    ``labelled``: the status codes under which ``attractor`` holds a label k; ``running``:
    those of an attractor without a k (the pendulum's running cycle; none for most models);
    ``positive``: the parameters > 0 at every point.
    ``map_variables``: the basin map's variables, in file order (``attractor`` and
    ``status`` among them); ``label_variables``: those every file of the model has.
    ``basin_variables`` / ``point_variables``: the summary per attractor index ``k`` / per
    parameter point, name → CF attributes (units "1" unless given). ``attractor``: what a
    label ``k`` names (for ``k``'s long name). ``planner``: the module that prepares the
    plans (:class:`Planner`). ``title``: the equation, in words for titles.
    """

    name: str
    title: str
    parameters: dict[str, tuple[str, str]]
    axes: tuple[Axis, Axis]
    section: str
    statuses: dict[int, str]
    in_file: dict[int, str]
    map_variables: dict[str, MapVariable]
    label_variables: tuple[str, ...]
    basin_variables: dict[str, dict]
    point_variables: dict[str, dict]
    attractor: str
    planner: str
    labelled: tuple[int, ...] = (0,)
    running: tuple[int, ...] = ()
    #: The parameters that are > 0 at every point (a file with another value is refused).
    positive: tuple[str, ...] = ()
    #: Summary variables absent from files of older formats: name → the first format with it.
    since: dict[str, int] = field(default_factory=dict)

    @property
    def status_flags(self) -> dict:
        """``status``'s CF flags and comment (:func:`status_flags`)."""
        return status_flags(self.statuses, self.in_file)

    def status_kinds(self) -> np.ndarray:
        """A table over the int8 status codes (index code + 128): 1 where ``attractor``
        holds a label k (:attr:`labelled`), 2 for an attractor without a k
        (:attr:`running`), 0 for no label; the compiled reductions of the views read it."""
        table = np.zeros(256, np.int8)
        table[np.array(self.labelled, np.int64) + 128] = 1
        table[np.array(self.running, np.int64) + 128] = 2
        return table

    @property
    def fills(self) -> dict[str, object]:
        """The padding of each map variable (a tile's edge chunk; the label arrays' fill)."""
        return {name: var.padding for name, var in self.map_variables.items()}

    @property
    def bytes_per_orbit(self) -> int:
        """The basin map's bytes per grid point, uncompressed."""
        return sum(np.dtype(var.dtype).itemsize for var in self.map_variables.values())


class PointPlan(Protocol):
    """One parameter point, prepared: picklable, so that a Dask worker labels its tiles.

    ``label(x0, v0, rows, backend, numba_threads, t_max)`` labels the orbits from the
    initial states (``x0``, ``v0``), arrays that broadcast (a tile: the columns as a row
    vector, its rows as a column vector; the pre-flight estimate: two 1-D samples), ``rows``
    the tile's slice of the whole grid (None for a sample), ``t_max`` [s] where given instead
    of the config's (the estimate times a call stopped at once);
    ``certify(rows, labelled, numba_threads)`` turns its result into the tile's arrays
    ({map variable: array (rows, columns)}) and tally (a dict of counts the summary adds up).
    The two halves are separate so that the local scheduler certifies one tile while it
    labels the next."""

    def label(self, x0: np.ndarray, v0: np.ndarray, rows: slice | None = None,
              backend: str = "cpu", numba_threads: int | None = None,
              t_max: float | None = None) -> Any: ...

    def certify(self, rows: slice, labelled: Any, numba_threads: int | None
                ) -> tuple[dict[str, np.ndarray], dict]: ...


class Plan(Protocol):
    """A config's parameter points, prepared (:meth:`Planner.plan`): ``points`` one
    :class:`PointPlan` each, in the layout's order; ``groups`` the per-point groups to store
    (path → xarray Dataset); ``warnings`` the lines the sweep logs (on stderr, even when
    quiet); ``summary(tallies)`` the root summary variables (an xarray Dataset with the
    parameter dims leading) from each point's list of tile tallies."""

    points: list
    groups: dict
    warnings: list

    def summary(self, tallies: list[list[dict]]) -> Any: ...


class Planner(Protocol):
    """What a model's planner module defines (the pendulum's: :mod:`atlas.models.pendulum.plan`).

    - ``Section``: the pydantic model of its config section (a StrictModel of
      :mod:`atlas.pipeline.config_sections`) with ``values(name)`` (a parameter's values),
      ``swept`` (the parameters given as lists) and ``points`` (every parameter point);
    - ``check(cfg, study)``: the checks across the config's sections (ValueError "key:
      problem", which loading the config turns into one line naming the file), so that a
      valid config never fails after work began; every check that needs no computation
      belongs here; the module that defines it should import little (every config is
      validated by it);
    - ``begin(cfg, layout)``: what is prepared before anything is written (cheap; a bad
      input only computation shows raises :class:`~atlas.errors.AtlasError` here); a list,
      one per point, that
      ``sample(begun, p)`` turns into a :class:`PointPlan` good enough to label (the
      pre-flight estimate measures the rate with it);
    - ``plan(cfg, layout, begun, track)``: the :class:`Plan` (the slow part: ``track(items,
      total, desc)`` shows its progress).
    """

    Section: type

    def check(self, cfg, study: bool) -> None: ...

    def begin(self, cfg, layout) -> list: ...

    def sample(self, cfg, begun: list, p: int) -> PointPlan: ...

    def plan(self, cfg, layout, begun: list, track) -> Plan: ...
