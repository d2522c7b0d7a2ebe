"""The attractors of the driven pendulum's stroboscopic map P, found, not assumed.

P advances a state (θ, θ̇) at a whole number of drive periods by one period T = 2π/Ω of RK4
with dt = T/N (:mod:`atlas.kernels.driven`). Seeds spread over the window are iterated
through a transient, then their returns are recorded:

- a seed whose returns repeat with period p ≤ ``max_period`` (up to whole turns in θ) lies on
  a periodic orbit: P^p(x) = x + (2πw, 0), w its **winding** (net turns over p periods:
  rotations are attractors too). Its point is refined by Newton's method on
  G(x) = P^p(x) − x − (2πw, 0) to |G| ≤ ``newton_tol`` (the Jacobian DP^p by central
  differences of P^p), and its **Floquet multipliers** are the eigenvalues of DP^p there: the
  orbit is an attractor where both have modulus below 1. Mirror twins (the same p and w,
  another orbit) are different attractors: orbits are told apart by their points, never by
  (p, w).
- a seed whose returns do not repeat by then, and stay away from every periodic attractor,
  is on a **chaotic** (recurrent, non-periodic) attractor, recorded as the cloud of its
  returns on P (θ wrapped to [−π, π)); clouds that come within the recording's own spacing
  of each other are one attractor. A chaotic attractor is never merged into a periodic one.

Each periodic attractor gets a capture radius and a contraction test: states sampled on the
circle of that radius around each of its points are mapped by P^p, and the orbit's labels
claim convergence (status ``converged``) only where every image came closer to the orbit
point than the sample started; else its labels say only ``near``
(:mod:`atlas.models.driven.description`). This is a sampled test of the RK4 map, not a
proof, and the statuses say so.

The approach follows Attractors.jl's mapping of attractors of a stroboscopic map by
recurrence (Datseris & Wagemakers, *Chaos* 32, 023104, 2022), with periodic orbits refined
and classified as in Parker & Chua, *Practical Numerical Algorithms for Chaotic Systems*
(Springer 1989), ch. 4 (Floquet multipliers of a periodic orbit of a stroboscopic map).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from atlas.kernels import driven as kernels
from atlas.models.driven.description import MAX_PERIOD

__all__ = ["Drive", "Attractor", "find_attractors", "capture_radius", "capture", "contracts",
           "MAX_RETURNS", "HALVINGS", "CLOUD_MAX", "beyond_bound",
           "wrap", "SEEDS", "TRANSIENT", "RECORD", "MAX_PERIOD"]

TWO_PI = 2.0 * math.pi
#: Seeds per axis of the window (a SEEDS × SEEDS grid, plus its cell centres).
SEEDS = 12
#: Periods a seed is iterated before its returns are recorded.
TRANSIENT = 400
#: Returns recorded per seed (periodicity is read from the last ones; a chaotic cloud is
#: all of them).
RECORD = 240
#: Two returns p periods apart are "the same" (up to whole turns) within this distance,
#: before Newton's refinement.
REPEAT_TOL = 1e-6


def wrap(theta):
    """θ [rad] wrapped to [−π, π)."""
    return (np.asarray(theta) + math.pi) % TWO_PI - math.pi


@dataclass(frozen=True)
class Drive:
    """One parameter point of the driven pendulum and its discretisation: α [s⁻¹], ω0
    [rad s⁻¹], τ [rad s⁻²], A [rad s⁻²], Ω [rad s⁻¹], φ [rad]; N steps per period."""

    alpha: float
    omega0: float
    torque: float
    amplitude: float
    frequency: float
    phase: float
    steps_per_period: int

    @property
    def period(self) -> float:
        """T = 2π/Ω [s]."""
        return TWO_PI / self.frequency

    @property
    def dt(self) -> float:
        """The RK4 step T/N [s]."""
        return self.period / self.steps_per_period

    @cached_property
    def table(self) -> np.ndarray:
        """The drive at the half-steps of one period (:func:`atlas.kernels.driven.
        forcing_table`), computed once per drive."""
        return kernels.forcing_table(self.amplitude, self.frequency, self.phase,
                                     self.steps_per_period)

    def advance(self, theta: np.ndarray, theta_dot: np.ndarray, periods: int) -> None:
        """P^periods applied in place to the states (θ unwrapped)."""
        kernels.advance(theta, theta_dot, self.alpha, self.omega0, self.torque, self.table,
                        self.dt, periods)

    def map(self, states: np.ndarray, periods: int) -> np.ndarray:
        """P^periods of states (n, 2): a new array."""
        theta, theta_dot = (np.array(states[:, i], np.float64) for i in (0, 1))  # copies
        self.advance(theta, theta_dot, periods)
        return np.stack([theta, theta_dot], axis=1)


@dataclass
class Attractor:
    """One attractor of P: ``kind`` "periodic" or "chaotic"; ``points`` (n, 2) on P (θ
    wrapped; a periodic orbit's p points in their order along the orbit, a chaotic one's
    recorded cloud); ``period`` p and ``winding`` w (periodic; 0 and 0 for chaotic);
    ``multipliers`` the Floquet multipliers (periodic; NaN for chaotic); ``residual``
    |P^p(x) − x − (2πw, 0)| after Newton's refinement [rad and rad s⁻¹ as one unit]."""

    kind: str
    points: np.ndarray
    period: int = 0
    winding: int = 0
    multipliers: np.ndarray = field(default_factory=lambda: np.full(2, np.nan + 0j))
    residual: float = math.nan

    @property
    def stable(self) -> bool:
        return self.kind == "chaotic" or bool(np.all(np.abs(self.multipliers) < 1.0))


