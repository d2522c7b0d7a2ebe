"""Locating the RK4 map's separatrices by shooting to the saddle: one orbit per point.

A separatrix is the stable manifold W^s(q) of a saddle q = (θs, 0) of the RK4 map F at step
dt (a saddle of the equation is a fixed point of F: every stage is at q). Instead of labelling
both ends of a bracket (:mod:`atlas.boundaries.bisection`: two orbits that each linger at the
saddle ln(1/δ)/u1 and then fall into a trap), the segment [c − w·d, c + w·d] across the curve
is followed as a whole: the orbit of its centre with its tangent and a bound β on the rest
(:mod:`atlas.kernels.shooting`). Near q its image is read in the eigen-coordinates z = (u, s)
of DF(q) = R(dt·A) (R the RK4 stability polynomial, A = Df(q)).

**The certificate** (a covering relation with cone conditions: Zgliczyński & Gidea, J.
Differential Equations 202 (2004) 32–58). In z, F is G(z) = Λz + N(z), Λ = diag(μu, μs) =
diag(R(dt·λu), R(dt·λs)), and on the box ‖z‖∞ ≤ r, |N(z)|∞ ≤ K(r)·‖z‖∞²
(:func:`saddle_box`, :func:`atlas.kernels.shooting.cone_slope`). If K·r·(1 + 1/κ) ≤
½(μu − μs), K·r/κ ≤ ½(μu − 1) and K·r ≤ ½(1 − μs), the cones U± = {±u ≥ κ|s|, u ≠ 0} map
into themselves with |u| growing, and S = {|u| < κ|s|} within ‖z‖∞ ≤ ρ = r/(μu + K·r) maps
into S (|s| shrinking) or into U. So a curve inside ‖z‖∞ ≤ ρ from a point of U+ to a point of
U− holds a point whose orbit stays in S for ever, so converges to q: a point of W^s(q). (Each
point of the curve that leaves S within the box leaves it into U+ or U−; the side where it
first does is locally constant along the curve — an image in U± stays in U± while in the
box, strictly inside by the factor ½ —, so it cannot change from + to − without a point that
never leaves.) The curve is the segment's image after k steps, enclosed in the line
x_k + σ·w·y_k thickened by β_k; when that lies in the box with its two ends in opposite
cones (:data:`~atlas.kernels.shooting.CROSSED`), W^s(q) crosses the segment: the point is
located to the segment's width 2w < tol.

What it takes as given, as every label of atlas does: the floating-point orbit is the RK4
map's orbit, and the polynomial sin of the kernels is sin (≤ 1e-15); the bounds' own rounding
is covered by the factor ½ in the cone conditions and a few ulp in the enclosure. How far the
orbit's rounding could move the crossing is estimated along each shot (pulled back along the
tangent, summed with one sign: pessimistic, not a bound); a point is certified only where
half its bracket plus that estimate is within tol. The stored bracket is the certified
segment: like a label's bracket, it does not include that rounding (the attribute
``rounding`` of a trace reports its largest estimate).

**Locating.** When both ends land in one cone (:data:`~atlas.kernels.shooting.SAME`), the
image's line crosses the stable eigen-line at σ* = −u(x_k)/u(w·y_k): a Newton step on the
saddle's unstable coordinate, good to the manifold's curvature over the distance the orbit
still has to go (≈ 1e-13 from 3e-9 off). :meth:`Shooter.locate` shoots every
``_STRIDE``-th vertex of a run from the exact curve and the others from a spline of those
located first (:func:`atlas.boundaries.bisection.predict_offsets`), with Newton steps, up to
``_ROUNDS`` shots a point (:meth:`Shooter.refine`); what it cannot certify is left to the
bisection on labels.

**A wide segment, a narrow bracket.** The enclosure holds for every σ ∈ [−1, 1] at once, so
a part of the segment is read as a segment of its own (its centre x_k + c·w·y_k, its
half-width h·w, the same β). A spline's prediction is shot ``PREDICTED_WIDTH`` times wider
than the bracket it needs; once the whole is crossed the orbit goes on, reading the part
of half-width HALF_WIDTH·tol around its latest Newton estimate until that part is crossed
too (:func:`atlas.kernels.shooting.shoot`'s ``target``): a few checks more instead of a
second orbit where the prediction was off by more than the bracket.
Derivation: docs/design/separatrices.md#shooting.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from atlas import defaults
from atlas.boundaries.bisection import FIRST_BRACKET, predict_offsets
from atlas.labels.trap import n_checks_for
from atlas.physics.pendulum import Pendulum

__all__ = ["SaddleBox", "Shooter", "saddle_box", "left_to_labels", "HALF_WIDTH"]

#: Half-width of a shot segment [tol]: the located point's bracket is 0.9·tol wide.
HALF_WIDTH = 0.45
_STRIDE = 16  # every 16th vertex of a run is shot first, from the exact curve
_ROUNDS = 4  # shots per vertex at most (each a Newton step when it does not cross)
_NARROWEST = 0.05  # no segment narrower than this [tol]: its orbit's rounding is too large
_R_MAX = 0.1  # the largest box [z units] an image is read in
#: Half-width [HALF_WIDTH·tol] of a segment shot around a spline's prediction: it covers the
#: prediction's error, and the orbit goes on until a part of it as narrow as HALF_WIDTH·tol
#: around the Newton estimate is crossed (a few more steps, instead of a second orbit).
PREDICTED_WIDTH = 128.0
EXACT_WIDTH = 1.0
_AFTER_NEWTON = 2.0  # the half-width [HALF_WIDTH·tol] of a segment around a Newton estimate


@dataclass(frozen=True)
class SaddleBox:
    """The saddles' constants for the RK4 map at step dt [s] (the module docstring's
    notation): ``pinv`` = P⁻¹ (rows: the unstable, then the stable coordinate of a
    displacement from q), the multipliers ``mu_u`` > 1 > ``mu_s`` > 0, ``lip`` ≥ ‖DF‖₂,
    ``curvature`` ≥ ‖D²F‖₂, ``gain`` (|P⁻¹e|∞ ≤ gain·|e|₂), ``spread`` (|Pz|₂ ≤ spread·‖z‖∞),
    ``sin_saddle`` = |sin θs| = |τ|/ω0², ``r_max``, the largest box tried; and for β, in the
    norm |v|_W = √(ω0²vθ² + vθ̇²): ``gain_w`` (|P⁻¹e|∞ ≤ gain_w·|e|_W), ``curvature_w`` ≥
    ‖D²F‖_W, ``step_base`` = 1 + ½(dt·L_W)² + ½(dt·L_W)²(1 + dt·L_W), the part of
    :func:`atlas.kernels.shooting.step_norm`'s bound that does not follow the orbit."""

    pinv: np.ndarray
    mu_u: float
    mu_s: float
    lip: float
    curvature: float
    gain: float
    spread: float
    sin_saddle: float
    r_max: float
    gain_w: float
    curvature_w: float
    step_base: float

    @property
    def constants(self) -> tuple:
        """The tuple the kernel reads (:func:`atlas.kernels.shooting.cone_slope`,
        :func:`~atlas.kernels.shooting.step_norm`)."""
        return (self.mu_u, self.mu_s, self.lip, self.curvature, self.gain, self.spread,
                self.sin_saddle, self.gain_w, self.curvature_w, self.step_base)

    def cone(self, r: float) -> tuple[float, float]:
        """(κ, ρ) certified in the box ‖z‖∞ ≤ r (:func:`atlas.kernels.shooting.cone_slope`)."""
        from atlas.kernels.shooting import cone_slope

        return cone_slope(float(r), self.constants)


