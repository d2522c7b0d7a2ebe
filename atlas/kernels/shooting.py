"""Shooting a short segment to a saddle: the RK4 map's orbit of its centre, with its tangent.

For the segment {c + σ·w·d : |σ| ≤ 1} (centre c = (θ, θ̇), unit direction d, half-width w),
:func:`shoot` follows x_k = F^k(c) for the RK4 map F of θ̈ = τ − ω0² sin θ − 2αθ̇ at step dt
and y_k = DF^k(c)·d, the RK4 map's exact Jacobian applied to d (the RK4 stages of the
variational equation are the derivatives of the stages: Hairer, Nørsett & Wanner, *Solving
ODEs I*, §II.3), with β_k, a bound on how far the true image F^k(c + σwd) lies from the line
x_k + σ·w·y_k, in the norm |v|_W = √(ω0²vθ² + vθ̇²):

    β_{k+1} = ‖DF(x_k)‖_W·β_k + ½·M_W·(w·|y_k|_W + β_k)²,   β_0 = 0,

with the bound on ‖DF(x_k)‖_W of :func:`step_norm` at the orbit's own stages, and
M_W ≥ ‖D²F‖_W everywhere (Taylor's theorem with the remainder;
:func:`atlas.boundaries.shooting.saddle_box` derives the constants). Every ``CHECK_EVERY``
steps θ is brought back within π of the saddle q = ``saddle0`` (its count of turns says
which saddle (saddle0 + 2πj, 0) the orbit came to) and the image is read in the saddle's
eigen-coordinates z = (u, s) = P⁻¹(x − q) (``pinv`` = P⁻¹; u along the unstable
eigenvector, s the stable one), with the enclosure's error gain·β (and a few ulp) in each
coordinate; the orbit ends when the whole image lies in the box ‖z‖∞ ≤ ρ(r), r = 1.01·μu
times the image's extent, with its ends in cones |u| ≥ κ|s| of that box (:func:`cone_slope`;
the certificate and its proof: :mod:`atlas.boundaries.shooting`):

* ``CROSSED``: the ends in opposite cones (u > 0 and u < 0): the stable manifold of the saddle
  crosses the segment;
* ``SAME``: both ends in one cone |u| ≥ |s| (not certified either way: a Newton step is
  read off);
* ``ESCAPED``: the centre was in the box and left it undecided; ``UNDECIDED``: ``n_checks``
  checks passed; ``NONFINITE``: NaN/inf met.

``sigma`` is the linear estimate of where the stable manifold crosses, in units of w from
the centre: −u(x_k)/u(w·y_k) at the decision (the stable eigen-line's crossing; NaN if never
decided). Orbits are dealt to lane blocks of ``LANES`` that advance in lockstep (as
:mod:`atlas.kernels.lanes`), with the sin and cos of :mod:`atlas.kernels.fastsin`; the result
of an orbit does not depend on the threads, chunks or the other orbits.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import cached_njit
from atlas.kernels.fastsin import SIN_FASTMATH, sin_cos_vers

__all__ = ["shoot", "cone_slope", "step_norm", "UNDECIDED", "CROSSED", "SAME", "ESCAPED",
           "NONFINITE", "CHECK_EVERY"]

#: Outcomes of :func:`shoot` (``kind``).
UNDECIDED, CROSSED, SAME, ESCAPED, NONFINITE = 0, 1, 2, 3, 4
#: Steps between two readings of the image in the saddle's coordinates.
CHECK_EVERY = 8
#: Orbits per lane block.
LANES = 32
TWO_PI = 2.0 * math.pi
EPS = 2.0**-52
#: The rounding of one RK4 step relative to |θ| + |θ̇|: u = eps/2 for the last addition of
#: each component, and 10 % for the stages before it (each weighted by dt).
ROUNDING = 0.55 * EPS
#: |fl(2π) − 2π| ≈ 2.45e-16 [rad], in units of ROUNDING: what shifting θ by TWO_PI·turn
#: instead of 2π·turn adds to the orbit's rounding, per turn.
TURN_ERROR = 2.5e-16 / ROUNDING
#: The enclosure's allowance for the rounding of a saddle's angle and of the coordinates, in
#: units of eps·(|θs| + 2π) [rad] (the angle is within a few ulp; so is P⁻¹(x − q)).
SLACK_ULPS = 16.0


@nb.njit(fastmath=SIN_FASTMATH)
def cone_slope(r, box):
    """The slope κ ≤ 1 of the cones |u| ≥ κ|s| that the saddle's ``box`` certifies in the box
    ‖z‖∞ ≤ r, and ρ(r), the box the image must lie in; κ = inf when r is too large. ``box``
    = (μu, μs, lip, curvature, gain, spread, |sin θs|, …) (:class:`atlas.boundaries.shooting.
    SaddleBox`'s ``constants``):
    on ‖z‖∞ ≤ r the stages stay within lip·spread·r of the saddle, where |D²f| ≤
    ω0²(|sin θs| + lip·spread·r), so |N(z)|∞ ≤ K(r)·‖z‖∞² with
    K(r) = ½·gain·spread²·curvature·min(1, |sin θs| + lip·spread·r); then κ is the least
    slope with K·r·(1 + 1/κ) ≤ ½(μu − μs) and K·r/κ ≤ ½(μu − 1), and K·r ≤ ½(1 − μs)."""
    mu_u, mu_s, lip, curvature, gain, spread, sin_s = box[0], box[1], box[2], box[3], box[4], \
        box[5], box[6]
    k = 0.5 * gain * spread * spread * curvature * min(1.0, sin_s + lip * spread * r)
    kr = k * r
    rho = r / (mu_u + kr)
    room = 0.5 * (mu_u - mu_s) - kr
    if not (room > 0.0 and kr <= 0.5 * (1.0 - mu_s)):
        return math.inf, rho
    slope = max(kr / room, 2.0 * kr / (mu_u - 1.0))
    return (slope if slope <= 1.0 else math.inf), rho


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _read(th, v, yt, yv, beta, w, q, pinv, box, r_max):
    """(outcome, centre inside the box, σ estimate) of the image at one check, relative to
    the saddle (q, 0)."""
    dx = th - q
    u = pinv[0, 0] * dx + pinv[0, 1] * v
    s = pinv[1, 0] * dx + pinv[1, 1] * v
    uy = w * (pinv[0, 0] * yt + pinv[0, 1] * yv)
    sy = w * (pinv[1, 0] * yt + pinv[1, 1] * yv)
    # the enclosure's error: β (in |·|_W), and the rounding of the saddle's angle and of z
    m = box[7] * beta + box[4] * SLACK_ULPS * EPS * (abs(q) + TWO_PI)
    if not (math.isfinite(u) and math.isfinite(s) and math.isfinite(uy)
            and math.isfinite(sy) and math.isfinite(m)):
        return NONFINITE, False, math.nan
    centre_in = max(abs(u), abs(s)) <= r_max
    extent = max(abs(u) + abs(uy), abs(s) + abs(sy)) + m
    if extent > r_max:
        return UNDECIDED, centre_in, math.nan
    # the least box whose ρ holds the image: ρ(r) ≥ extent for r = 1.01·μu·extent
    r = 1.01 * box[0] * extent
    slope, rho = cone_slope(r, box)
    if not (rho >= extent and slope <= 1.0):
        return UNDECIDED, centre_in, math.nan
    sigma = -u / uy if uy != 0.0 else math.nan
    need = (1.0 + slope) * m
    up_plus = (u + uy) - slope * abs(s + sy) > need
    down_plus = -(u + uy) - slope * abs(s + sy) > need
    up_minus = (u - uy) - slope * abs(s - sy) > need
    down_minus = -(u - uy) - slope * abs(s - sy) > need
    if (up_plus and down_minus) or (down_plus and up_minus):
        return CROSSED, True, sigma
    # a Newton step is read off later, where both ends are in the cones |u| ≥ |s| (its
    # error, the manifold's curvature over the orbit's distance |s| to go, is then small)
    if (up_plus and up_minus) or (down_plus and down_minus):
        near = max(abs(s + sy), abs(s - sy)) + m
        if min(abs(u + uy), abs(u - uy)) - m >= near:
            return SAME, True, sigma
    return UNDECIDED, True, sigma


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _stage(t, v, yt, yv, w2, a2, torque):
    """(k_θ, k_θ̇, j_θ, j_θ̇, cos θ): the field and the tangent's field at one stage."""
    s, c, _ = sin_cos_vers(t)
    return v, torque - w2 * s - a2 * v, yv, -(w2 * c) * yt - a2 * yv, c


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def step_norm(mean_cos, omega0, dt, base):
    """A bound on ‖DF(x)‖_W, the RK4 step's Jacobian in the norm |v|_W = √(ω0²vθ² + vθ̇²),
    from the weighted mean c̄ = (c1 + 2c2 + 2c3 + c4)/6 of cos θ at its stages: DF =
    I + dt·J̄ + dt·E with J̄ = Df at cos θ = c̄, and ‖I + dt·J̄‖_W ≤ √(1 + 2dt·μ + dt²L_W²)
    ≤ 1 + dt·μ + ½dt²L_W², with μ the log-norm of W·J̄·W⁻¹ = [[0, ω0], [−ω0 c̄, −2α]],
    −α + √(α² + ω0²(1 − c̄)²/4) ≤ ω0(1 − c̄)/2. ``base`` = 1 + ½dt²L_W² + ‖dt·E‖_W's bound
    (:func:`atlas.boundaries.shooting.saddle_box`). Near the bottom of a well this is ≈ 1,
    near a saddle ≈ 1 + dt·ω0: a bound that follows the orbit, where one constant would
    grow like e^{‖Df‖·t} along the whole approach (no square root: a step's cost)."""
    return base + 0.5 * dt * omega0 * (1.0 - mean_cos)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _middle_stage(th, v, yt, yv, st, sv, syt, syv, at, av, ayt, ayv, cb, reach, w2, a2,
                  torque):
    """RK4's second or third stage for every lane: its field added twice to the sums, and
    the next stage's point ``reach`` [s] (dt/2, then dt) along it."""
    for lane in range(LANES):
        kt, kv, jt, jv, c = _stage(st[lane], sv[lane], syt[lane], syv[lane], w2, a2, torque)
        at[lane] += 2.0 * kt
        av[lane] += 2.0 * kv
        ayt[lane] += 2.0 * jt
        ayv[lane] += 2.0 * jv
        cb[lane] += 2.0 * c
        st[lane], sv[lane] = th[lane] + reach * kt, v[lane] + reach * kv
        syt[lane], syv[lane] = yt[lane] + reach * jt, yv[lane] + reach * jv


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def _advance(th, v, yt, yv, beta, drift, pull, w, st, sv, syt, syv, at, av, ayt, ayv, cb, sg,
             half_curvature, extra, alpha, omega0, torque, dt):
    """One RK4 step [dt s] of (θ, θ̇) and of the tangent (yθ, yθ̇) it carries — the tangent's
    stages are the state's stages' derivatives, so (yθ, yθ̇) becomes DF(θ, θ̇)·(yθ, yθ̇)
    exactly, up to rounding — and of β, in the norm |·|_W of :func:`step_norm`, for every
    lane, stage by stage: each stage is one short loop over the lanes, whose
    iterations are independent, so the processor overlaps them (a whole step per lane is
    one long chain of dependent operations)."""
    w2 = omega0 * omega0
    a2 = 2.0 * alpha
    h2 = 0.5 * dt
    # (loops over few arrays each: LLVM vectorises a loop only while the runtime checks that
    # its arrays do not overlap stay few)
    for lane in range(LANES):
        sg[lane] = w[lane] * math.sqrt(w2 * yt[lane] * yt[lane] + yv[lane] * yv[lane]) \
            + beta[lane]
        # the rounding pulled back along the tangent, with 1/|y| from the last check (a
        # division here would cost as much as the step)
        drift[lane] += (abs(th[lane]) + abs(v[lane])) * pull[lane]
    for lane in range(LANES):
        kt, kv, jt, jv, c = _stage(th[lane], v[lane], yt[lane], yv[lane], w2, a2, torque)
        at[lane], av[lane], ayt[lane], ayv[lane], cb[lane] = kt, kv, jt, jv, c
        st[lane], sv[lane] = th[lane] + h2 * kt, v[lane] + h2 * kv
        syt[lane], syv[lane] = yt[lane] + h2 * jt, yv[lane] + h2 * jv
    _middle_stage(th, v, yt, yv, st, sv, syt, syv, at, av, ayt, ayv, cb, h2, w2, a2, torque)
    _middle_stage(th, v, yt, yv, st, sv, syt, syv, at, av, ayt, ayv, cb, dt, w2, a2, torque)
    h6 = dt / 6.0
    for lane in range(LANES):
        kt, kv, jt, jv, c = _stage(st[lane], sv[lane], syt[lane], syv[lane], w2, a2, torque)
        th[lane] += h6 * (at[lane] + kt)
        v[lane] += h6 * (av[lane] + kv)
        yt[lane] += h6 * (ayt[lane] + jt)
        yv[lane] += h6 * (ayv[lane] + jv)
        cb[lane] += c
    for lane in range(LANES):
        lip = step_norm(cb[lane] / 6.0, omega0, dt, extra)
        beta[lane] = lip * beta[lane] + half_curvature * sg[lane] * sg[lane]


@nb.njit(nogil=True, fastmath=SIN_FASTMATH)
def _shoot_chunk(b, n_chunks, theta, theta_dot, d_theta, d_theta_dot, half_width, target,
                 budget, pinv, box, r_max, saddle0, alpha, omega0, torque, dt, n_checks, kind,
                 n_steps, sigma, rounding, reached, bracket):
    n = theta.size
    th = np.zeros(LANES)
    v = np.zeros(LANES)
    yt = np.zeros(LANES)
    yv = np.zeros(LANES)
    beta = np.zeros(LANES)
    drift = np.zeros(LANES)
    pull = np.zeros(LANES)  # ROUNDING/|y| at the last check, times lip^(2·CHECK_EVERY)
    turns = np.zeros(LANES)
    w = np.zeros(LANES)
    orbit = np.full(LANES, -1, np.int64)
    check = np.zeros(LANES, np.int64)
    was_in = np.zeros(LANES, np.bool_)
    sub = np.zeros(LANES, np.bool_)  # the whole segment crossed: a narrower part is read
    sub_c, sub_r = np.zeros(LANES), np.zeros(LANES)  # its centre and half-width [w]
    st, sv, syt, syv = np.zeros(LANES), np.zeros(LANES), np.zeros(LANES), np.zeros(LANES)
    at, av, ayt, ayv = np.zeros(LANES), np.zeros(LANES), np.zeros(LANES), np.zeros(LANES)
    cb, seg = np.zeros(LANES), np.zeros(LANES)
    lip, half_curvature, extra = box[2], 0.5 * box[8], box[9]
    lip_check = lip ** (2 * CHECK_EVERY)
    nxt = b
    while True:
        active = 0
        for lane in range(LANES):
            while True:
                i = orbit[lane]
                if i >= 0:
                    # θ back to within π of the saddle saddle0 (exact but for one rounding,
                    # counted in the drift): the orbit's rounding stays that of |θ| ≤ 2π
                    turn = math.floor((th[lane] - saddle0) / TWO_PI + 0.5)
                    if turn != 0.0:
                        th[lane] -= TWO_PI * turn
                        turns[lane] += turn
                        # the subtraction's rounding, and fl(2π)'s own error per turn
                        drift[lane] += (abs(th[lane]) + abs(turn) * TURN_ERROR) * pull[lane]
                    lo, hi = -1.0, 1.0
                    if not sub[lane]:
                        code, centre_in, sg = _read(th[lane], v[lane], yt[lane], yv[lane],
                                                    beta[lane], w[lane], saddle0, pinv, box,
                                                    r_max)
                        if code == CROSSED and check[lane] < n_checks and (
                                w[lane] > target[i] or w[lane] + drift[lane] > budget):
                            # certified for the whole segment, wider than wanted: a part of
                            # half-width h < 1 (in units of w) around the estimate is read
                            # from now on (while checks are left: else the whole stands)
                            h = min(target[i], 0.9 * (budget - drift[lane])) / w[lane]
                            if h > 0.0:
                                sub[lane], sub_r[lane] = True, h
                                sub_c[lane] = min(max(sg, h - 1.0), 1.0 - h)
                                code = UNDECIDED
                    else:
                        c, h = sub_c[lane], sub_r[lane]
                        code, centre_in, sg = _read(th[lane] + c * w[lane] * yt[lane],
                                                    v[lane] + c * w[lane] * yv[lane],
                                                    yt[lane], yv[lane], beta[lane],
                                                    h * w[lane], saddle0, pinv, box, r_max)
                        sg = c + h * sg
                        if code == CROSSED and h * w[lane] + drift[lane] <= budget:
                            lo, hi = c - h, c + h
                        elif code == NONFINITE or check[lane] >= n_checks or not centre_in:
                            # the part undecided: the whole segment's certificate stands
                            code = CROSSED
                            sg = min(max(sg, -1.0), 1.0) if math.isfinite(sg) else c
                        else:  # undecided, beside the estimate, or wider than the rounding
                            # now leaves room for: centred on the latest estimate
                            h = min(h, 0.9 * (budget - drift[lane]) / w[lane])
                            if math.isfinite(sg) and h > 0.0:
                                sub_r[lane] = h
                                sub_c[lane] = min(max(sg, h - 1.0), 1.0 - h)
                            code = UNDECIDED
                    if code == UNDECIDED and was_in[lane] and not centre_in and not sub[lane]:
                        code = ESCAPED
                    was_in[lane] = was_in[lane] or centre_in
                    if code == UNDECIDED and check[lane] < n_checks:
                        active += 1
                        break
                    kind[i] = code
                    n_steps[i] = check[lane] * CHECK_EVERY
                    sigma[i] = sg if code == CROSSED or code == SAME else math.nan
                    rounding[i] = drift[lane]
                    reached[i] = np.int64(turns[lane])
                    bracket[i, 0], bracket[i, 1] = lo, hi
                    orbit[lane] = -1
                if nxt >= n:  # nothing left: the lane idles at rest
                    th[lane] = v[lane] = beta[lane] = w[lane] = drift[lane] = 0.0
                    yt[lane], yv[lane] = 1.0, 0.0
                    break
                i = nxt
                nxt += n_chunks
                orbit[lane] = i
                th[lane], v[lane] = theta[i], theta_dot[i]
                yt[lane], yv[lane] = d_theta[i], d_theta_dot[i]
                beta[lane], w[lane], drift[lane], turns[lane] = 0.0, half_width[i], 0.0, 0.0
                pull[lane] = ROUNDING * lip_check / math.sqrt(yt[lane] * yt[lane]
                                                            + yv[lane] * yv[lane])
                check[lane] = 0
                was_in[lane] = sub[lane] = False
        if active == 0:
            return
        for lane in range(LANES):  # |y| shrinks by at most lip per step, forwards or back
            pull[lane] = ROUNDING * lip_check / math.sqrt(yt[lane] * yt[lane]
                                                        + yv[lane] * yv[lane])
        for _ in range(CHECK_EVERY):
            _advance(th, v, yt, yv, beta, drift, pull, w, st, sv, syt, syv, at, av, ayt, ayv, cb,
                     seg, half_curvature, extra, alpha, omega0, torque, dt)
        for lane in range(LANES):
            check[lane] += 1


@cached_njit(parallel=True, nogil=True, fastmath=SIN_FASTMATH)
def _shoot(theta, theta_dot, d_theta, d_theta_dot, half_width, target, budget, pinv, box,
           r_max, saddle0, alpha, omega0, torque, dt, n_checks, kind, n_steps, sigma,
           rounding, reached, bracket, n_chunks):
    for b in nb.prange(n_chunks):
        _shoot_chunk(np.int64(b), n_chunks, theta, theta_dot, d_theta, d_theta_dot,
                     half_width, target, budget, pinv, box, r_max, saddle0, alpha, omega0,
                     torque, dt, n_checks, kind, n_steps, sigma, rounding, reached, bracket)


def shoot(theta, theta_dot, d_theta, d_theta_dot, half_width, pinv, box, *, r_max, saddle0,
          alpha, omega0, torque, dt, n_checks, target=None, budget=math.inf):
    """Shoot every segment (centres ``theta``, ``theta_dot`` [rad, rad s⁻¹], unit directions
    ``d_theta``, ``d_theta_dot``, ``half_width`` [rad-ish]) to the saddles
    (``saddle0`` + 2πj, 0) [rad], as the module docstring says, for at most ``n_checks`` ·
    CHECK_EVERY steps; ``pinv``, ``box``, ``r_max``: the saddles' constants
    (:class:`atlas.boundaries.shooting.SaddleBox`).

    ``target`` [rad-ish] (default: ``half_width``) and ``budget`` [rad-ish]: once a whole
    segment is crossed, the orbit goes on where it is wider than wanted, and reads only a
    part of it, of half-width h = min(target, 0.9·(budget − R)) (R the orbit's rounding
    estimate) centred on the latest Newton estimate, until that part is crossed too with
    h + R ≤ budget (the whole image's enclosure holds for every part of it, so each part's
    ends are read as a segment's; a few more steps, where a narrower segment would be a
    second orbit); if the part stays undecided until the orbit leaves the box or the checks
    run out, the whole segment's certificate is returned.

    Returns, one per segment: kind (int8), the step of the decision (int32), sigma, the
    rounding estimate [rad-ish] (the rounding of the orbit, ε_k = ROUNDING·(|θ| + |θ̇|) at
    every step, each pulled back to the segment as ε_k/|y_k| and summed: how far it could
    move the crossing, at the worst, not a bound), the j of the saddle the orbit was read at
    (int64), and the certified part (N, 2) [units of half_width from the centre]: (−1, 1)
    for the whole segment (NaN-free; meaningful where kind is CROSSED)."""
    arrays = [np.ascontiguousarray(a, dtype=np.float64)
              for a in (theta, theta_dot, d_theta, d_theta_dot, half_width)]
    n = arrays[0].size
    wanted = arrays[4] if target is None else np.ascontiguousarray(
        np.broadcast_to(np.asarray(target, dtype=np.float64), (n,)))
    kind = np.zeros(n, np.int8)
    n_steps = np.zeros(n, np.int32)
    sigma = np.full(n, np.nan)
    rounding = np.zeros(n)
    reached = np.zeros(n, np.int64)
    bracket = np.zeros((n, 2))
    bracket[:, 0], bracket[:, 1] = -1.0, 1.0
    if n:
        # one chunk a thread, each dealt every n_chunks-th orbit: a lane block advances until
        # its last orbit ends, so many orbits a lane keep the idle tail short (16 chunks a
        # thread, about 2 orbits a lane, cost 20 % more)
        chunks = max(1, min(n // LANES, nb.get_num_threads()))
        box = tuple(float(x) for x in box)
        _shoot(*arrays, wanted, float(budget), np.ascontiguousarray(pinv, dtype=np.float64),
               box, float(r_max), float(saddle0), float(alpha), float(omega0), float(torque),
               float(dt), int(n_checks), kind, n_steps, sigma, rounding, reached, bracket,
               chunks)
    return kind, n_steps, sigma, rounding, reached, bracket
