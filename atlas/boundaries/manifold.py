"""The exact basin boundaries without torque: the stable manifolds of the saddles, by DOP853.

Every basin boundary of eq. (1) (τ = 0) is the stable manifold of a saddle ((2j+1)π, 0), and
by θ → θ + 2π and (θ, θ̇) → (−θ, −θ̇) each is a copy of one curve, the left branch L of
(π, 0): a graph θ̇ = L(u), u ≤ π, so the boundary through nπ is S_n(θ) = L(θ − (n − 1)π) left
of the saddle, −L((n + 1)π − θ) right of it, and the basin of the rest state (2πk, 0) is the
strip S_{2k−1} < θ̇ < S_{2k+1}. :class:`StableManifold` integrates L once (DOP853, rtol =
atol = 1e-13, dense output: :mod:`atlas.kernels.dop853`; from 1e-7 along the stable
eigenvector, essay eqs. 22, 24) with Q(τ) = ∫ θ̇ dθ; from it come foot points and distances
(:class:`BoundaryIndex`, ≈ 1e-13), sides, and the exact area of each basin in a window
(:func:`basin_areas`, piecewise from Q; error: the change from rtol 1e-12 to 1e-13).
References: Krauskopf et al., Int. J. Bifurcation Chaos 15 (2005) 763; Hairer, Nørsett &
Wanner, *Solving ODEs I*, §II.5–6. Derivation: docs/design/stable-manifolds.md.
"""

from __future__ import annotations

import bisect
import copy
import math
from dataclasses import dataclass

import numpy as np

from atlas.physics.pendulum import START_DISTANCE, Pendulum

__all__ = ["StableManifold", "BoundaryIndex", "to_left_branch", "basin_areas", "BasinAreas",
           "RTOL", "START_DISTANCE", "DenseOutput"]

#: Relative and absolute tolerance of the DOP853 reference.
RTOL = 1e-13
#: The tolerance whose result is compared with :data:`RTOL`'s for the error estimate.
RTOL_CHECK = 1e-12
#: Arc-length spacing of the samples used to seed foot-point searches [rad-ish].
SAMPLE_SPACING = 0.02
_NEWTON = 6  # iterations for foot points and inverse functions (quadratic convergence)
#: Side of the cells that bin boundary samples for the nearest-sample search [rad-ish], and
#: the most cells an index may have.
_CELL, _MAX_CELLS = 0.3, 1 << 20
#: Steps a DOP853 piece is first given room for (about 130 at rtol 1e-13 on the default
#: window; more are made room for as needed).
_STEPS = 1024
#: Smallest speed [rad s⁻¹] a StableManifold is integrated to (well above its start's).
_MIN_SPEED = 1e-3
#: Gauss–Legendre nodes per part of a small window's boundary integral.
_GAUSS_NODES = 20
#: Windows whose shorter side is below this [rad-ish] get their areas at the window's scale
#: (:meth:`StableManifold.boundary_fraction`); wider ones as differences of Q, whose rounding
#: is negligible there.
SMALL_WINDOW = 0.5
#: Most boundaries a window's area walk visits before it gives up (a bug, never a window).
_MAX_WALK = 100_000