def _period_of(returns: np.ndarray, max_period: int) -> tuple[int, int] | None:
    """(p, w) of the smallest period p ≤ max_period with which the last returns (θ
    unwrapped, θ̇) repeat up to whole turns, within REPEAT_TOL; None where none does."""
    last = returns[-1]
    for p in range(1, max_period + 1):
        earlier = returns[-1 - p]
        turns = (last[0] - earlier[0]) / TWO_PI
        w = int(round(turns))
        if abs(last[0] - earlier[0] - TWO_PI * w) < REPEAT_TOL and \
                abs(last[1] - earlier[1]) < REPEAT_TOL:
            return p, w
    return None


def _refine(drive: Drive, x: np.ndarray, p: int, w: int, tol: float, steps: int = 12
            ) -> tuple[np.ndarray, np.ndarray, float]:
    """Newton on G(x) = P^p(x) − x − (2πw, 0): (x, DP^p(x), |G(x)|). DP^p by central
    differences (step 1e-6 relative to the state's scale)."""
    shift = np.array([TWO_PI * w, 0.0])
    jac = np.eye(2)
    residual = math.inf
    for _ in range(steps):
        h = 1e-6 * max(1.0, float(np.abs(x).max()))
        probes = np.array([x, x + [h, 0], x - [h, 0], x + [0, h], x - [0, h]])
        images = drive.map(probes, p)
        g = images[0] - x - shift
        jac = np.column_stack([(images[1] - images[2]) / (2 * h),
                               (images[3] - images[4]) / (2 * h)])
        residual = float(np.hypot(*g))
        if residual <= tol:
            break
        x = x - np.linalg.solve(jac - np.eye(2), g)
    return x, jac, residual


def _orbit(drive: Drive, x: np.ndarray, p: int) -> np.ndarray:
    """The p points of the periodic orbit through x on P, θ wrapped."""
    points = [x]
    for _ in range(p - 1):
        points.append(drive.map(points[-1][None, :], 1)[0])
    out = np.array(points)
    out[:, 0] = wrap(out[:, 0])
    return out