def _stability(x: float) -> float:
    """RK4's stability polynomial R(x) = 1 + x + x²/2 + x³/6 + x⁴/24."""
    return 1.0 + x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x / 24.0)))


def _field_norm(a: float, c: float, alpha: float) -> float:
    """The spectral norm of [[0, a], [c, −2α]]: √ of the larger eigenvalue of its Gram
    matrix, whose trace is a² + c² + 4α² and determinant (ac)², rounded up by a relative
    1e-12."""
    trace, det = a * a + c * c + 4.0 * alpha * alpha, (a * c) ** 2
    return math.sqrt(0.5 * (trace + math.sqrt(trace * trace - 4.0 * det))) * (1.0 + 1e-12)


def saddle_box(p: Pendulum, dt: float) -> SaddleBox | None:
    """The constants of every saddle of ``p`` (they differ by 2π shifts only) for the RK4
    map at step ``dt`` [s], or None when no cone can be certified (no saddle, or dt so coarse
    that R(dt·λs) ≤ 0).

    Bounds, for f = (θ̇, τ − ω0² sin θ − 2αθ̇): ‖Df‖₂ ≤ L, the largest singular value of
    [[0, 1], [c, −2α]] over |c| ≤ ω0² (:func:`_field_norm`; at |c| = ω0², the norm being
    convex in c; in |·|_W the same with [[0, ω0], [−ω0 c, −2α]], |c| ≤ 1, L_W),
    |D²f[a, b]| = ω0²|sin θ||aθ||bθ|; the RK4 stages then give ‖DF‖₂ ≤ R(dt·L) ≤ e^{dt·L}
    (``lip``) and ‖D²F‖₂ ≤ dt·ω0²·e^{3·dt·L} (``curvature``: each stage's second derivative
    is at most ω0²·e^{3·dt·L}, and the weights sum to 1). P = [[1, 1], [λu, λs]] (A's
    eigenvectors (1, λ)); ``spread`` = ‖P‖∞→2. In |·|_W: ‖D²F‖_W ≤ dt·e^{3·dt·L_W}, and
    the stages' own Jacobians add at most dt·E with ‖dt·E‖_W ≤ ½(dt·L_W)²(1 + dt·L_W) to
    DF = I + dt·J̄ + dt·E (DY_i − I is dt/2, dt/2, dt times the previous stage's Jacobian)."""
    if not p.has_rest_states:
        return None
    lam_u, lam_s = p.saddle_eigenvalues()
    mu_u, mu_s = _stability(dt * lam_u), _stability(dt * lam_s)
    if not (mu_u > 1.0 > mu_s > 0.0):
        return None
    big_l = _field_norm(1.0, p.omega0**2, p.alpha)
    # in |·|_W, W = diag(ω0, 1): W·Df·W⁻¹ = [[0, ω0], [−ω0 cos θ, −2α]], and
    # |D²f[a, b]|_W ≤ |sin θ|·|a|_W·|b|_W
    norm_w = _field_norm(p.omega0, p.omega0, p.alpha)
    pmat = np.array([[1.0, 1.0], [lam_u, lam_s]])
    pinv = np.array([[lam_s, -1.0], [-lam_u, 1.0]]) / (lam_s - lam_u)
    return SaddleBox(pinv=pinv, mu_u=mu_u, mu_s=mu_s, lip=math.exp(dt * big_l),
                     curvature=dt * p.omega0**2 * math.exp(3.0 * dt * big_l),
                     gain=float(np.max(np.hypot(pinv[:, 0], pinv[:, 1]))),
                     spread=float(np.hypot(*np.abs(pmat).sum(axis=1))),
                     sin_saddle=min(1.0, abs(p.torque) / p.omega0**2), r_max=_R_MAX,
                     gain_w=float(np.max(np.hypot(pinv[:, 0] / p.omega0, pinv[:, 1]))),
                     curvature_w=dt * math.exp(3.0 * dt * norm_w),
                     step_base=1.0 + 0.5 * (dt * norm_w) ** 2 * (2.0 + dt * norm_w))


