"""A second model, defined in the tests alone: the damped double-well Duffing oscillator

    ẍ + δẋ − x + x³ = 0,

whose two rest states (±1, 0) are the attractors and whose saddle (0, 0) splits the plane
into their basins. It is the proof that atlas's model seam (:mod:`atlas.models`) is real:
this file is the whole model (its description and its planner), it registers itself with
:func:`atlas.models.registry.register`, and :func:`atlas.run`, ``atlas info``, ``atlas
plot`` and ``atlas view`` take it with no edit to any module of atlas.

The label: the energy E = v²/2 − x²/2 + x⁴/4 decreases along every exact orbit
(dE/dt = −δv² ≤ 0), and E < 0 only inside one of the two wells (E ≥ 0 wherever x = 0), so an
orbit whose energy drops below 0 never leaves the well of sign(x): k = sign(x). RK4's energy
is not exactly monotone; the trap here asks E < −``TRAP_MARGIN`` (a fixed margin, enough for
the small steps the tests take, not a proof: the status says "for the RK4 map"). Plain
NumPy RK4, no Numba: the model is small, and the seam is what is tested.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import xarray as xr

from atlas.layout import Layout
from atlas.models.base import Axis, MapVariable, Model, status_flags
from atlas.models.registry import register
from atlas.pipeline.config_numbers import Numbers
from atlas.pipeline.config_sections import ParameterSection
from atlas.store.schema import summary_dataset

#: An orbit is trapped in its well once its energy is below −TRAP_MARGIN.
TRAP_MARGIN = 0.01
#: The status codes: the label's trap, no trap by t_max, a non-finite state.
TRAPPED, UNRESOLVED, NONFINITE = 0, 1, 2
FILL = int(np.iinfo(np.int16).min)

STATUSES = {TRAPPED: "trapped", UNRESOLVED: "unresolved", NONFINITE: "nonfinite"}
IN_FILE = {TRAPPED: f"energy below -{TRAP_MARGIN} (in one well) for the RK4 map",
           UNRESOLVED: "not trapped before t_max", NONFINITE: "a NaN or inf state was met"}

DUFFING = Model(
    name="duffing",
    title="double-well Duffing oscillator",
    parameters={"delta": ("s-1", "damping coefficient")},
    axes=(Axis("x0", "1", "initial position", "x0"),
          Axis("v0", "s-1", "initial velocity", "v0")),
    section="duffing",
    statuses=STATUSES,
    in_file=IN_FILE,
    map_variables={
        "attractor": MapVariable(np.int16, FILL, FILL, {
            "long_name": "index k of the rest state (k, 0) reached", "units": "1"}),
        "status": MapVariable(np.int8, None, np.int8(0), {
            "long_name": "labelling status", "units": "1", **status_flags(STATUSES, IN_FILE)}),
        "t_trap": MapVariable(np.float32, np.float32(np.nan), np.float32(np.nan), {
            "long_name": "time at which the orbit was trapped", "units": "s"}),
    },
    label_variables=("attractor", "status", "t_trap"),
    basin_variables={"basin_fraction": {
        "long_name": "fraction of the grid points labelled k (a count, not an area)"}},
    point_variables={"unresolved_fraction": {
        "long_name": "fraction of the grid without a label (unresolved or nonfinite)"}},
    attractor="the rest state (k, 0), k = -1 or +1",
    planner=__name__,
    positive=("delta",),
)
register(DUFFING)


class Section(ParameterSection):
    """The ``duffing:`` section: the damping δ [s⁻¹], a number, a list or a range."""

    NAMES: ClassVar[tuple[str, ...]] = tuple(DUFFING.parameters)
    delta: Numbers = 0.3


def check(cfg, study: bool) -> None:
    if study:
        raise ValueError("stability: the duffing model has no study")
    if min(cfg.section.values("delta")) <= 0:
        raise ValueError("duffing.delta: must be > 0 (without damping no orbit settles)")
    if cfg.integrator.t_max <= cfg.integrator.dt:
        raise ValueError("integrator.t_max: must be larger than dt")


def _energy(x, v):
    return 0.5 * v * v - 0.5 * x * x + 0.25 * x ** 4


class DuffingPoint:
    """One δ, prepared: RK4 with step ``dt`` [s] up to ``t_max`` [s], the energy trap."""

    def __init__(self, delta: float, dt: float, t_max: float):
        self.delta, self.dt, self.t_max = delta, dt, t_max

    def _field(self, x, v):
        return v, -self.delta * v + x - x ** 3

    def label(self, x0, v0, rows=None, backend="cpu", numba_threads=None, t_max=None):
        x, v = (np.array(a, np.float64) for a in np.broadcast_arrays(x0, v0))
        attractor = np.full(x.shape, FILL, np.int16)
        status = np.full(x.shape, UNRESOLVED, np.int8)
        t_trap = np.full(x.shape, np.nan, np.float32)
        live, h = np.ones(x.shape, bool), self.dt
        steps = int(round((self.t_max if t_max is None else t_max) / h))
        for n in range(steps + 1):
            energy = _energy(x, v)
            bad = live & ~np.isfinite(energy)
            status[bad] = NONFINITE
            done = live & (energy < -TRAP_MARGIN)
            attractor[done] = np.sign(x[done]).astype(np.int16)
            status[done], t_trap[done] = TRAPPED, n * h
            live &= ~(done | bad)
            if not live.any() or n == steps:
                break
            xs, vs = x[live], v[live]
            k1 = self._field(xs, vs)
            k2 = self._field(xs + 0.5 * h * k1[0], vs + 0.5 * h * k1[1])
            k3 = self._field(xs + 0.5 * h * k2[0], vs + 0.5 * h * k2[1])
            k4 = self._field(xs + h * k3[0], vs + h * k3[1])
            x[live] = xs + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            v[live] = vs + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        return attractor, status, t_trap

    def certify(self, rows, labelled, numba_threads=None):
        attractor, status, t_trap = labelled
        tally = {"minus": np.int64((attractor == -1).sum()),
                 "plus": np.int64((attractor == 1).sum()),
                 "unlabelled": np.int64((status != TRAPPED).sum())}
        return {"attractor": attractor, "status": status, "t_trap": t_trap}, tally


class DuffingPlan:
    def __init__(self, layout: Layout, points: list[DuffingPoint]):
        self.layout, self.points, self.groups, self.warnings = layout, points, {}, []

    def summary(self, tallies: list[list[dict]]) -> xr.Dataset:
        orbits = self.layout.x0.size * self.layout.v0.size
        out = []
        for point in tallies:
            total = {name: sum(int(t[name]) for t in point) for name in point[0]}
            out.append({"k": [-1, 1],
                        "basin_fraction": np.array([total["minus"], total["plus"]]) / orbits,
                        "unresolved_fraction": total["unlabelled"] / orbits})
        return summary_dataset(self.layout, out)


def begin(cfg, layout: Layout) -> list[DuffingPoint]:
    return [DuffingPoint(layout.point(p)["delta"], cfg.integrator.dt, cfg.integrator.t_max)
            for p in range(layout.n_params)]


def sample(cfg, begun: list[DuffingPoint], p: int) -> DuffingPoint:
    return begun[p]


def plan(cfg, layout: Layout, begun: list[DuffingPoint], track=None) -> DuffingPlan:
    return DuffingPlan(layout, begun)