class DenseOutput:
    """DOP853's dense output (Hairer, Nørsett & Wanner, §II.6) of a whole solution, evaluated
    for many times at once: the polynomial of every step, its coefficients stacked over the
    steps (evaluated by a compiled loop: a call costs microseconds). ``t``: the step ends
    (steps + 1); per step ``t_old``, ``h``, ``y_old`` (steps, 3) and ``F`` (steps, 7, 3),
    lowest power first (as :func:`atlas.kernels.dop853.stable_manifold` and scipy's
    ``Dop853DenseOutput`` hold it)."""

    def __init__(self, t, t_old, h, y_old, F):
        if np.size(h) == 0:
            raise ValueError("a dense output needs at least one step")
        self.t, self.t_old, self.h, self.y_old = t, t_old, h, y_old
        self.F = np.ascontiguousarray(F[:, ::-1])  # highest power first
        self._lists = None  # the same as Python lists, for point()

    @classmethod
    def from_scipy(cls, solutions) -> DenseOutput:
        """The dense output of scipy ``OdeSolution`` pieces (DOP853), each starting where the
        one before ends."""
        parts = [q for solution in solutions for q in solution.interpolants]
        return cls(np.concatenate([solutions[0].ts] + [s.ts[1:] for s in solutions[1:]]),
                   np.array([q.t_old for q in parts]), np.array([q.h for q in parts]),
                   np.array([q.y_old for q in parts]), np.array([q.F for q in parts]))

    @classmethod
    def from_pieces(cls, pieces) -> DenseOutput:
        """The dense output of :class:`atlas.kernels.dop853.Solution` s, each starting where
        the one before ends."""
        return cls(np.concatenate([pieces[0].t] + [q.t[1:] for q in pieces[1:]]),
                   *(np.concatenate([getattr(q, name) for q in pieces])
                     for name in ("t_old", "h", "y_old", "F")))

    def point(self, tau: float) -> list[float]:
        """The solution at one time τ, as floats: the same polynomial evaluated without
        array overhead, for callers that step along the curve one point at a time."""
        if self._lists is None:
            self._lists = (self.t.tolist(), self.t_old.tolist(), self.h.tolist(),
                           self.y_old.tolist(), self.F.tolist())
        t, t_old, h, y_old, F = self._lists
        step = min(max(bisect.bisect_right(t, tau) - 1, 0), len(h) - 1)
        x = (tau - t_old[step]) / h[step]
        y = [0.0] * len(y_old[step])
        for i, row in enumerate(F[step]):
            w = x if i % 2 == 0 else 1.0 - x
            y = [(a + c) * w for a, c in zip(y, row)]
        return [a + b for a, b in zip(y, y_old[step])]

    def __call__(self, tau):
        """The solution at the times ``tau`` (any shape): components × tau's shape
        (compiled: :func:`atlas.kernels.dop853.dense_output`)."""
        from atlas.kernels.dop853 import dense_output

        tau = np.asarray(tau, float)
        flat = np.ascontiguousarray(tau.ravel())
        out = np.empty((self.y_old.shape[1], flat.size))
        dense_output(flat, self.t, self.t_old, self.h, self.y_old, self.F, out)
        return out.reshape(self.y_old.shape[1], *tau.shape)


def to_left_branch(n, right, theta, theta_dot):
    """Points of the boundary branch through the saddle (nπ, 0) (``right`` true: its right
    branch, else its left one) mapped into the frame of L: the inverse of the shift by
    (n − 1)π of the left branch, or of the point reflection θ → (n + 1)π − θ, θ̇ → −θ̇ of the
    right one. Both maps are isometries, so distances to L are distances to the branch."""
    n, right = np.asarray(n), np.asarray(right, bool)
    theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
    return (np.where(right, (n + 1) * math.pi - theta, theta - (n - 1) * math.pi),
            np.where(right, -theta_dot, theta_dot))