class Shooter:
    """Shoots segments of half-width ``HALF_WIDTH``·``tol`` across the stable manifolds of
    the pendulum ``p``'s saddles for the RK4 map at step ``dt`` [s], each shot at most
    ``t_max`` [s] long, with Newton steps (module docstring); counts its ``shots``. ``box``
    is None (and nothing is certified) where no cone can be (:func:`saddle_box`) or the
    labels' ``method`` is not "rk4" (the kernel's map)."""

    def __init__(self, p: Pendulum, tol: float, *, dt: float, t_max: float,
                 method: str = defaults.METHOD):
        self.p, self.tol, self.dt = p, tol, dt
        # the kernel integrates classical RK4 on (θ, θ̇): another method's map is not its map
        self.box = saddle_box(p, dt) if method == "rk4" else None
        from atlas.kernels.shooting import CHECK_EVERY

        self.n_checks = n_checks_for(t_max, dt, CHECK_EVERY)  # checks of a shot
        self.shots = 0
        self.rounding = 0.0  # the largest rounding estimate of a certified shot [rad-ish]

    def refine(self, base, normal, offset, saddle, fresh=None, frame: int = 0, wide=None):
        """Shoot the segments base + (offset ± w)·normal towards the saddles (``saddle`` (N,)
        [rad], 0), w = ``wide`` (N,) [HALF_WIDTH·tol] times HALF_WIDTH·tol (1 by default),
        certifying a part of half-width ≤ HALF_WIDTH·tol whose half-width plus the orbit's
        rounding estimate R is within tol (:func:`atlas.kernels.shooting.shoot`'s ``target``
        and ``budget``: one orbit, where a wide segment is crossed, locates the point to its
        narrow bracket); moving each centre by the Newton step while both ends fall on one
        side (then w = ``_AFTER_NEWTON``·HALF_WIDTH·tol), at most ``_ROUNDS`` shots; a crossed
        segment left wider than that (its part undecided) is shot again, with the half-width
        0.9·(tol − R), around the Newton estimate; a centre whose shot misses the saddle
        (neither side: a prediction far off) starts once more from offset 0 where ``fresh``
        is True. Returns (s_lo, s_hi, ok, estimate): where ``ok``, W^s crosses
        base + s·normal for some s in [s_lo, s_hi] (NaN elsewhere); ``estimate`` the last
        Newton estimate of that s (inside the bracket where ``ok``; not certified), NaN where
        no shot reached the saddle. ``frame``: the orbits are kept within π of the saddle
        θs + 2π·frame, so that a copy shifted by 2π·frame is computed with other roundings
        (the shift check)."""
        n = offset.size
        lo, hi, estimate = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
        ok = np.zeros(n, bool)
        if self.box is None:
            return lo, hi, ok, estimate
        from atlas.kernels.shooting import CROSSED, SAME, shoot

        tol = self.tol
        narrow_half = HALF_WIDTH * tol
        todo, off = np.arange(n), np.asarray(offset, float).copy()
        half = narrow_half * (np.ones(n) if wide is None else np.asarray(wide, float))
        fresh = np.zeros(n, bool) if fresh is None else np.asarray(fresh, bool).copy()
        box, p = self.box, self.p
        centre_saddle = p.saddle_angle + 2.0 * math.pi * frame
        for _ in range(_ROUNDS):
            if not todo.size:
                break
            w = half[todo]
            centre = base[todo] + off[:, None] * normal[todo]
            kind, _, sigma, rounding, reached, part = shoot(
                centre[:, 0], centre[:, 1], normal[todo, 0], normal[todo, 1], w, box.pinv,
                box.constants, r_max=box.r_max, saddle0=centre_saddle, alpha=p.alpha,
                omega0=p.omega0, torque=p.torque, dt=self.dt, n_checks=self.n_checks,
                target=narrow_half, budget=tol)
            # a shot read at another saddle than the vertex's is no use to it
            target = saddle[todo]
            elsewhere = np.isfinite(target) & (reached != np.rint(
                (target - centre_saddle) / (2.0 * math.pi)))
            kind = np.where(elsewhere, -1, kind)
            self.shots += todo.size
            # the certified part: narrower than tol, and half of it plus the rounding
            # estimate within tol; where it is not, a narrower segment is shot around the
            # Newton estimate (its rounding is the same: the orbit is), if one is left
            across = kind == CROSSED
            s_lo, s_hi = off + part[:, 0] * w, off + part[:, 1] * w
            width = s_hi - s_lo
            crossed = across & (width < tol) & (0.5 * width + rounding <= tol)
            narrower = 0.9 * (tol - rounding)
            narrow = across & ~crossed & (narrower >= _NARROWEST * tol)
            self.rounding = max(self.rounding, float(rounding[crossed].max(initial=0.0)))
            done = todo[crossed]
            lo[done], hi[done] = s_lo[crossed], s_hi[crossed]
            ok[done] = True
            # the Newton estimate, certified or not (a CROSSED shot's lies in its part)
            read = (across | (kind == SAME)) & np.isfinite(sigma)
            moved = off + np.where(across, np.clip(np.nan_to_num(sigma), part[:, 0],
                                                   part[:, 1]), np.nan_to_num(sigma)) * w
            estimate[todo[read]] = moved[read]
            # a Newton step where both ends fell on one side; a centre whose shot missed the
            # saddle (a spline's prediction far off) starts again from the exact curve
            step = (kind == SAME) & np.isfinite(sigma)
            lost = ~across & ~step & fresh[todo]
            again = step | lost | narrow
            half[todo[narrow]] = narrower[narrow]
            half[todo[step]] = _AFTER_NEWTON * narrow_half
            off = np.where(step | narrow, moved, 0.0)[again]
            fresh[todo[lost]] = False
            half[todo[lost]] = narrow_half
            todo = todo[again]
        return lo, hi, ok, estimate

    def locate(self, base, normal, saddle, run, along):
        """Locate every vertex (``base`` (N, 2) on the exact curve, unit ``normal`` (N, 2),
        on the stable manifold of the saddle (``saddle`` (N,) [rad], 0)): every
        ``_STRIDE``-th vertex of each run (consecutive vertices with one ``run`` value,
        ordered by ``along``) and its last from the exact curve, the others from a spline
        of the Newton estimates of those (:func:`atlas.boundaries.bisection.predict_offsets`).
        Returns (s_lo, s_hi, ok, estimate) as :meth:`refine`."""
        n = run.size
        lo, hi, ok = np.full(n, np.nan), np.full(n, np.nan), np.zeros(n, bool)
        best = np.full(n, np.nan)
        if not n:
            return lo, hi, ok, best
        start = np.flatnonzero(np.diff(run, prepend=-1) != 0)
        stop = np.append(start[1:], n)
        local = np.arange(n) - np.repeat(start, stop - start)
        first = local % _STRIDE == 0
        first[stop - 1] = True
        for pick in (first, ~first):  # the spline reads the certified points' estimates only
            offset, predicted = predict_offsets(along, best, ok, pick, start, stop)
            i = np.flatnonzero(pick)
            lo[i], hi[i], ok[i], best[i] = self.refine(
                base[i], normal[i], offset[i], saddle[i], fresh=predicted[i],
                wide=np.where(predicted[i], PREDICTED_WIDTH, EXACT_WIDTH))
        return lo, hi, ok, best


def left_to_labels(ok, estimate, tol: float) -> list[tuple]:
    """The points the shots did not certify (``ok`` False), grouped for the bisection on
    labels: (indices, centre offsets, first half-width [rad-ish]) — around a shot's Newton
    estimate (±HALF_WIDTH·tol) where a shot reached the saddle, else around the exact curve
    (±FIRST_BRACKET·tol)."""
    groups = []
    for guessed in (True, False):
        i = np.flatnonzero(~ok & (np.isfinite(estimate) == guessed))
        if i.size:
            groups.append((i, np.nan_to_num(estimate[i]) if guessed else np.zeros(i.size),
                           (HALF_WIDTH if guessed else FIRST_BRACKET) * tol))
    return groups
