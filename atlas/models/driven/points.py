"""The driven pendulum's parameter points, prepared (what its planner,
:mod:`atlas.models.driven.plan`, hands the sweep): per point the stroboscopic map's
attractors (:mod:`atlas.models.driven.attractors`), their capture radius and contraction,
the ``/attractors`` group, and one picklable :class:`DrivenPoint` that labels a tile
(:func:`atlas.kernels.driven.label_driven`: each orbit stops as soon as its label is
decided) and counts its labels.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.kernels import driven as kernels
from atlas.kernels.threads import use_threads
from atlas.layout import Layout, per_point, point_label
from atlas.models.driven.attractors import (
    Attractor,
    Drive,
    beyond_bound,
    capture,
    capture_radius,
    find_attractors,
)
from atlas.models.driven.description import (
    ATTRACTOR_FILL,
    CHAOTIC,
    CONVERGED,
    MAX_PERIOD,
    NEAR,
    NONFINITE,
    UNRESOLVED,
    confirm_returns,
    steps_per_period,
    stored_confirm,
)
from atlas.store.schema import summary_dataset

__all__ = ["DrivenPoint", "DrivenPlan", "drives", "begin", "plan",
           "attractors_dataset", "stored_point", "search_window", "shifted_spread",
           "prepared"]

#: Points of a chaotic attractor's cloud stored in ``/attractors`` (and used as targets).
CLOUD_POINTS = 2000


def drives(cfg, layout: Layout) -> list[Drive]:
    """The drive of every parameter point with its N = T/dt steps per period (a whole number:
    :func:`atlas.models.driven.plan.check`)."""
    out = []
    for p in range(layout.n_params):
        point = layout.point(p)
        out.append(Drive(point["alpha"], point["omega0"], point["torque"], point["amplitude"],
                         point["frequency"], point["phase"],
                         steps_per_period(point["frequency"], cfg.integrator.dt)))
    return out


@dataclass(frozen=True)
class DrivenPoint:
    """One parameter point, prepared (:class:`atlas.models.base.PointPlan`): the drive, the
    targets (every attractor's points on P, θ wrapped) with the index of their attractor
    and their capture radius, the status each attractor's labels get and the returns in a
    row that decide them (:func:`confirm_returns`), the most periods (t_max / T), and the
    grid (θ0 columns, θ̇0 rows) whose tiles :meth:`certify` labels
    again at dt/2 (None: not checked)."""

    drive: Drive
    targets: np.ndarray
    target_attractor: np.ndarray
    attractor_status: np.ndarray
    radius: np.ndarray
    confirm: np.ndarray
    max_periods: int
    grid: tuple[np.ndarray, np.ndarray] | None = None

    @classmethod
    def searching(cls, drive: Drive, t_max: float) -> DrivenPoint:
        """The point with no attractor to reach: every orbit runs to ``t_max`` [s] (what a
        label costs at most: the pre-flight estimate's sample)."""
        return cls(drive, np.zeros((0, 2)), np.zeros(0, np.int16), np.zeros(0, np.int8),
                   np.zeros(0), np.zeros(0, np.int64), max(1, int(t_max / drive.period)))

    def label(self, x0, v0, rows=None, backend: str = "cpu", numba_threads=None,
              t_max: float | None = None):
        """The labels of the orbits from θ0 = ``x0`` [rad], θ̇0 = ``v0`` [rad s⁻¹] (arrays
        that broadcast): (attractor, status, t_trap [s]) shaped as their broadcast, by the
        CPU kernel or (``backend`` "cuda") the GPU's, one thread per orbit, same rule; and
        the backend, for :meth:`certify`'s labels at dt/2."""
        use_threads(numba_threads)
        theta, theta_dot = (np.ascontiguousarray(a, np.float64).ravel()
                            for a in np.broadcast_arrays(x0, v0))
        shape = np.broadcast_shapes(np.shape(x0), np.shape(v0))
        periods_max = self.max_periods if t_max is None else \
            max(1, int(t_max / self.drive.period))
        d = self.drive
        if backend == "cuda":
            from atlas.kernels.driven_cuda import label_driven_cuda as labelling
        else:
            labelling = kernels.label_driven
        attractor, periods, status = labelling(
            theta, theta_dot, d.alpha, d.omega0, d.torque, d.table, d.dt, self.targets,
            self.target_attractor, self.radius, self.confirm, periods_max)
        decided = status == 0
        status = status.astype(np.int8)
        status[decided] = self.attractor_status[attractor[decided]]
        t_trap = np.where(decided, periods * d.period, np.nan).astype(np.float32)
        attractor = np.where(decided, attractor, ATTRACTOR_FILL).astype(np.int16)
        return (attractor.reshape(shape), status.reshape(shape), t_trap.reshape(shape),
                backend)

    def halved(self) -> DrivenPoint:
        """The same point on the RK4 map with half the step (2N steps per period), the same
        targets (the attractors move by RK4's error, far less than a capture radius)."""
        drive = replace(self.drive, steps_per_period=2 * self.drive.steps_per_period)
        return replace(self, drive=drive, grid=None)

    def certify(self, rows, labelled, numba_threads=None) -> tuple[dict, dict]:
        """The tile's arrays as labelled (a label of P is not certified for the exact
        equation: the statuses say what it is), with ``changes_at_half_dt``: 1 where the
        tile's orbit, labelled again with dt/2, reaches another attractor (or none); and its
        tally: the count of each attractor at dt and at dt/2, of changed labels and of
        unlabelled orbits."""
        attractor, status, t_trap, backend = labelled
        if self.grid is not None and rows is not None:
            x0, v0 = self.grid
            again = self.halved().label(x0[None, :], v0[rows][:, None], backend=backend,
                                        numba_threads=numba_threads)[0]
        else:
            again = attractor
        changed = (again != attractor).astype(np.int8)

        def count(labels):
            return np.bincount(labels[labels >= 0].ravel(),
                               minlength=len(self.attractor_status)).astype(np.int64)

        unlabelled = np.int64(np.isin(status, (UNRESOLVED, NONFINITE)).sum())
        tally = {"count": count(attractor), "count_half_dt": count(again),
                 "changed": np.int64(changed.sum()), "unlabelled": unlabelled,
                 "labels": attractor}  # the map's rows, for the fractal measures
        if self.grid is not None and rows is not None:
            # the four interleaved half-resolution grids (row parity, column parity)
            row_parity = np.arange(len(self.grid[1]))[rows] % 2
            column_parity = np.arange(attractor.shape[-1]) % 2
            tally["count_shifted"] = np.array([
                count(attractor[row_parity == i][:, column_parity == j])
                for i in (0, 1) for j in (0, 1)])
        return ({"attractor": attractor, "status": status, "t_trap": t_trap,
                 "changes_at_half_dt": changed}, tally)


def shifted_spread(counts: np.ndarray, rows: int, columns: int) -> np.ndarray:
    """The spread of each basin's fraction over the four interleaved half-resolution grids
    of a ``rows`` × ``columns`` grid (``counts`` (4, K): its labels counted on the points
    of each row parity and column parity), as an error of the whole grid's fraction: the
    standard deviation of the four fractions over √4, their mean being (nearly) the grid's.
    Four shifts of one coarse lattice, as the random shifts of a randomised lattice rule
    (Owen, *Practical Quasi-Monte Carlo Integration*, 2023, ch. 17): for a smooth boundary
    their spread is of the lattice's error at the coarse spacing (an upper bound for the
    fine grid's), for a fractal one it shows the error that a grid count makes there, which
    the binomial standard error does not."""
    sizes = np.array([((rows + 1 - i) // 2) * ((columns + 1 - j) // 2)
                      for i in (0, 1) for j in (0, 1)], float)
    if np.any(sizes == 0) or counts.shape[0] != 4:
        return np.full(counts.shape[-1], np.nan)
    return np.std(counts / sizes[:, None], axis=0, ddof=1) / 2.0


def attractors_dataset(drive: Drive, attractors: list[Attractor], statuses: np.ndarray,
                       radii: np.ndarray, max_period: int = MAX_PERIOD) -> xr.Dataset:
    """One parameter point's node of ``/attractors``: per attractor its kind, period,
    winding, status its labels get, the returns in a row that decide them
    (:func:`confirm_returns`), capture radius, Floquet multipliers' moduli and its
    points on P (θ wrapped to [−π, π), θ̇; NaN past its own count), with the discretisation
    and the period bound ``max_period`` of the search as attributes."""
    n = max([len(a.points) for a in attractors] + [1])
    theta = np.full((len(attractors), n), np.nan)
    theta_dot = np.full((len(attractors), n), np.nan)
    for i, a in enumerate(attractors):
        theta[i, :len(a.points)], theta_dot[i, :len(a.points)] = a.points.T
    moduli = np.array([np.abs(a.multipliers) for a in attractors]).reshape(-1, 2)
    return xr.Dataset(
        {"kind": ("attractor", np.array([a.kind for a in attractors], dtype=str),
                  {"long_name": "periodic, or chaotic (recurrent, and not periodic with "
                               "a period up to max_period)"}),
         "period": ("attractor", np.array([a.period for a in attractors], np.int32),
                    {"units": "1", "long_name": "period in drive periods (0: chaotic)"}),
         "winding": ("attractor", np.array([a.winding for a in attractors], np.int32),
                     {"units": "1", "long_name": "net turns of the orbit over its period"}),
         "status": ("attractor", statuses.astype(np.int8),
                    {"units": "1", "long_name": "the status of this attractor's labels"}),
         "confirm": ("attractor", confirm_returns(statuses),
                     {"units": "1", "long_name": "returns of P in a row within the capture "
                                                 "radius that decide a label: 1 where the "
                                                 "capture ball was seen to map into itself"}),
         "floquet_modulus": (("attractor", "multiplier"), moduli,
                             {"units": "1", "long_name": "moduli of the Floquet multipliers "
                                                         "(NaN: chaotic)"}),
         "capture_radius": ("attractor", np.asarray(radii, np.float64),
                            {"long_name": "radius around each of its points on P within "
                                          "which returns count as reaching it",
                             "comment": "rad (theta) and rad s-1 (theta_dot) as one "
                                        "Euclidean unit"}),
         "residual": ("attractor", np.array([a.residual for a in attractors]),
                      {"long_name": "|P^p(x) - x - (2 pi winding, 0)| after Newton's "
                                    "refinement (NaN: chaotic)"}),
         "theta": (("attractor", "sample"), theta,
                   {"units": "rad", "long_name": "angle of the orbit's points on the "
                                                 "stroboscopic map, wrapped to [-pi, pi)"}),
         "theta_dot": (("attractor", "sample"), theta_dot,
                       {"units": "rad s-1", "long_name": "angular velocity of the orbit's "
                                                         "points on the stroboscopic map"})},
        coords={"attractor": ("attractor", np.arange(len(attractors), dtype=np.int16))},
        attrs={"description": "attractors of the stroboscopic map (one drive period of RK4 "
                              "with dt = period / steps_per_period), found from seeds "
                              "spread over the window",
               "steps_per_period": np.int64(drive.steps_per_period),
               "drive_period": drive.period, "drive_period_units": "s",
               "max_period": np.int64(max_period)})


@dataclass
class DrivenPlan:
    """Every parameter point of a driven config, prepared (:class:`atlas.models.base.Plan`)."""

    layout: Layout
    points: list[DrivenPoint]
    groups: dict[str, xr.Dataset]
    warnings: list[str]

    def summary(self, tallies: list[list[dict]]) -> xr.Dataset:
        """Per point: each attractor's share of the grid, its uncertainty (the binomial
        standard error plus the share's change when dt is halved), the share of labels that
        change at dt/2, the unlabelled share and the number of attractors."""
        n = self.layout.x0.size * self.layout.v0.size
        out = []
        for tally in tallies:
            f = np.sum([t["count"] for t in tally], axis=0) / n
            f_half = np.sum([t["count_half_dt"] for t in tally], axis=0) / n
            shifted = shifted_spread(np.sum([t["count_shifted"] for t in tally], axis=0),
                                     self.layout.v0.size, self.layout.x0.size)
            sampling = np.maximum(np.sqrt(f * (1 - f) / n), shifted)
            out.append({"k": list(range(len(f))), "basin_fraction": f,
                        "basin_fraction_shifted_spread": shifted,
                        "basin_fraction_error": sampling + np.abs(f - f_half),
                        "unresolved_fraction": sum(int(t["unlabelled"]) for t in tally) / n,
                        "changed_at_half_dt_fraction":
                            sum(int(t["changed"]) for t in tally) / n,
                        "attractor_count": float(len(f))})
        return summary_dataset(self.layout, out).merge(self._measured(tallies))

    def _measured(self, tallies: list[list[dict]]) -> xr.Dataset:
        """The fractal measures of every point's map (:mod:`atlas.models.driven.measures`),
        from its tiles' rows; none where a tile holds no rows (a partial run of an earlier
        version)."""
        from atlas.models.driven import measures

        layout = self.layout
        if not all("labels" in t for tally in tallies for t in tally):
            return xr.Dataset()
        found = [measures.measure(point, np.concatenate([t["labels"] for t in tally]),
                                  layout.x0, layout.v0, len(point.attractor_status))
                 for point, tally in zip(self.points, tallies)]
        lead, dims = layout.parameter_shape, layout.swept
        seen = max([len(m["wada"]) for m in found] + [1])
        data = {}
        for name, attrs in MEASURES.items():
            values = np.array([m[name] for m in found], np.float64).reshape(lead)
            data[name] = (dims, values, attrs)
        data["uncertain_fraction"] = (
            (*dims, "epsilon"), np.array([m["uncertain_fraction"] for m in found]).reshape(
                *lead, len(measures.EPSILONS)),
            {"units": "1", "long_name": "fraction f of the random initial conditions whose "
                                        "label changes when moved by +-epsilon",
             "n_points": np.int64(measures.UNCERTAIN_POINTS), "seed": np.int64(measures.SEED)})
        wada = np.full((len(found), seen), np.nan)
        for row, m in zip(wada, found):
            row[:len(m["wada"])] = m["wada"]
        data["wada"] = ((*dims, "basins_seen"), wada.reshape(*lead, seen), {
            "units": "1", "long_name": "Wada grid method: W_m, the share of boundary cells "
                                      "whose refined neighbourhood meets m basins",
            "thinned_to_at_most": np.int64(measures.WADA_CELLS),
            "refinements": np.int64(measures.WADA_REFINEMENTS),
            "reference": "Daza, Wagemakers, Sanjuan & Yorke, Sci. Rep. 5, 16579 (2015)"})
        return xr.Dataset(data, coords={
            "epsilon": ("epsilon", measures.EPSILONS, {
                "units": "1", "long_name": "perturbation as a fraction of the window's sides"}),
            "basins_seen": ("basins_seen", np.arange(1, seen + 1, dtype=np.int16), {
                "units": "1", "long_name": "number m of basins a boundary cell meets"})})


def search_window(cfg) -> tuple[tuple[float, float], tuple[float, float]]:
    """Where the attractors' search spreads its seeds: ``pendulum.drive.search_window``, else
    the grid's window ((θ lo, hi) [rad], (θ̇ lo, hi) [rad s⁻¹])."""
    given, g = cfg.pendulum.drive.search_window, cfg.grid
    if given is not None:
        return (tuple(given.theta0), tuple(given.theta_dot0))
    return ((g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop))


#: The scalar fractal measures stored per point (:mod:`atlas.models.driven.measures`).
MEASURES = {
    "basin_entropy": {"units": "1", "long_name": "basin entropy S_b (natural log)",
                      "box": "5 x 5 grid points",
                      "reference": "Daza et al., Sci. Rep. 6, 31416 (2016)"},
    "boundary_basin_entropy": {"units": "1", "long_name": "boundary basin entropy S_bb "
                               "(natural log)", "box": "5 x 5 grid points"},
    "fractal_boundary": {"units": "1", "long_name": "1 where S_bb > ln 2, a sufficient "
                         "(not necessary) condition of a fractal boundary; never with two "
                         "basins"},
    "uncertainty_exponent": {"units": "1", "long_name": "uncertainty exponent alpha: "
                             "f(epsilon) ~ epsilon^alpha, least-squares fit in log-log",
                             "reference": "Grebogi, McDonald, Ott & Yorke, Phys. Lett. A "
                                          "99, 415 (1983)"},
    "uncertainty_exponent_error": {"units": "1", "long_name": "standard error of the "
                                   "uncertainty exponent's fit (not its whole uncertainty)"},
    "boundary_dimension": {"units": "1", "long_name": "box-counting dimension of the basin "
                           "boundary, 2 - alpha"},
    "wada_merge_distance_max": {"units": "1", "long_name": "merging method: largest "
                                "Hausdorff distance between a basin's boundary and the "
                                "others' [cells of the thinned map]",
                                "reference": "Daza, Wagemakers & Sanjuan, Sci. Rep. 8, 9954 "
                                             "(2018)"},
    "wada_merge_distance_min": {"units": "1", "long_name": "merging method: smallest such "
                                "Hausdorff distance [cells of the thinned map]"},
}


def begin(cfg, layout: Layout) -> list[Drive]:
    """Every point's drive (nothing to refuse here: the config's checks hold)."""
    return drives(cfg, layout)


def _targets(points: list[np.ndarray], kinds: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """(targets (K, 2), the index of each one's attractor (int16 K)): every point on P of a
    periodic attractor, the last :data:`CLOUD_POINTS` of a chaotic one's cloud."""
    clouds = [p if kind == "periodic" else p[-CLOUD_POINTS:] for p, kind in zip(points, kinds)]
    targets = np.concatenate(clouds) if clouds else np.zeros((0, 2))
    owner = np.concatenate([np.full(len(c), i, np.int16) for i, c in enumerate(clouds)]) \
        if clouds else np.zeros(0, np.int16)
    return np.ascontiguousarray(targets), owner


def stored_point(group: xr.Dataset, params: dict[str, float], t_max: float) -> DrivenPoint:
    """The :class:`DrivenPoint` a run labelled a parameter point's grid with, rebuilt from
    what its file stores: the point's ``/attractors`` node (``group``, as
    :func:`attractors_dataset` wrote it: each attractor's points on P, kind, status and
    capture radius, and N), its parameters ``params`` (α, ω0, τ, A, Ω, φ; the file's) and
    the file's ``t_max`` [s]; no grid (nothing is checked at dt/2). Its
    :meth:`DrivenPoint.label` gives the run's labels (tests/commands/test_orbit_driven.py,
    tests/views/test_page_driven.py)."""
    drive = Drive(float(params["alpha"]), float(params["omega0"]),
                  float(params.get("torque", 0.0)), float(params["amplitude"]),
                  float(params["frequency"]), float(params.get("phase", 0.0)),
                  int(group.attrs["steps_per_period"]))
    n = group.sizes.get("attractor", 0)
    points, kinds = [], []
    for i in range(n):
        theta = np.asarray(group["theta"].values[i], np.float64)
        theta_dot = np.asarray(group["theta_dot"].values[i], np.float64)
        keep = np.isfinite(theta) & np.isfinite(theta_dot)
        points.append(np.column_stack([theta[keep], theta_dot[keep]]))
        kinds.append(str(group["kind"].values[i]))
    targets, owner = _targets(points, kinds)
    radii = np.asarray(group["capture_radius"].values, np.float64) if n else np.zeros(0)
    statuses = np.asarray(group["status"].values, np.int8) if n else np.zeros(0, np.int8)
    return DrivenPoint(drive, targets, owner, statuses,
                       radii[owner] if len(owner) else np.zeros(0), stored_confirm(group),
                       max(1, int(t_max / drive.period)))


def prepared(drive: Drive, window, max_period: int, t_max: float, grid=None
             ) -> tuple[DrivenPoint, list[Attractor], np.ndarray, np.ndarray]:
    """One parameter point prepared from its drive alone: (the :class:`DrivenPoint` that
    labels orbits there, its attractors found in ``window`` with periods up to
    ``max_period``, the status their labels get, their capture radii); orbits run at most
    ``t_max`` [s]; ``grid`` as :class:`DrivenPoint`'s. What a grid run prepares per point
    (:func:`plan`) and a driven study (:mod:`atlas.stability.driven`) too."""
    # a chaotic attractor is its last CLOUD_POINTS points from here on: its targets, the
    # spacing its capture radius is measured on, and what the file stores
    found = [a if a.kind == "periodic" else replace(a, points=a.points[-CLOUD_POINTS:])
             for a in find_attractors(drive, window, max_period=max_period)]
    largest = capture_radius(found)
    captures = [capture(drive, a, largest,
                        np.concatenate([b.points for b in found if b is not a] or
                                       [np.zeros((0, 2))]))
                for a in found]
    statuses = np.array([CHAOTIC if a.kind == "chaotic" else CONVERGED if contracting
                         else NEAR for a, (_, contracting) in zip(found, captures)], np.int8)
    radii = np.array([radius for radius, _ in captures])
    targets, owner = _targets([a.points for a in found], [a.kind for a in found])
    point = DrivenPoint(drive, targets, owner, statuses,
                        radii[owner] if len(owner) else np.zeros(0), confirm_returns(statuses),
                        max(1, int(t_max / drive.period)), grid=grid)
    return point, found, statuses, radii


def _prepared(cfg, layout: Layout, drive: Drive
              ) -> tuple[DrivenPoint, xr.Dataset, str | None]:
    window = search_window(cfg)
    point, found, statuses, radii = prepared(drive, window, cfg.pendulum.drive.max_period,
                                             cfg.integrator.t_max, (layout.x0, layout.v0))
    warning = None if found else "no attractor found in the window"
    longer = [f"#{i}" for i, a in enumerate(found)
              if a.kind == "chaotic" and beyond_bound(a.points)]
    if longer:
        warning = (f"attractor {', '.join(longer)}: its returns repeat with a period longer "
                   f"than pendulum.drive.max_period = {cfg.pendulum.drive.max_period} and "
                   "it is kept as a recurrent (chaotic) one: raise max_period to find it "
                   "periodic")
    # the file stores each attractor's targets (a chaotic cloud's last CLOUD_POINTS points)
    ds = attractors_dataset(drive, found, statuses, radii, cfg.pendulum.drive.max_period)
    ds.attrs["search_window"] = np.array(window, np.float64).ravel()
    ds.attrs["search_window_comment"] = ("theta0 lo, hi [rad], theta_dot0 lo, hi [rad s-1]: "
                                         "where the attractors' search spread its seeds")
    return point, ds, warning


def plan(cfg, layout: Layout, begun: list[Drive], track=None) -> DrivenPlan:
    """Every point prepared: its attractors found (the slow part), their targets and radius."""
    items = begun if track is None else track(begun, len(begun), "attractors")
    points, datasets, warnings = [], [], []
    for p, drive in enumerate(items):
        point, ds, warning = _prepared(cfg, layout, drive)
        points.append(point)
        datasets.append(ds)
        if warning:
            warnings.append(f"{point_label(layout.point(p))}: {warning}")
    return DrivenPlan(layout, points, per_point(layout, "attractors", datasets), warnings)