class StableManifold:
    """The left branch L of the saddle (π, 0) of ``pendulum``, integrated until θ̇ > ``speed``
    [rad s⁻¹]; beyond that point L(u) > speed for ever (its energy exceeds ½speed² + 2ω0² and
    only grows). Requires α > 0. :meth:`extended` continues it further.
    """

    def __init__(self, pendulum: Pendulum, speed: float, rtol: float = RTOL):
        p = self.pendulum = pendulum
        if not p.alpha > 0:
            raise ValueError("the stable manifolds bound basins only for alpha > 0")
        if p.torque != 0.0:
            raise ValueError("StableManifold is the untilted pendulum's; with torque see "
                             "atlas.boundaries.tilted")
        # at least _MIN_SPEED: the integration starts at θ̇ ≈ u2 · START_DISTANCE, and ends
        # on crossing ``speed`` upwards (a window around the saddle asks for less)
        self.speed, self.rtol = max(float(speed), _MIN_SPEED), rtol
        self.u2 = -p.saddle_eigenvalues()[1]
        e_theta, e_theta_dot = p.saddle_stable_direction()
        self.start = (math.pi - START_DISTANCE * e_theta, -START_DISTANCE * e_theta_dot)
        # ∫ θ̇ dθ along the straight piece from the start point to the saddle
        q0 = 0.5 * self.start[1] * START_DISTANCE * e_theta
        self._pieces = [self._integrate(0.0, [*self.start, q0], math.pi)]
        self._finish()

    def _integrate(self, tau0: float, y0, theta_min: float):
        """DOP853 from state ``y0`` = (θ, θ̇, Q) at τ0 until θ̇ > ``speed`` and θ < theta_min
        (compiled: :func:`atlas.kernels.dop853.stable_manifold`, through
        :func:`atlas.kernels.dop853.solve`): a :class:`atlas.kernels.dop853.Solution`."""
        from atlas.kernels.dop853 import ENERGY, EVENT, REVERSED, solve

        p = self.pendulum
        e_stop = 0.5 * self.speed**2 + p.saddle_energy
        t_cap = tau0 + 1e4 * (1.0 / p.alpha + 1.0 / p.omega0)
        piece = solve(REVERSED, [float(p.alpha), float(p.omega0), 0.0, 0.0], ENERGY,
                      [e_stop, float(theta_min)], np.asarray(y0, float), t_cap, self.rtol,
                      [self.rtol] * 3, 3, t0=float(tau0), capacity=_STEPS)
        if piece.status != EVENT:
            why = "step too small" if piece.status < 0 else "ran out of time"
            raise RuntimeError(f"the stable manifold did not reach speed {self.speed:g} "
                               f"(DOP853 {why})")
        return piece

    def _finish(self) -> None:
        """Dense output, end point and samples of the integrated pieces."""
        first, rest = self._pieces[0], self._pieces[1:]
        self._sol = DenseOutput.from_pieces(self._pieces)
        t = self._sol.t  # the step ends of every piece
        y = np.concatenate([first.y.T] + [piece.y[1:].T for piece in rest], axis=1)
        self.tau_end = float(t[-1])
        self.theta_end = float(y[0, -1])  # L(u) > speed for u < theta_end
        # samples at arc length ≤ SAMPLE_SPACING, from the saddle outward
        steps = np.hypot(np.diff(y[0]), np.diff(y[1]))
        pieces = np.maximum(1, np.ceil(steps / SAMPLE_SPACING)).astype(int)
        tau = np.concatenate([np.linspace(a, b, m, endpoint=False)
                              for a, b, m in zip(t[:-1], t[1:], pieces)] + [t[-1:]])
        self.tau = tau
        self.theta, self.theta_dot, _ = self._sol(tau)
        self._crossings: dict[float, np.ndarray] = {}  # _tau_at_speed's results by level

    def extended(self, theta_min: float) -> StableManifold:
        """L integrated on until θ < ``theta_min`` [rad] as well (``self`` if it already
        reaches that far); unchanged for τ ≤ ``tau_end``: its steps are kept, the
        integration continues from its end."""
        if self.theta_end < theta_min:
            return self
        longer = copy.copy(self)
        last = self._pieces[-1]
        longer._pieces = self._pieces + [self._integrate(self.tau_end, last.y[-1],
                                                         theta_min)]
        longer._finish()
        return longer

    # ------------------------------------------------------------------ on the curve

    def _state(self, tau):
        """(θ, θ̇, Q) on L at reversed time τ ∈ [0, tau_end] [s]."""
        return self._sol(np.clip(tau, 0.0, self.tau_end))

    def at(self, tau):
        """(θ [rad], θ̇ [rad s⁻¹]) on L at reversed time τ [s] from its first point
        ``start``, clipped to [0, ``tau_end``] (DOP853's dense output); floats for a scalar τ."""
        if np.ndim(tau) == 0:
            theta, theta_dot, _ = self._sol.point(min(max(float(tau), 0.0), self.tau_end))
        else:
            theta, theta_dot, _ = self._state(tau)
        return theta, theta_dot

    def tau_at(self, u):
        """τ [s] where L passes θ = u [rad], for theta_end ≤ u ≤ θ(0) (θ decreases along L)."""
        u = np.asarray(u, float)
        tau = np.interp(-u, -self.theta, self.tau)
        for _ in range(_NEWTON):
            theta, theta_dot, _ = self._state(tau)
            tau = np.clip(tau + (theta - u) / theta_dot, 0.0, self.tau_end)  # dθ/dτ = −θ̇
        return tau

    def _tau_at_speed(self, level: float) -> np.ndarray:
        """Every τ where θ̇(τ) = ``level`` on L (θ̇ oscillates while it grows); remembered
        per level (the areas ask for the window's two θ̇ edges once per boundary copy)."""
        level = float(level)
        if level not in self._crossings:
            self._crossings[level] = self._bisect_speed(level)
        return self._crossings[level]

    def _bisect_speed(self, level: float) -> np.ndarray:
        diff = self.theta_dot - level
        i = np.flatnonzero(np.sign(diff[:-1]) * np.sign(diff[1:]) < 0)
        return self.speed_crossing(level, self.tau[i], self.tau[i + 1])

    def speed_crossing(self, level: float, a, b):
        """The τ [s] in each bracket [a, b] where θ̇ on L passes ``level`` [rad s⁻¹] (θ̇ − level
        changes sign between a and b), by bisection on the dense output: 60 halvings, to the
        last bits of τ, robust where θ̇ turns near the level."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        rising = self._state(a)[1] < level
        for _ in range(60):
            mid = 0.5 * (a + b)
            above = self._state(mid)[1] > level
            b = np.where(above == rising, mid, b)
            a = np.where(above == rising, a, mid)
        return 0.5 * (a + b)

    def left(self, u):
        """L(u) [rad s⁻¹] for u ≤ π [rad]; +inf beyond ``theta_end``, where L is faster than
        ``speed``."""
        u = np.atleast_1d(np.asarray(u, float))
        out = np.full(u.shape, np.inf)
        line = u >= self.start[0]  # the straight piece next to the saddle
        out[line] = self.u2 * (math.pi - u[line])
        mid = (u >= self.theta_end) & ~line
        out[mid] = self._state(self.tau_at(u[mid]))[1]
        return out

    def boundary(self, n: int, theta):
        """S_n(θ) [rad s⁻¹]: the basin boundary through the saddle (nπ, 0), n odd, at θ
        [rad] (±inf where it is faster than ``speed``)."""
        theta = np.asarray(theta, float)
        return np.where(theta <= n * math.pi, self.left(theta - (n - 1) * math.pi),
                        -self.left((n + 1) * math.pi - theta))

    # ------------------------------------------------------------------ areas

    def clipped_integral(self, u1: float, u2: float, lo: float, hi: float) -> float:
        """∫ clip(L(u), lo, hi) du over [u1, u2] ⊂ (−∞, π], lo ≤ hi ≤ ``speed`` [rad s⁻¹].

        Exact up to the dense output's accuracy: the interval is cut where L crosses lo or hi
        and at the ends of the integrated piece; on each part the integrand is a constant
        or L itself, whose integral is a difference of Q (∫ θ̇ dθ = ∫ θ̇² dτ along L)."""
        if not u1 < u2:
            return 0.0
        cuts = [u1, u2, self.start[0], self.theta_end]
        for level in (lo, hi):
            cuts += list(self._state(self._tau_at_speed(level))[0])
        cuts = np.unique(np.clip(cuts, u1, u2))
        total = 0.0
        for a, b in zip(cuts[:-1], cuts[1:]):
            value = float(self.left(0.5 * (a + b))[0])
            if not lo < value < hi:  # constant on this part: L does not cross lo or hi
                total += (lo if value <= lo else hi) * (b - a)
            elif a >= self.start[0]:  # straight piece: L = u2 (π − u)
                total += 0.5 * self.u2 * ((math.pi - a) ** 2 - (math.pi - b) ** 2)
            else:
                q_a, q_b = self._state(self.tau_at(np.array([a, b])))[2]
                total += q_a - q_b
        return total

    def clipped_excess(self, u1: float, u2: float, lo: float, hi: float):
        """(∫ (clip(L(u), lo, hi) − lo) du over [u1, u2], and where L lies there: +1 at or
        above hi throughout, −1 at or below lo throughout, 0 otherwise or for an empty
        interval), lo ≤ hi ≤ ``speed``: :meth:`clipped_integral` at the window's scale,
        for small windows. The same cuts; a constant part is exactly 0 or (hi − lo) × its
        length, and L itself is integrated by Gauss–Legendre quadrature
        (:data:`_GAUSS_NODES` nodes on a part, exact to rounding for the short parts of a
        small window) instead of as a difference of Q, whose rounding (≈ 1e-15 of Q) would
        swamp the area of a window narrower than about 1e-4."""
        if not u1 < u2:
            return 0.0, 0
        cuts = [u1, u2, self.start[0], self.theta_end]
        for level in (lo, hi):
            cuts += list(self._state(self._tau_at_speed(level))[0])
        cuts = np.unique(np.clip(cuts, u1, u2))
        x, w = np.polynomial.legendre.leggauss(_GAUSS_NODES)
        total, kinds = 0.0, set()
        for a, b in zip(cuts[:-1], cuts[1:]):
            value = float(self.left(0.5 * (a + b))[0])
            if value <= lo:
                kinds.add(-1)
            elif value >= hi:
                kinds.add(1)
                total += (hi - lo) * (b - a)
            else:
                kinds.add(0)
                nodes = 0.5 * (a + b) + 0.5 * (b - a) * x
                total += 0.5 * (b - a) * float(np.dot(w, np.clip(self.left(nodes), lo, hi)
                                                      - lo))
        return total, (kinds.pop() if len(kinds) == 1 else 0)

    def boundary_fraction(self, n: int, theta_window, theta_dot_window):
        """(the fraction of the window below S_n, ∫ (clip(S_n(θ), θ̇min, θ̇max) − θ̇min) dθ
        over the window's area; +1 if S_n lies at or above the window throughout, −1 at or
        below it, else 0): :meth:`boundary_integral` at the window's scale
        (:meth:`clipped_excess`)."""
        (a, b), (lo, hi) = theta_window, theta_dot_window
        saddle = n * math.pi
        shift_left, shift_right = (n - 1) * math.pi, (n + 1) * math.pi
        total, kinds = 0.0, set()
        if a < saddle:  # left branch: S_n(θ) = L(θ − (n−1)π)
            part, kind = self.clipped_excess(a - shift_left, min(b, saddle) - shift_left,
                                             lo, hi)
            total += part
            kinds.add(kind)
        if b > saddle:  # right branch: clip(−L(w), lo, hi) − lo = (hi − lo) − (clip(L(w),
            # −hi, −lo) + hi), and L above −lo is S_n below lo
            w1, w2 = shift_right - b, shift_right - max(a, saddle)
            part, kind = self.clipped_excess(w1, w2, -hi, -lo)
            total += (hi - lo) * (w2 - w1) - part
            kinds.add(-kind)
        area = (b - a) * (hi - lo)
        return total / area, (kinds.pop() if len(kinds) == 1 else 0)

    def boundary_integral(self, n: int, theta_window, theta_dot_window) -> float:
        """∫ clip(S_n(θ), θ̇min, θ̇max) dθ over the θ window [rad² s⁻¹]."""
        (a, b), (lo, hi) = theta_window, theta_dot_window
        saddle = n * math.pi
        shift_left, shift_right = (n - 1) * math.pi, (n + 1) * math.pi
        total = 0.0
        if a < saddle:  # left branch: S_n(θ) = L(θ − (n−1)π)
            total += self.clipped_integral(a - shift_left, min(b, saddle) - shift_left, lo, hi)
        if b > saddle:  # right branch: clip(−L(w), lo, hi) = −clip(L(w), −hi, −lo)
            total -= self.clipped_integral(shift_right - b, shift_right - max(a, saddle),
                                           -hi, -lo)
        return total

    # ------------------------------------------------------------------ distances

    def _copies(self, box):
        """Samples of every boundary copy inside ``box`` = ((θ0, θ1), (v0, v1)):
        (θ, θ̇, n, branch 0 left / 1 right, sample index)."""
        (t0, t1), (v0, v1) = box
        out = []
        for branch, sign in ((0, 1.0), (1, -1.0)):
            theta, speed = sign * self.theta, sign * self.theta_dot
            in_band = (speed >= v0) & (speed <= v1)
            if not in_band.any():
                continue
            lo, hi = theta[in_band].min(), theta[in_band].max()
            # left copy of saddle n: θ + (n − 1)π; right copy: −θ + (n + 1)π
            offset = -1 if branch == 0 else 1
            n_lo = math.floor((t0 - hi) / math.pi) - offset - 2
            n_hi = math.ceil((t1 - lo) / math.pi) - offset + 2
            for n in range(n_lo | 1, n_hi + 1, 2):
                shifted = theta + (n + offset) * math.pi
                keep = np.flatnonzero(in_band & (shifted >= t0) & (shifted <= t1))
                if keep.size:
                    out.append((shifted[keep], speed[keep], np.full(keep.size, n),
                                np.full(keep.size, branch), keep))
        if not out:
            return None
        return tuple(np.concatenate(parts) for parts in zip(*out))

    def _foot(self, x, v, i):
        """(τ, distance) of the foot points on L of points (x, v), in L's own frame, near
        sample ``i``: Newton's method on the dense output, kept within the neighbouring
        samples (the sample itself if nearer), and the straight piece to the saddle for the
        first samples (τ = 0 when the foot lies on it)."""
        lo = self.tau[np.maximum(i - 1, 0)]
        hi = self.tau[np.minimum(i + 1, self.tau.size - 1)]
        tau = self.tau[i].copy()
        for _ in range(_NEWTON):  # Newton on g(τ) = (c(τ) − q)·c'(τ) = 0
            theta, theta_dot, _ = self._state(tau)
            (f0, f1), (dd0, dd1) = self.pendulum.field_jet(theta, theta_dot)
            d0, d1 = -f0, -f1  # c' = −f (reversed flow), c'' = J·f
            g = (theta - x) * d0 + (theta_dot - v) * d1
            slope = d0 * d0 + d1 * d1 + (theta - x) * dd0 + (theta_dot - v) * dd1
            # near a centre of curvature g' ≤ 0: fall back to the Gauss–Newton step
            slope = np.where(slope > 0, slope, d0 * d0 + d1 * d1)
            tau = np.clip(tau - g / slope, lo, hi)
        theta, theta_dot, _ = self._state(tau)
        dist = np.hypot(theta - x, theta_dot - v)
        sample = np.hypot(self.theta[i] - x, self.theta_dot[i] - v)
        tau = np.where(sample < dist, self.tau[i], tau)
        dist = np.minimum(dist, sample)
        near = i <= 1  # the segment from the saddle (π, 0) to the first integrated point
        if near.any():
            ax, av = self.start[0] - math.pi, self.start[1]
            s = np.clip(((x[near] - math.pi) * ax + v[near] * av) / (ax * ax + av * av), 0, 1)
            seg = np.hypot(math.pi + s * ax - x[near], s * av - v[near])
            tau[near] = np.where(seg < dist[near], 0.0, tau[near])
            dist[near] = np.minimum(dist[near], seg)
        return tau, dist

    def foot_points(self, x, v):
        """(τ [s], distance [rad-ish]) of the foot points on L — the nearest points of L — of
        points (x [rad], v [rad s⁻¹]) given in L's own frame (:func:`to_left_branch`), exact to
        ≈ 1e-13 for points within about ``SAMPLE_SPACING`` of L: the nearest sample, then
        Newton's method on the dense output."""
        from atlas.kernels.foot import nearest_sample

        x, v = np.atleast_1d(np.asarray(x, float)), np.atleast_1d(np.asarray(v, float))
        if x.size == 0:
            return np.zeros(0), np.zeros(0)
        i = np.empty(x.size, np.int64)
        nearest_sample(np.ascontiguousarray(x.ravel()), np.ascontiguousarray(v.ravel()),
                       self.theta, self.theta_dot, i)
        return self._foot(x, v, i.reshape(x.shape))

    def index(self, box) -> BoundaryIndex:
        """A search index over every boundary passing through ``box`` = ((θ0, θ1), (v0, v1))
        [rad, rad s⁻¹]; ``box``'s θ̇ range must lie within ±``speed``."""
        return BoundaryIndex(self, box)

    def side(self, theta, theta_dot, saddles):
        """Basin k of the exact equation at each point (θ [rad], θ̇ [rad s⁻¹], broadcast):
        the strip S_{2k−1}(θ) < θ̇ < S_{2k+1}(θ).

        ``saddles`` = (n_below, n_above): odd n of boundaries that lie entirely below and
        above the points (from :func:`basin_areas`). For a grid pass θ shaped (1, C) and θ̇
        shaped (R, 1): each boundary is then evaluated once per column."""
        n_below, n_above = saddles
        theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
        k = np.full(np.broadcast_shapes(theta.shape, theta_dot.shape), (n_below + 1) // 2,
                    np.int64)
        for n in range(n_below + 2, n_above, 2):
            k += theta_dot > self.boundary(n, theta)
        return k