def _distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances between the states a (n, 2) and b (m, 2), θ differences wrapped: (n, m)."""
    d_theta = wrap(a[:, None, 0] - b[None, :, 0])
    return np.hypot(d_theta, a[:, None, 1] - b[None, :, 1])


def _seeds(window: tuple[tuple[float, float], tuple[float, float]], n: int) -> np.ndarray:
    """A deterministic spread of seeds: an n × n grid of the window and its cell centres."""
    (t0, t1), (v0, v1) = window
    grids = []
    for offset in (0.0, 0.5):
        th = t0 + (np.arange(n) + offset) * (t1 - t0) / (n - (1 - offset))
        v = v0 + (np.arange(n) + offset) * (v1 - v0) / (n - (1 - offset))
        tt, vv = np.meshgrid(th, v)
        grids.append(np.column_stack([tt.ravel(), vv.ravel()]))
    return np.concatenate(grids)


def find_attractors(drive: Drive, window, *, seeds: int = SEEDS, transient: int = TRANSIENT,
                    record: int = RECORD, max_period: int = MAX_PERIOD,
                    newton_tol: float = 1e-12) -> list[Attractor]:
    """The attractors of P that seeds in ``window`` ((θ lo, hi) [rad], (θ̇ lo, hi) [rad s⁻¹])
    reach: stable periodic orbits of period ≤ ``max_period`` (refined to ``newton_tol``) and
    chaotic attractors, in a deterministic order (periodic first, by period, winding and
    first point; then chaotic)."""
    start = _seeds(window, seeds)
    returns = kernels.sample(np.ascontiguousarray(start[:, 0]),
                             np.ascontiguousarray(start[:, 1]), drive.alpha, drive.omega0,
                             drive.torque, drive.table, drive.dt, transient, record)
    periodic: list[Attractor] = []
    clouds: list[np.ndarray] = []
    for seed in returns:
        if not np.all(np.isfinite(seed)):
            continue
        found = _period_of(seed, max_period)
        if found is None:
            cloud = seed.copy()
            cloud[:, 0] = wrap(cloud[:, 0])
            clouds.append(_distinct(cloud))
            continue
        p, w = found
        start = seed[-1].copy()
        start[0] = wrap(start[0])  # a rotation's θ has grown by many turns: ulp(θ) matters
        x, jac, residual = _refine(drive, start, p, w, newton_tol)
        if residual > 1e3 * newton_tol:  # Newton did not converge: leave it to other seeds
            continue
        orbit = _orbit(drive, x, p)
        if any(a.period == p and _distance(orbit[:1], a.points).min() < 1e-7
               for a in periodic):
            continue
        multipliers = np.linalg.eigvals(jac)
        attractor = Attractor("periodic", orbit, p, w, multipliers, residual)
        if attractor.stable:
            periodic.append(attractor)
    periodic.sort(key=lambda a: (a.period, a.winding, tuple(np.round(a.points[0], 9))))
    return periodic + _chaotic(clouds, periodic)


def _chaotic(clouds: list[np.ndarray], periodic: list[Attractor]) -> list[Attractor]:
    """The chaotic attractors among the recorded clouds of seeds with no period: clouds that
    meet (within the larger of their own spacings) are one; a cloud that comes within its
    spacing of a periodic attractor is a slow transient to it, not an attractor."""
    merged: list[np.ndarray] = []
    for cloud in clouds:
        spacing = _reach(cloud)
        if any(_distance(cloud, a.points).min() < spacing for a in periodic):
            continue
        for i, other in enumerate(merged):
            if _distance(cloud, other).min() < max(spacing, _reach(other)):
                merged[i] = _thinned(_distinct(np.concatenate([other, cloud])))
                break
        else:
            merged.append(cloud)
    return [Attractor("chaotic", cloud) for cloud in merged]


def beyond_bound(cloud: np.ndarray) -> bool:
    """Whether a cloud of returns (its distinct points) is a periodic orbit longer than the
    period bound rather than a chaotic attractor: it has at most RECORD/4 distinct points."""
    return len(cloud) <= RECORD // 4


def _reach(cloud: np.ndarray) -> float:
    """How near another cloud or orbit must come to be the same attractor: the cloud's
    spacing, or for a periodic orbit beyond the bound (whose few points lie far apart)
    100 REPEAT_TOL."""
    return 100 * REPEAT_TOL if beyond_bound(cloud) else _spacing(cloud)


#: The most points a chaotic attractor's cloud keeps (evenly thinned beyond).
CLOUD_MAX = 4000


def _distinct(cloud: np.ndarray) -> np.ndarray:
    """The cloud's points, each kept once where several agree to REPEAT_TOL (in the order
    first met): the returns of a periodic orbit longer than the period bound are its few
    points, not a cloud of hundreds of copies."""
    _, first = np.unique(np.round(cloud / REPEAT_TOL), axis=0, return_index=True)
    return cloud[np.sort(first)]


def _thinned(cloud: np.ndarray) -> np.ndarray:
    """At most CLOUD_MAX of the cloud's points, evenly spaced in the order recorded."""
    if len(cloud) <= CLOUD_MAX:
        return cloud
    return cloud[np.linspace(0, len(cloud) - 1, CLOUD_MAX).astype(np.int64)]


