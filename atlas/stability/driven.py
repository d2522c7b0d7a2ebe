"""A driven pendulum's stability study: its attractors followed along one swept parameter,
their basin fractions sampled, their bifurcations located.

Per parameter point (:func:`compute_point`, independent of every other, so a CPU thread or
a Dask worker computes whole points): the attractors of the stroboscopic map P are found
(:func:`atlas.models.driven.points.prepared`, as a grid run prepares its points), then
``samples`` initial conditions, drawn uniformly in the window by NumPy's PCG64 seeded with
``seed`` — the same states at every point (common random numbers: the change of a fraction
from one point to the next is the attractors', not the draw's) — are labelled
(:meth:`DrivenPoint.label`), and counted per attractor. A fraction f of N samples has the
binomial standard error √(f(1 − f)/N).

Then (:func:`compute_study`): the attractors are matched from point to point and given
global ids (:func:`atlas.models.driven.continuation.follow`); each step with events (a
birth, a death, a period change) is one task, again on CPU threads or Dask, that bridges
its attractors through midpoints where some die and others are born
(:func:`~atlas.models.driven.continuation.bridge`) and locates each event by bisection in
the parameter (:func:`~atlas.models.driven.continuation.locate`), the midpoints' searches
shared. :func:`driven_dataset` lays it out as
:mod:`atlas.store.driven_study` says.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import datetime, timezone

import numpy as np
import xarray as xr

from atlas.models.driven.attractors import Attractor, Drive, find_attractors
from atlas.models.driven.continuation import (
    EVENT_KINDS,
    MATCH_POINTS,
    THRESHOLD,
    Event,
    Located,
    bridge,
    changes,
    follow,
    locate,
)
from atlas.models.driven.description import steps_per_period
from atlas.models.driven.points import prepared

__all__ = ["DrivenSettings", "DrivenPointResult", "DrivenStudy", "initial_states",
           "compute_point", "compute_study", "driven_dataset", "STORED_POINTS"]

#: The most points of a chaotic attractor's cloud a study keeps (matching, file).
STORED_POINTS = MATCH_POINTS


@dataclass(frozen=True)
class DrivenSettings:
    """What every point computes: the ``window`` ((θ lo, hi) [rad], (θ̇ lo, hi)
    [rad s⁻¹]), ``samples`` and ``seed`` of the initial conditions, the search's
    ``max_period``, each orbit's ``t_max`` [s], the RK4 step ``dt`` [s] (T/N); the matching
    ``threshold``, and the bisection's ``rtol`` and ``max_steps``."""

    window: tuple[tuple[float, float], tuple[float, float]]
    samples: int
    seed: int
    max_period: int
    t_max: float
    dt: float
    threshold: float = THRESHOLD
    rtol: float = 1e-4
    max_steps: int = 16


@dataclass
class DrivenPointResult:
    """One parameter point: its ``params`` (α, ω0, τ, A, Ω, φ by name), its
    ``attractors`` (clouds thinned to :data:`STORED_POINTS`), the ``statuses`` their labels
    get, the ``counts`` of samples that reached each, the ``unresolved`` count, and
    ``seconds`` per phase."""

    params: dict
    attractors: list[Attractor]
    statuses: np.ndarray
    counts: np.ndarray
    unresolved: int
    seconds: dict = field(default_factory=dict)