def bins(theta, theta_dot, box, cell: float):
    """Points (θ, θ̇) binned in square cells over ``box`` = ((θ0, θ1), (v0, v1)) for the
    compiled searches of :mod:`atlas.kernels.foot`: (cell side — ``cell`` [rad-ish], larger
    if the box would need more than ``_MAX_CELLS`` —, (cells along θ, along θ̇), CSR starts
    over the cells, the points' indices cell by cell). Points outside the box go to its edge
    cells."""
    (t0, t1), (v0, v1) = box
    cell = max(cell, math.sqrt((t1 - t0) * (v1 - v0) / _MAX_CELLS))
    shape = (max(1, math.ceil((t1 - t0) / cell)), max(1, math.ceil((v1 - v0) / cell)))
    cx = np.clip(((theta - t0) // cell).astype(np.int64), 0, shape[0] - 1)
    cy = np.clip(((theta_dot - v0) // cell).astype(np.int64), 0, shape[1] - 1)
    bucket = cx * shape[1] + cy
    items = np.argsort(bucket, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(bucket, minlength=shape[0] * shape[1]))])
    return cell, shape, start, items


class BoundaryIndex:
    """Nearest basin boundaries of points, among the boundary copies that pass through a box:
    their samples binned in square cells, searched and refined on the dense output of
    :class:`StableManifold` by the kernel :func:`atlas.kernels.foot.nearest_boundary`."""

    def __init__(self, manifold: StableManifold, box):
        self.manifold, self.box = manifold, box
        copies = manifold._copies(box)
        self.empty = copies is None
        if self.empty:
            return
        self.theta, self.theta_dot, self.n, self.branch, self.sample = copies
        self.cell, self.shape, self.start, self.items = bins(self.theta, self.theta_dot, box,
                                                             _CELL)

    def nearest(self, theta, theta_dot):
        """Distance [rad-ish, Euclidean in the (θ, θ̇) plane] from each point to the nearest
        boundary in the index, and that boundary's saddle n (odd); (inf, 0) if none. Exact
        (to ≈ 1e-12) wherever the true nearest boundary passes through the box."""
        from atlas.kernels.foot import nearest_boundary

        theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
        if self.empty or theta.size == 0:
            return np.full(theta.shape, np.inf), np.zeros(theta.shape, np.int64)
        m, d = self.manifold, self.manifold._sol
        dist = np.empty(theta.size)
        n = np.empty(theta.size, np.int64)
        (t0, _), (v0, _) = self.box
        nearest_boundary(np.ascontiguousarray(theta.ravel()),
                         np.ascontiguousarray(theta_dot.ravel()), self.theta, self.theta_dot,
                         self.n.astype(np.int64), self.branch.astype(np.int64),
                         self.sample.astype(np.int64), self.start, self.items, float(t0),
                         float(v0), float(self.cell), self.shape[0], self.shape[1], m.tau,
                         m.theta, m.theta_dot, d.t, d.t_old, d.h, d.y_old,
                         np.ascontiguousarray(d.F), float(m.pendulum.omega0),
                         float(m.pendulum.alpha), float(m.start[0]), float(m.start[1]), dist, n)
        return dist.reshape(theta.shape), n.reshape(theta.shape)

    def saddles_within(self, theta, theta_dot, radius: float):
        """(lowest, highest) saddle n of the boundaries that pass within ``radius`` of each
        point (a superset: samples within radius + the sample spacing); (0, 0) where none."""
        from atlas.kernels.foot import saddles_near

        theta = np.ascontiguousarray(np.ravel(theta), dtype=float)
        theta_dot = np.ascontiguousarray(np.ravel(theta_dot), dtype=float)
        lo, hi = np.zeros(theta.size, np.int64), np.zeros(theta.size, np.int64)
        if self.empty or not theta.size:
            return lo, hi
        (t0, _), (v0, _) = self.box
        saddles_near(theta, theta_dot, float(radius + SAMPLE_SPACING), self.theta,
                     self.theta_dot, self.n.astype(np.int64), self.start, self.items,
                     float(t0), float(v0), float(self.cell), self.shape[0], self.shape[1],
                     lo, hi)
        return lo, hi


@dataclass(frozen=True)
class BasinAreas:
    """Exact area fractions of a window in the basins k = k[0], …, k[-1].

    fraction: the area fraction of the window in each basin (sums to 1);
    error:    estimated error of each fraction (the change from rtol 1e-12 to 1e-13 of the
              reference, which bounds the error at 1e-13 about tenfold), at least 4 ulp;
    saddles:  (n_below, n_above), the odd n of the highest boundary entirely below the
              window and of the lowest entirely above it.
    """

    k: np.ndarray
    fraction: np.ndarray
    error: np.ndarray
    saddles: tuple[int, int]


def _boundary_integrals(manifold: StableManifold, theta_window, theta_dot_window):
    """{n: ∫ clip(S_n) dθ} for every odd n from the highest boundary entirely below the
    window to the lowest entirely above it (S_n increases with n)."""
    (a, b), (lo, hi) = theta_window, theta_dot_window
    floor, ceiling = lo * (b - a), hi * (b - a)
    scale = 1e-13 * max(abs(floor), abs(ceiling), (hi - lo) * (b - a))
    centre = 2 * math.floor(0.5 * (a + b) / (2 * math.pi)) + 1
    g = {centre: manifold.boundary_integral(centre, theta_window, theta_dot_window)}
    for step, extreme in ((2, ceiling), (-2, floor)):
        n = centre
        while abs(g[n] - extreme) > scale:
            n += step
            g[n] = manifold.boundary_integral(n, theta_window, theta_dot_window)
    return g


def _window_fractions(manifold: StableManifold, theta_window, theta_dot_window):
    """{n: the fraction of the window below S_n} for every odd n from the highest boundary
    entirely below the window to the lowest entirely above it (at the window's scale)."""
    (a, b) = theta_window
    centre = 2 * math.floor(0.5 * (a + b) / (2 * math.pi)) + 1
    g, where = {}, {}
    g[centre], where[centre] = manifold.boundary_fraction(centre, theta_window,
                                                          theta_dot_window)
    for step, wanted in ((2, 1), (-2, -1)):
        n = centre
        while where[n] != wanted:
            n += step
            if abs(n - centre) > _MAX_WALK:
                raise RuntimeError("the basin areas found no boundary beyond the window")
            g[n], where[n] = manifold.boundary_fraction(n, theta_window, theta_dot_window)
    return g


def basin_areas(pendulum: Pendulum, theta_window, theta_dot_window,
                manifolds: tuple[StableManifold, StableManifold] | None = None) -> BasinAreas:
    """Exact area fractions of the window θ ∈ ``theta_window`` [rad] × θ̇ ∈
    ``theta_dot_window`` [rad s⁻¹] in each basin: (G_{2k+1} − G_{2k−1}) / area with
    G_n = ∫ clip(S_n(θ), θ̇min, θ̇max) dθ (docs/design/stable-manifolds.md). ``manifolds``:
    the left branch integrated at rtol :data:`RTOL` and :data:`RTOL_CHECK`, each at least as
    fast as the window's θ̇ (integrated here if not given)."""
    speed = max(abs(x) for x in theta_dot_window)
    width = theta_window[1] - theta_window[0]
    area = width * (theta_dot_window[1] - theta_dot_window[0])
    if manifolds is None:
        manifolds = tuple(StableManifold(pendulum, speed, rtol) for rtol in (RTOL, RTOL_CHECK))
    small = min(width, theta_dot_window[1] - theta_dot_window[0]) < SMALL_WINDOW
    integrals = _window_fractions if small else _boundary_integrals
    fine, coarse = (integrals(m, theta_window, theta_dot_window) for m in manifolds)
    below, above = min(fine), max(fine)
    n = np.arange(min(below, min(coarse)), max(above, max(coarse)) + 1, 2)
    if small:  # fractions below each S_n: 0 below the lowest, 1 above the highest
        def below_fractions(g):
            return np.diff([g.get(n_, 0.0 if n_ < min(g) else 1.0) for n_ in n])

        fraction = below_fractions(fine)
        # rounding of the coordinates at the window's scale: the shifted θ of a boundary
        # copy and θ̇, each to an ulp, over the window's sides
        big_u = max(abs(theta_window[0]), abs(theta_window[1])) + math.pi * (np.abs(n).max()
                                                                            + 1)
        big_v = max(abs(x) for x in theta_dot_window)
        rounding = 16 * np.finfo(float).eps * (big_u / width + big_v / (
            theta_dot_window[1] - theta_dot_window[0]))
        error = np.maximum(np.abs(fraction - below_fractions(coarse)) + rounding,
                           4 * np.finfo(float).eps)
        return BasinAreas(k=(n[:-1] + 1) // 2, fraction=fraction, error=error,
                          saddles=(int(below), int(above)))

    def fractions(g):
        edge = {n_: theta_dot_window[0 if n_ < min(g) else 1] * width for n_ in n}
        values = np.array([g.get(n_, edge[n_]) for n_ in n])
        return np.diff(values) / area

    fraction = fractions(fine)
    error = np.maximum(np.abs(fraction - fractions(coarse)), 4 * np.finfo(float).eps)
    return BasinAreas(k=(n[:-1] + 1) // 2, fraction=fraction, error=error,
                      saddles=(int(below), int(above)))