def _spacing(cloud: np.ndarray) -> float:
    """The typical distance between a cloud's points and their nearest neighbour (median),
    θ differences wrapped: by a k-d tree of the points and their copies one turn either
    side (the same distances as all pairs', in O(n log n) rather than O(n²): a merged cloud
    of CLOUD_MAX points took 0.3 s a call, 29 s of one search)."""
    from scipy.spatial import cKDTree

    cloud = np.asarray(cloud, np.float64)
    if len(cloud) < 2:
        return math.inf
    turn = np.array([TWO_PI, 0.0])
    tree = cKDTree(np.concatenate([cloud, cloud + turn, cloud - turn]))
    nearest, _ = tree.query(cloud, k=2)  # the first is the point itself
    return float(np.median(nearest[:, 1]))


def capture_radius(attractors: list[Attractor]) -> float:
    """The largest capture radius a periodic attractor may have [rad and rad s⁻¹ as one
    unit]: a quarter of the least distance between points of different periodic orbits or
    between points of one orbit, and at most 0.1 (a smaller radius only takes more periods
    to decide), so that no two captures overlap."""
    least = 0.4
    points = [a.points for a in attractors if a.kind == "periodic"]
    for i, a in enumerate(points):
        if len(a) > 1:
            d = _distance(a, a)
            np.fill_diagonal(d, np.inf)
            least = min(least, float(d.min()))
        for b in points[i + 1:]:
            least = min(least, float(_distance(a, b).min()))
    return 0.25 * least


#: Halvings of the capture radius tried before an attractor's ball is given up.
HALVINGS = 8


def capture(drive: Drive, attractor: Attractor, largest: float,
            others: np.ndarray | None = None) -> tuple[float, bool]:
    """(radius, contracting) of one attractor: for a periodic one the largest of
    ``largest`` · 2^−j (j ≤ :data:`HALVINGS`) whose ball was seen to map into itself
    (:func:`contracts`; True), else ``largest`` (False); for a chaotic one twice its cloud's
    spacing (False: a cloud is no contraction), so that a return inside the cloud is seen,
    and at most a quarter of its distance to the points ``others`` (n, 2) of the other
    attractors, so that no two captures overlap."""
    if attractor.kind == "chaotic":
        # a periodic orbit beyond the bound: a quarter of its points' spacing, as a
        # periodic attractor's; a cloud: twice its spacing
        radius = (0.25 if beyond_bound(attractor.points) else 2.0) * _spacing(
            attractor.points)
        if others is not None and len(others):
            radius = min(radius, 0.25 * float(_distance(attractor.points, others).min()))
        return radius, False
    for j in range(HALVINGS + 1):
        if contracts(drive, attractor, largest * 0.5 ** j):
            return largest * 0.5 ** j, True
    return largest, False


#: The most returns m of P^p over which the capture ball must map into itself.
MAX_RETURNS = 8


def contracts(drive: Drive, attractor: Attractor, radius: float, samples: int = 32) -> bool:
    """Whether, for some m ≤ :data:`MAX_RETURNS`, P^(p·m) mapped every sampled state on the
    circle of ``radius`` around each point of the periodic ``attractor`` strictly inside
    that circle (a sampled test, for the RK4 map, that the capture ball maps into itself:
    with eigenvalues of modulus below 1 but a non-normal DP^p, one return may first stretch
    a ball before later ones shrink it)."""
    if attractor.kind != "periodic":
        return False
    angles = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    ring = radius * np.column_stack([np.cos(angles), np.sin(angles)])
    for x in attractor.points:
        states = x + ring
        for _ in range(MAX_RETURNS):
            states = drive.map(states, attractor.period)
            if np.all(_distance(states, x[None, :])[:, 0] < radius):
                break
        else:
            return False
    return True