def initial_states(window, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(θ0, θ̇0) of the study's ``samples`` initial conditions, uniform in ``window``:
    PCG64 seeded with ``seed``, θ0 drawn first; the same arrays whatever the machine."""
    rng = np.random.default_rng(seed)
    (t0, t1), (v0, v1) = window
    return rng.uniform(t0, t1, samples), rng.uniform(v0, v1, samples)


def _drive(params: dict, dt: float) -> Drive:
    return Drive(float(params["alpha"]), float(params["omega0"]), float(params["torque"]),
                 float(params["amplitude"]), float(params["frequency"]),
                 float(params["phase"]), steps_per_period(params["frequency"], dt))


def _thinned(attractors: list[Attractor]) -> list[Attractor]:
    out = []
    for a in attractors:
        if len(a.points) > STORED_POINTS:
            keep = np.linspace(0, len(a.points) - 1, STORED_POINTS).astype(np.int64)
            a = replace(a, points=a.points[keep])
        out.append(a)
    return out


def compute_point(params: dict, settings: DrivenSettings,
                  numba_threads: int | None = None) -> DrivenPointResult:
    """One parameter point (module docstring)."""
    from atlas.kernels.threads import use_threads

    use_threads(numba_threads)
    clock = time.perf_counter()
    point, found, statuses, _ = prepared(_drive(params, settings.dt), settings.window,
                                         settings.max_period, settings.t_max)
    seconds = {"attractors": time.perf_counter() - clock}
    clock = time.perf_counter()
    theta, theta_dot = initial_states(settings.window, settings.samples, settings.seed)
    attractor = point.label(theta, theta_dot, numba_threads=numba_threads)[0]
    decided = attractor >= 0
    counts = np.bincount(attractor[decided].astype(np.int64), minlength=len(found))
    seconds["samples"] = time.perf_counter() - clock
    return DrivenPointResult(dict(params), _thinned(found), statuses, counts,
                             int((~decided).sum()), seconds)


def _attractors_at(params: dict, swept: str, value: float, settings: DrivenSettings
                   ) -> list[Attractor]:
    return _thinned(find_attractors(_drive({**params, swept: value}, settings.dt),
                                    settings.window, max_period=settings.max_period))


def _step_task(params: dict, swept: str, lo: float, hi: float, at_lo: list[Attractor],
               at_hi: list[Attractor], settings: DrivenSettings,
               numba_threads: int | None = None) -> tuple[dict[int, int], dict]:
    """One step of the sweep with events (one task): its pairs, bridged through midpoints
    where attractors die and are born (:func:`~atlas.models.driven.continuation.bridge`),
    and each of its events located (:func:`~atlas.models.driven.continuation.locate`), the
    attractors of every midpoint found once for both: (pairs, {(kind, index before, index
    after): Located})."""
    from atlas.kernels.threads import use_threads

    use_threads(numba_threads)
    cache: dict[float, list[Attractor]] = {}

    def find(value: float) -> list[Attractor]:
        if value not in cache:
            cache[value] = _attractors_at(params, swept, value, settings)
        return cache[value]

    pairs = bridge(find, lo, hi, at_lo, at_hi, settings.threshold)
    events = changes(at_lo, at_hi, pairs)
    located = locate(find, lo, hi, at_lo, at_hi, events, threshold=settings.threshold,
                     rtol=settings.rtol, max_steps=settings.max_steps)
    return pairs, {(e.kind, e.before, e.after): p for e, p in zip(events, located)}


@dataclass
class DrivenStudy:
    """A computed study: the points' results in sweep order, each point's global ids
    (:func:`~atlas.models.driven.continuation.follow`), the events and where each was
    located (same order), the swept parameter (None: one point), and seconds per stage."""

    results: list[DrivenPointResult]
    ids: list[np.ndarray]
    events: list[Event]
    located: list[Located]
    swept: str | None
    seconds: dict = field(default_factory=dict)


def compute_study(points: list[dict], swept: str | None, settings: DrivenSettings, *,
                  backend: str = "cpu", scheduler: str | None = None,
                  workers: int | None = None,
                  on_result: Callable[[int, DrivenPointResult], None] | None = None
                  ) -> DrivenStudy:
    """Every point of a 1-D sweep (``points`` in the order of ``swept``'s values), then the
    matching, the bridges and the events' bisections (:func:`_step_task`): on this machine
    (``backend`` "cpu", ``workers`` threads) or as Dask tasks ("dask", on ``scheduler`` or
    a local cluster), as
    :func:`atlas.pipeline.schedule.point_results` runs them. The result does not depend on
    where or on how many threads: each task is computed alone, and the matching after."""
    from atlas.pipeline.schedule import point_results

    clock = time.perf_counter()
    results: list[DrivenPointResult | None] = [None] * len(points)
    for i, result in point_results(compute_point, [(p, settings) for p in points],
                                   backend=backend, scheduler=scheduler, workers=workers,
                                   per_thread=2):
        results[i] = result
        if on_result is not None:
            on_result(i, result)
    seconds = {"points": time.perf_counter() - clock}
    clock = time.perf_counter()
    found = [r.attractors for r in results]
    ids, events = follow(found, settings.threshold)
    steps = sorted({e.step for e in events}) if swept is not None else []
    tasks = [(results[s].params, swept, results[s].params[swept],
              results[s + 1].params[swept], found[s], found[s + 1], settings) for s in steps]
    pairs, where = {}, {}
    for t, (paired, placed) in point_results(_step_task, tasks, backend=backend,
                                             scheduler=scheduler, workers=workers,
                                             per_thread=1):
        pairs[steps[t] + 1] = paired
        where.update({(steps[t], *key): p for key, p in placed.items()})
    ids, events = follow(found, settings.threshold, pairs)
    located = [where.get((e.step, e.kind, e.before, e.after)) for e in events]
    seconds["bifurcations"] = time.perf_counter() - clock
    return DrivenStudy(results, ids, events, located, swept, seconds)


def driven_dataset(cfg, settings: DrivenSettings, study: DrivenStudy) -> xr.Dataset:
    """The study file's Dataset (:mod:`atlas.store.driven_study`) of ``cfg`` (validated)."""
    from atlas.models.driven.description import PARAMETERS
    from atlas.pipeline.identity import library_versions
    from atlas.store.driven_study import (
        DRIVEN_MODEL,
        DRIVEN_PARAMETERS,
        driven_attrs,
    )
    from atlas.store.schema import STUDY_SCHEMA
    from atlas.store.study import STUDY_FORMAT

    pend = cfg.pendulum
    dim = study.swept or "amplitude"
    n, g = len(study.results), 1 + max([int(i.max()) for i in study.ids if i.size] + [-1])
    nan = np.full((n, g), np.nan)
    frac, err = nan.copy(), nan.copy()
    kind = np.zeros((n, g), np.int8)
    period = np.full((n, g), -1, np.int32)
    winding = np.zeros((n, g), np.int32)
    status = np.full((n, g), -1, np.int8)
    unresolved = np.zeros(n)
    orbit = {"orbit_step": [], "orbit_attractor": [], "orbit_theta": [],
             "orbit_theta_dot": []}
    samples = settings.samples
    for p, (r, ids) in enumerate(zip(study.results, study.ids)):
        for a, gid, count, st in zip(r.attractors, ids, r.counts, r.statuses):
            f = count / samples
            frac[p, gid], err[p, gid] = f, np.sqrt(f * (1 - f) / samples)
            kind[p, gid] = 1 if a.kind == "periodic" else 2
            period[p, gid], winding[p, gid], status[p, gid] = a.period, a.winding, st
            orbit["orbit_step"].append(np.full(len(a.points), p, np.int32))
            orbit["orbit_attractor"].append(np.full(len(a.points), gid, np.int64))
            orbit["orbit_theta"].append(a.points[:, 0])
            orbit["orbit_theta_dot"].append(a.points[:, 1])
        unresolved[p] = r.unresolved / samples
    dtypes = {"orbit_step": np.int32, "orbit_attractor": np.int64,
              "orbit_theta": np.float64, "orbit_theta_dot": np.float64}
    orbit = {k: np.concatenate(v).astype(dtypes[k]) if v else np.zeros(0, dtypes[k])
             for k, v in orbit.items()}
    events, located = study.events, study.located
    table = {"bifurcation_value": np.array([np.nan if p is None else p.value
                                            for p in located], np.float64),
             "bifurcation_error": np.array([np.nan if p is None else p.error
                                            for p in located], np.float64),
             "bifurcation_kind": np.array([EVENT_KINDS.index(e.kind) for e in events],
                                          np.int8),
             "bifurcation_attractor": np.array([e.attractor for e in events], np.int64),
             "bifurcation_period_before": np.array([e.period_before for e in events],
                                                   np.int32),
             "bifurcation_period_after": np.array([e.period_after for e in events],
                                                  np.int32),
             "bifurcation_step": np.array([e.step for e in events], np.int32)}
    data = {}

    def put(name, array, dims):
        data[name] = (dims, array, driven_attrs(name))

    put("basin_fraction", frac, (dim, "attractor_id"))
    put("basin_fraction_error", err, (dim, "attractor_id"))
    put("unresolved_fraction", unresolved, (dim,))
    put("unresolved_fraction_error", np.sqrt(unresolved * (1 - unresolved) / samples), (dim,))
    put("attractor_count", np.array([len(r.attractors) for r in study.results], np.int32),
        (dim,))
    put("attractor_kind", kind, (dim, "attractor_id"))
    put("attractor_period", period, (dim, "attractor_id"))
    put("attractor_winding", winding, (dim, "attractor_id"))
    put("attractor_status", status, (dim, "attractor_id"))
    for name, array in orbit.items():
        put(name, array, ("orbit_point",))
    for name, array in table.items():
        put(name, array, ("bifurcation",))
    units = PARAMETERS
    for name in ("bifurcation_value", "bifurcation_error"):
        data[name][2]["units"] = units[dim][0]
    coords = {}
    for name in DRIVEN_PARAMETERS:
        values = [float(r.params[name]) for r in study.results]
        coords[name] = ((dim, np.array(values, np.float64)) if name == dim
                        else ((), float(pend.values(name)[0])))
    coords["attractor_id"] = ("attractor_id", np.arange(g, dtype=np.int64))
    attrs = {"title": f"atlas stability study of a driven pendulum: {cfg.name}",
             "Conventions": "CF-1.10", "atlas_schema": STUDY_SCHEMA,
             "format_version": np.int64(STUDY_FORMAT), "model": DRIVEN_MODEL,
             "config": cfg.to_json(), "swept_parameter": dim,
             "samples": np.int64(samples), "seed": np.int64(settings.seed),
             "sampling": "uniform in the window, numpy PCG64 seeded with seed, theta0 drawn "
                         "first, the same states at every point",
             "window_theta": np.array(settings.window[0], float),
             "window_theta_dot": np.array(settings.window[1], float),
             "max_period": np.int64(settings.max_period), "t_max": float(settings.t_max),
             "dt": float(settings.dt),
             "matching": "set distance: least Euclidean distance between the two "
                         "attractors' points on P, theta differences wrapped; pairs of "
                         "least total distance (Hungarian) nearer than matching_threshold",
             "matching_threshold": float(settings.threshold),
             "bisection_rtol": float(settings.rtol),
             "bisection_max_steps": np.int64(settings.max_steps),
             "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             **library_versions()}
    ds = xr.Dataset(data, coords=coords, attrs=attrs)
    for name in DRIVEN_PARAMETERS:
        unit, long_name = units[name]
        ds[name].attrs.update(long_name=long_name, units=unit)
    ds["attractor_id"].attrs.update(long_name="global id of an attractor followed along "
                                    "the sweep", units="1")
    return ds

