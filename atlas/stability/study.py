"""A stability study: per parameter point, exactly (from the manifolds, no orbits sampled),
the basin stability of every rest state and of the running cycle, the minimal fatal shocks
of both, the Gaussian-perturbation stability if asked, and the basins for the tipping
probabilities; then every point of a config's parameter ranges, here or as Dask tasks.

A point is independent of every other: :func:`compute_point` takes numbers and returns
numbers (:class:`PointResult`), so a Dask worker computes whole points and a point lost with a
dead worker is computed again elsewhere with the same result. The exact numbers come from
:func:`atlas.boundaries.exact.exact_boundaries` (its ``areas`` are what a grid run stores as
``basin_fraction_exact``). A point exactly at the saddle-node |τ| = ω0² has no certified
boundaries: its values are NaN and its status says why (:data:`POINT_STATUS`); a point whose
boundaries fail (a bug, or a torque within rounding of the homoclinic one) likewise, with the
reason, and the study goes on.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from atlas.stability.bifurcations import at_saddle_node
from atlas.stability.shocks import (
    FatalShock,
    RunningShock,
    minimal_fatal_shock,
    running_fatal_shock,
)

__all__ = ["StudySettings", "PointResult", "compute_point", "compute_points", "POINT_STATUS",
           "PHASES", "gaussian_box"]

#: The status of a parameter point (CF flag values of ``point_status``).
POINT_STATUS = {"exact": 0, "saddle_node": 1, "failed": 2}
#: The phases of a point's cost, in order (``atlas stability -v``, ``atlas bench``).
PHASES = ("boundaries", "shock", "gaussian", "basins")


@dataclass(frozen=True)
class StudySettings:
    """What every point computes: the ``window`` ((θmin, θmax) [rad], (θ̇min, θ̇max)
    [rad s⁻¹]), the Gaussian's ``sigma`` (σθ [rad], σθ̇ [rad s⁻¹]) or None, and whether the
    basins are kept as polygons for the tipping probabilities."""

    window: tuple[tuple[float, float], tuple[float, float]]
    sigma: tuple[float, float] | None = None
    tipping: bool = False


@dataclass
class PointResult:
    """One parameter point's numbers. ``k`` the wells whose basins meet the window, with
    ``fraction`` and ``error``; ``running``, ``running_error``; ``running_shock`` of the
    running limit cycle; ``shock`` of well 0's rest
    state; ``gaussian`` (P, error) or (NaN, NaN); ``basins`` {basin: shapely geometry ∩
    window} when tipping is asked; ``status`` (:data:`POINT_STATUS`) and ``message``;
    ``seconds`` per phase."""

    alpha: float
    omega0: float
    torque: float
    status: int = POINT_STATUS["exact"]
    message: str = ""
    k: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    fraction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    running: float = math.nan
    running_error: float = math.nan
    shock: FatalShock = FatalShock(math.nan, math.nan, math.nan, math.nan)
    running_shock: RunningShock = RunningShock(*(math.nan,) * 6)
    gaussian: tuple[float, float] = (math.nan, math.nan)
    basins: dict | None = None
    seconds: dict = field(default_factory=dict)


def gaussian_box(rest_angle: float, sigma: tuple[float, float]):
    """The window ((θmin, θmax) [rad], (θ̇min, θ̇max) [rad s⁻¹]) whose exact boundaries the
    Gaussian stability of the rest state at ``rest_angle`` [rad] needs: ±REACH σθ around it,
    and speeds to REACH σθ̇ and 0.5 rad s⁻¹ beyond (:mod:`atlas.stability.gaussian`)."""
    from atlas.stability.gaussian import REACH

    s_theta, s_dot = sigma
    speed = REACH * s_dot + 0.5
    return ((rest_angle - REACH * s_theta, rest_angle + REACH * s_theta), (-speed, speed))


def _gaussian(boundaries, settings: StudySettings):
    """(P, error) of well 0's rest state; the boundaries are integrated again over the
    Gaussian's box where the window's do not reach it."""
    from atlas.boundaries.exact import exact_boundaries
    from atlas.stability.gaussian import gaussian_stability
    from atlas.stability.polygons import basin_shape

    box = gaussian_box(boundaries.pendulum.rest_angle, settings.sigma)
    speed = box[1][1]
    if speed > boundaries.outline_reach:  # beyond the band they were built for: build there
        boundaries = exact_boundaries(boundaries.pendulum, box)
    return gaussian_stability(basin_shape(boundaries, speed), *settings.sigma)


def compute_point(alpha: float, omega0: float, torque: float,
                  settings: StudySettings) -> PointResult:
    """Every number of one parameter point (module docstring)."""
    from atlas.boundaries.exact import exact_boundaries
    from atlas.physics.pendulum import Pendulum
    from atlas.stability.polygons import basin_shape, window_basins

    out = PointResult(alpha, omega0, torque)
    if at_saddle_node(omega0, torque):
        out.status = POINT_STATUS["saddle_node"]
        out.message = (f"|torque| = omega0^2 = {omega0 * omega0:g}: the saddle-node, no "
                       "certified boundaries (values NaN)")
        return out
    clock = time.perf_counter()
    try:
        p = Pendulum(alpha, omega0, torque)
        boundaries = exact_boundaries(p, settings.window)
        areas = boundaries.areas
        out.k, out.fraction, out.error = areas.k, areas.fraction, areas.error
        out.running, out.running_error = float(areas.running), float(areas.running_error)
        out.seconds["boundaries"], clock = time.perf_counter() - clock, time.perf_counter()
        out.shock = minimal_fatal_shock(boundaries)
        if p.has_rest_states:
            out.running_shock = running_fatal_shock(boundaries)
        out.seconds["shock"], clock = time.perf_counter() - clock, time.perf_counter()
        if settings.sigma is not None and p.has_rest_states:
            out.gaussian = _gaussian(boundaries, settings)
        out.seconds["gaussian"], clock = time.perf_counter() - clock, time.perf_counter()
        if settings.tipping:
            shape = basin_shape(boundaries) if p.has_rest_states else None
            out.basins = window_basins(shape, settings.window, out.k,
                                       boundaries.running_possible)
        out.seconds["basins"] = time.perf_counter() - clock
    except (RuntimeError, ValueError) as exc:
        out = PointResult(alpha, omega0, torque, status=POINT_STATUS["failed"],
                          message=f"the exact boundaries failed: {exc}")
    return out


#: Points per thread below which a local study stays in this thread.
_POINTS_PER_THREAD = 4


def _point_task(alpha: float, omega0: float, torque: float, settings: StudySettings,
                numba_threads: int | None = None) -> PointResult:
    """:func:`compute_point` as a task of :func:`atlas.pipeline.schedule.point_results`,
    with ``numba_threads`` Numba threads where given (a Dask worker's share of its host)."""
    from atlas.kernels.threads import use_threads

    use_threads(numba_threads)
    return compute_point(alpha, omega0, torque, settings)


def compute_points(points: list[tuple[float, float, float]], settings: StudySettings, *,
                   backend: str = "cpu", scheduler: str | None = None,
                   workers: int | None = None,
                   on_result: Callable[[int, PointResult], None] | None = None,
                   ) -> list[PointResult]:
    """:func:`compute_point` of every (α, ω0, τ) in ``points``, in their order: on this
    machine (``backend`` "cpu": here, or by ``workers`` threads for studies of at least 4
    points per thread; ``atlas stability`` asks for one per core) or as Dask tasks
    ("dask": on ``scheduler`` if given, else a local cluster of ``workers`` processes), each
    task one whole point.
    ``on_result(i, result)`` is called as each arrives (on the CPU in order, with Dask in
    the order they finish). A point's result does not depend on where it was computed."""
    from atlas.pipeline.schedule import point_results

    results: list[PointResult | None] = [None] * len(points)
    for i, result in point_results(_point_task, [(*point, settings) for point in points],
                                   backend=backend, scheduler=scheduler, workers=workers,
                                   per_thread=_POINTS_PER_THREAD):
        results[i] = result
        if on_result is not None:
            on_result(i, result)
    return results
