"""DOP853, compiled: every manifold and cycle atlas integrates on the run path.

:func:`integrate` solves one of three problems (``kind``) of eq. (1) with torque τ until a
terminal event: REVERSED, the stable manifolds in reversed time with Q(τ) = ∫ θ̇² dτ,
(θ, θ̇, Q)' = (−θ̇, ω0² sin θ + 2αθ̇ − τ, θ̇²) — without torque the left branch L of (π, 0)
(:mod:`atlas.boundaries.manifold`, :func:`stable_manifold`), with torque the tilted branches
until θ̇ leaves a band (:mod:`atlas.boundaries.tilted`); FLOW, forward time, the turns of
the running limit cycle's Poincaré map (:mod:`atlas.physics.running`); ALONG_THETA, an orbit
(or the running barrier's lower curve) as a function of θ. The method is scipy's
``solve_ivp(method="DOP853")`` step for step (scipy's import alone took a tenth of an
``atlas run``): the Dormand–Prince 8(5,3) pair with
its 7th-order dense output (Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed., §II.5–6; the
coefficients of Hairer's ``dop853.f``), held as a :class:`Tableau` that checks its own
consistency; that code's step-size control as scipy implements it (error norm
|err5|²/√(|err5|² + 0.01|err3|²), safety 0.9, factors in [0.2, 10], exponent −1/8) and its
initial step (§II.4); a terminal event (ENERGY … BELOW) located on the dense output by
bisection to 4 ulp, where the solution ends, as ``solve_ivp``'s does. Accuracy: scipy's
DOP853 on the same problem to rounding (tests/kernels/test_dop853.py,
tests/kernels/test_dop853_torque.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import cached_njit

__all__ = ["integrate", "solve", "Solution", "stable_manifold", "dense_output", "FINISHED", "EVENT",
           "STEP_TOO_SMALL", "FULL", "REVERSED", "FLOW", "ALONG_THETA", "ENERGY", "BAND", "TURN",
           "BELOW", "NONE", "Tableau", "TABLEAU"]

#: Statuses of :func:`stable_manifold`: reached t_bound; stopped at the event; the step
#: fell below 10 ulp of τ; more steps than the output arrays hold (call again with more).
FINISHED, EVENT, STEP_TOO_SMALL, FULL = 0, 1, -1, -2
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_EXPONENT = -1.0 / 8.0  # −1/(order of the error estimator + 1)
_STAGES = 12  # stages of a step; 13 … 15 are the dense output's extra stages
_POWER = 7  # terms of the dense output's polynomial
_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class Tableau:
    """An explicit Runge–Kutta pair as data, after diffrax's ``ButcherTableau``: the nodes
    ``c``, the stage weights ``a`` (row s: the weights of stages 0 … s − 1 in stage s), the
    solution weights ``b``, the error weights ``e3`` and ``e5`` (b minus an embedded
    solution's weights) and the dense output's coefficients ``d``.

    It checks its own consistency on construction, so that a mistyped coefficient fails at
    import instead of in a result: each row sum of ``a`` is its node (stage s is evaluated at
    t + c_s·h), ``b`` sums to 1 (consistency: order ≥ 1) and ``e3``, ``e5`` sum to 0 (both
    solutions consistent) — each to ``ULPS`` ulps of the sum of the magnitudes added, i.e.
    to rounding (this pair's defects are below 0.2 ulp; one coefficient off by 1e-14 of its
    row's magnitude makes a defect of 45 ulps).
    Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.1 (the conditions), §II.5 (this pair)."""

    c: np.ndarray
    a: np.ndarray
    b: np.ndarray
    e3: np.ndarray
    e5: np.ndarray
    d: np.ndarray

    #: Largest accepted defect of a consistency condition, in ulps of its magnitude.
    ULPS = 4.0

    def __post_init__(self) -> None:
        bad = {name: round(ulps, 1) for name, ulps in self.defects().items()
               if not ulps <= self.ULPS}
        if bad:
            raise ValueError(f"inconsistent Runge-Kutta tableau (defects in ulps): {bad}")

    def defects(self) -> dict[str, float]:
        """Each consistency condition's defect, in ulps of the magnitude of its terms:
        ``a[s]`` for the row sums (stage s), ``b``, ``e3``, ``e5`` for the weight sums."""
        def ulps(terms, target):
            terms = np.asarray(terms, float)
            scale = np.finfo(float).eps * max(float(np.abs(terms).sum()), abs(target), 1e-300)
            return float(abs(terms.sum() - target) / scale)

        out = {f"a[{s}]": ulps(self.a[s, :s], self.c[s]) for s in range(1, self.c.size)}
        out.update(b=ulps(self.b, 1.0), e3=ulps(self.e3, 0.0), e5=ulps(self.e5, 0.0))
        return out


# The Dormand–Prince 8(5,3) tableau and dense output of dop853.f (module docstring).
_C = np.array([0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274,
               0.2816496580927726, 0.3333333333333333, 0.25, 0.3076923076923077,
               0.6512820512820513, 0.6, 0.8571428571428571, 1.0, 1.0, 0.1, 0.2, 0.7777777777777778])
_A = np.zeros((16, 16))  # row s: the stage-s weights of stages 0 … s − 1
_A[1, :1] = [0.05260015195876773]
_A[2, :2] = [0.0197250569845379, 0.0591751709536137]
_A[3, :3] = [0.02958758547680685, 0.0, 0.08876275643042054]
_A[4, :4] = [0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792]
_A[5, :5] = [0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242]
_A[6, :6] = [0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125]
_A[7, :7] = [0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328,
             -0.015319437748624402, 0.008273789163814023]
_A[8, :8] = [0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726,
             27.59209969944671, 20.154067550477894, -43.48988418106996]
_A[9, :9] = [0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843,
             21.230051448181193, 15.279233632882423, -33.28821096898486, -0.020331201708508627]
_A[10, :10] = [-0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295,
               -8.149787010746927, -18.52006565999696, 22.739487099350505, 2.4936055526796523,
               -3.0467644718982196]
_A[11, :11] = [2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625,
               -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063,
               12.360567175794303, 0.6433927460157636]
_A[12, :12] = [0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
               -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034,
               0.04471061572777259]
_A[13, :13] = [0.056167502283047954, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25350021021662483,
               -0.2462390374708025, -0.12419142326381637, 0.15329179827876568, 0.00820105229563469,
               0.007567897660545699, -0.008298]
_A[14, :14] = [0.03183464816350214, 0.0, 0.0, 0.0, 0.0, 0.028300909672366776, 0.053541988307438566,
               -0.05492374857139099, 0.0, 0.0, -0.00010834732869724932, 0.0003825710908356584,
               -0.00034046500868740456, 0.1413124436746325]
_A[15, :15] = [-0.42889630158379194, 0.0, 0.0, 0.0, 0.0, -4.697621415361164, 7.683421196062599,
               4.06898981839711, 0.3567271874552811, 0.0, 0.0, 0.0, -0.0013990241651590145,
               2.9475147891527724, -9.15095847217987]
_B = np.array([0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
               -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034,
               0.04471061572777259])
_E3 = np.array([-0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
                -5.801203960010585, -0.4226823213237919, -0.1521609496625161, 0.20136540080403034,
                0.02265179219836082, 0.0])
_E5 = np.array([0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044, -0.4957589496572502,
                1.6643771824549864, -0.35032884874997366, 0.3341791187130175, 0.08192320648511571,
                -0.022355307863886294, 0.0])
_D = np.array([
    [-8.428938276109013, 0.0, 0.0, 0.0, 0.0, 0.5667149535193777, -3.0689499459498917,
     2.38466765651207, 2.117034582445028, -0.871391583777973, 2.2404374302607883,
     0.6315787787694688, -0.08899033645133331, 18.148505520854727, -9.194632392478356,
     -4.436036387594894],
    [10.427508642579134, 0.0, 0.0, 0.0, 0.0, 242.28349177525817, 165.20045171727028,
     -374.5467547226902, -22.113666853125306, 7.733432668472264, -30.674084731089398,
     -9.332130526430229, 15.697238121770845, -31.139403219565178, -9.35292435884448,
     35.81684148639408],
    [19.985053242002433, 0.0, 0.0, 0.0, 0.0, -387.0373087493518, -189.17813819516758,
     527.8081592054236, -11.57390253995963, 6.8812326946963, -1.0006050966910838,
     0.7777137798053443, -2.778205752353508, -60.19669523126412, 84.32040550667716,
     11.99229113618279],
    [-25.69393346270375, 0.0, 0.0, 0.0, 0.0, -154.18974869023643, -231.5293791760455,
     357.6391179106141, 93.40532418362432, -37.45832313645163, 104.0996495089623, 29.8402934266605,
     -43.53345659001114, 96.32455395918828, -39.17726167561544, -149.72683625798564],
])
#: The DOP853 pair above as one checked object (:class:`Tableau`); the compiled step reads
#: the same arrays.
TABLEAU = Tableau(c=_C, a=_A, b=_B, e3=_E3, e5=_E5, d=_D)


#: The problems :func:`integrate` solves (``kind``), y = (y0, y1, y2), params = (α, ω0, τ, ε):
#: REVERSED: eq. (1) with τ in reversed time and Q, (θ, θ̇, Q)' = (−θ̇, −θ̈, θ̇²);
#: FLOW: eq. (1) with τ forward, (θ, θ̇, Q)' = (θ̇, θ̈, θ̇²);
#: ALONG_THETA: the orbit as a function of the angle x = θ, y = (θ̇, t, ·):
#: (θ̇, t)' = ((θ̈ − ε)/θ̇, 1/θ̇) (ε = 0: an orbit; ε > 0: a curve the flow crosses upward).
REVERSED, FLOW, ALONG_THETA = 0, 1, 2
#: The terminal events (``event``), g(x, y) crossing 0 upwards, event_params = (e0, e1):
#: ENERGY: min(E − e0, e1 − θ) (the untilted manifold: faster than e0, left of e1);
#: BAND: max(θ̇ − e1, e0 − θ̇) (θ̇ leaves the band (e0, e1)); TURN: max(θ − e0, −θ̇) (θ reaches
#: e0, or θ̇ falls to 0); BELOW: e0 − y0 (y0 falls to e0); NONE: no event.
ENERGY, BAND, TURN, BELOW, NONE = 0, 1, 2, 3, 4


@nb.njit
def _rhs(kind, x, y, params):
    """The right-hand side of problem ``kind`` at x (see REVERSED, FLOW, ALONG_THETA), as a
    tuple of its three components. θ̈ = τ − X, X = ω0² sin θ + 2αθ̇, written so that REVERSED
    with τ = 0 gives the untilted manifold's doubles (−(0 − X) = X exactly)."""
    alpha, omega0, torque = params[0], params[1], params[2]
    if kind == ALONG_THETA:
        accel = torque - (omega0 * omega0 * math.sin(x) + 2.0 * alpha * y[0])
        return (accel - params[3]) / y[0], 1.0 / y[0], 0.0
    accel = torque - (omega0 * omega0 * math.sin(y[0]) + 2.0 * alpha * y[1])
    if kind == REVERSED:
        return -y[1], -accel, y[1] * y[1]
    return y[1], accel, y[1] * y[1]


@nb.njit
def _event(event, y, params, event_params):
    """g of the terminal ``event`` (see ENERGY … NONE); the solution ends where g first
    crosses 0 upwards."""
    e0, e1 = event_params[0], event_params[1]
    if event == ENERGY:  # E = ½θ̇² + 2ω0² sin²(θ/2): grows along the untilted manifold
        s = math.sin(0.5 * y[0])
        omega0 = params[1]
        energy = 0.5 * y[1] * y[1] + 2.0 * omega0 * omega0 * s * s
        return min(energy - e0, e1 - y[0])
    if event == BAND:
        return max(y[1] - e1, e0 - y[1])
    if event == TURN:
        return max(y[0] - e0, -y[1])
    if event == BELOW:
        return e0 - y[0]
    return -1.0


@nb.njit
def _rms(v, scale, dim):
    total = 0.0
    for i in range(dim):
        total += (v[i] / scale[i]) ** 2
    return math.sqrt(total / dim)


@nb.njit
def _initial_step(kind, t0, y0, f0, t_bound, rtol, atol, params, dim):
    """The first step (Hairer, Nørsett & Wanner §II.4, as scipy's select_initial_step), over
    the first ``dim`` components."""
    interval = abs(t_bound - t0)
    scale = atol + np.abs(y0) * rtol
    d0, d1 = _rms(y0, scale, dim), _rms(f0, scale, dim)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    f1 = np.array(_rhs(kind, t0 + h0, y0 + h0 * f0, params))
    d2 = _rms(f1 - f0, scale, dim) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


@nb.njit(inline="always")
def _stage(K, table, row, count, h, y, out):
    """out = y + h·Σ_j table[row, j]·K[j] over the first ``count`` stages (the weights read
    in place: no slice of ``table`` per stage)."""
    for i in range(3):
        acc = 0.0
        for j in range(count):
            acc += K[j, i] * table[row, j]
        out[i] = y[i] + acc * h


@nb.njit
def _dense(tau, t_old, h, y_old, F):
    """The dense output of one step at τ (F highest power last, as in dop853.f)."""
    x = (tau - t_old) / h
    out = np.zeros(3)
    for i in range(_POWER - 1, -1, -1):
        for c in range(3):
            out[c] += F[i, c]
            out[c] *= x if (_POWER - 1 - i) % 2 == 0 else 1.0 - x
    return out + y_old


@nb.njit(inline="always")
def dense_step(tau, t, last):
    """The step of a whole solution's dense output that holds τ: bisection in the step ends
    ``t`` (before the first: step 0; after the last: ``last``)."""
    lo, hi = 0, t.size - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if t[mid] <= tau:
            lo = mid
        else:
            hi = mid
    return min(lo, last)


@nb.njit(inline="always")
def dense_component(F, step, c, x, y_old):
    """Component ``c`` of step ``step``'s polynomial at x = (τ − t_old)/h, ``F`` (steps ×
    powers × components) highest power first."""
    y = 0.0
    for p in range(F.shape[1]):
        y += F[step, p, c]
        y *= x if p % 2 == 0 else 1.0 - x
    return y + y_old[step, c]


@cached_njit(nogil=True)
def dense_output(tau, t, t_old, h, y_old, F, out):
    """The dense output of a whole solution at each ``tau`` into ``out`` (components ×
    len(tau)): the step found by bisection in the step ends ``t`` (before the first: the
    first step; after the last: the last), then its polynomial, ``F`` (steps × powers ×
    components) highest power first, evaluated as
    :class:`atlas.boundaries.manifold.DenseOutput` did with numpy (the same operations in the
    same order: the same doubles)."""
    for i in range(tau.size):
        step = dense_step(tau[i], t, h.size - 1)
        x = (tau[i] - t_old[step]) / h[step]
        for c in range(y_old.shape[1]):
            out[c, i] = dense_component(F, step, c, x, y_old)


@cached_njit(nogil=True)
def integrate(kind, params, event, event_params, y0, t0, t_bound, rtol, atol, dim, capacity):
    """Integrate problem ``kind`` (REVERSED, FLOW or ALONG_THETA; ``params`` = (α [s⁻¹],
    ω0 [rad s⁻¹], τ [rad s⁻²], ε [rad s⁻²])) from ``y0`` (3 components; the first ``dim``
    enter the error norm, as a ``dim``-component problem in scipy) at ``t0`` towards
    ``t_bound`` with DOP853 at ``rtol`` and per-component ``atol`` (3,), until the terminal
    ``event`` (ENERGY … NONE, with ``event_params``) or t_bound: scipy's
    ``solve_ivp(method="DOP853")`` step for step (module docstring).

    Returns (status, n steps, t (n + 1) step ends — the last one the event —, y (n + 1, 3)
    there, and per step t_old, h, y_old (n, 3) and F (n, 7, 3): step i's dense output is
    y_old[i] + the polynomial of F[i] in x = (τ − t_old[i])/h[i], F[i, 0] the lowest term).
    At most ``capacity`` steps; integration runs forward (t_bound > t0)."""
    ts = np.empty(capacity + 1)
    ys = np.empty((capacity + 1, 3))
    t_olds, hs = np.empty(capacity), np.empty(capacity)
    y_olds, Fs = np.empty((capacity, 3)), np.empty((capacity, _POWER, 3))
    K = np.empty((16, 3))
    y = y0.copy()
    t = t0
    f = np.array(_rhs(kind, t, y, params))
    weights = _B.reshape(1, _STAGES)  # the solution's weights as a table of one row
    h_abs = _initial_step(kind, t0, y, f, t_bound, rtol, atol, params, dim)
    g = _event(event, y, params, event_params)
    ts[0] = t
    ys[0] = y
    n = 0
    y_new, f_new, stage = np.empty(3), np.empty(3), np.empty(3)
    while True:
        if n == capacity:
            return FULL, n, ts, ys, t_olds, hs, y_olds, Fs
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:  # one accepted step
            if h_abs < min_step:
                return STEP_TOO_SMALL, n, ts, ys, t_olds, hs, y_olds, Fs
            t_new = min(t + h_abs, t_bound)
            h = t_new - t
            h_abs = abs(h)
            K[0, 0], K[0, 1], K[0, 2] = f[0], f[1], f[2]
            for s in range(1, _STAGES):
                _stage(K, _A, s, s, h, y, stage)
                K[s, 0], K[s, 1], K[s, 2] = _rhs(kind, t + _C[s] * h, stage, params)
            _stage(K, weights, 0, _STAGES, h, y, y_new)
            K[_STAGES, 0], K[_STAGES, 1], K[_STAGES, 2] = _rhs(kind, t + h, y_new, params)
            f_new[0], f_new[1], f_new[2] = K[_STAGES, 0], K[_STAGES, 1], K[_STAGES, 2]
            err5, err3 = 0.0, 0.0
            for i in range(dim):
                scale = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                e5, e3 = 0.0, 0.0
                for j in range(_STAGES + 1):
                    e5 += K[j, i] * _E5[j]
                    e3 += K[j, i] * _E3[j]
                err5 += (e5 / scale) ** 2
                err3 += (e3 / scale) ** 2
            if err5 == 0.0 and err3 == 0.0:
                norm = 0.0
            else:
                norm = h_abs * err5 / math.sqrt((err5 + 0.01 * err3) * float(dim))
            if norm < 1.0:
                factor = _MAX_FACTOR if norm == 0.0 else min(_MAX_FACTOR,
                                                            _SAFETY * norm**_EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            h_abs *= max(_MIN_FACTOR, _SAFETY * norm**_EXPONENT)
            rejected = True
        # dense output of the accepted step: three more stages (dop853.f's CONTD8)
        for s in range(_STAGES + 1, 16):
            _stage(K, _A, s, s, h, y, stage)
            K[s, 0], K[s, 1], K[s, 2] = _rhs(kind, t + _C[s] * h, stage, params)
        F = Fs[n]
        for i in range(3):
            delta = y_new[i] - y[i]
            F[0, i] = delta
            F[1, i] = h * f[i] - delta
            F[2, i] = 2.0 * delta - h * (f_new[i] + f[i])
            for r in range(4):
                acc = 0.0
                for j in range(16):
                    acc += _D[r, j] * K[j, i]
                F[3 + r, i] = h * acc
        t_olds[n], hs[n], y_olds[n] = t, h, y
        g_new = _event(event, y_new, params, event_params)
        n += 1
        if g <= 0.0 <= g_new:  # the event, crossed upwards: bisect on the dense output
            lo, hi = t, t_new
            while hi - lo > 4.0 * _EPS * max(abs(lo), abs(hi), 1.0):
                mid = 0.5 * (lo + hi)
                if _event(event, _dense(mid, t, h, y, F), params, event_params) >= 0.0:
                    hi = mid
                else:
                    lo = mid
            ts[n] = hi
            ys[n] = _dense(hi, t, h, y, F)
            return EVENT, n, ts, ys, t_olds, hs, y_olds, Fs
        t, g = t_new, g_new
        y[:] = y_new
        f[:] = f_new
        ts[n] = t
        ys[n] = y
        if t == t_bound:
            return FINISHED, n, ts, ys, t_olds, hs, y_olds, Fs


@cached_njit(nogil=True)
def stable_manifold(y0, t0, t_bound, rtol, atol, alpha, omega0, e_stop, theta_min, capacity):
    """Integrate (θ, θ̇, Q) from ``y0`` at reversed time ``t0`` [s] towards ``t_bound`` until
    the event min(E − e_stop, θ_min − θ) crosses 0 (the untilted manifold, τ = 0) with DOP853
    at ``rtol``, ``atol``; α [s⁻¹], ω0 [rad s⁻¹]: :func:`integrate` of REVERSED with event
    ENERGY, all three components in the error norm. Returns as :func:`integrate`."""
    params = np.array([alpha, omega0, 0.0, 0.0])
    return integrate(REVERSED, params, ENERGY, np.array([e_stop, theta_min]), y0, t0, t_bound,
                     rtol, np.full(3, atol), 3, capacity)


@dataclass(frozen=True)
class Solution:
    """What :func:`solve` returns: ``status`` (FINISHED, EVENT or STEP_TOO_SMALL), the step
    ends ``t`` (n + 1) and states ``y`` (n + 1, 3) there, and each step's dense output
    (``t_old``, ``h`` (n), ``y_old`` (n, 3), ``F`` (n, 7, 3), lowest power first)."""

    status: int
    t: np.ndarray
    y: np.ndarray
    t_old: np.ndarray
    h: np.ndarray
    y_old: np.ndarray
    F: np.ndarray

    def at(self, x) -> np.ndarray:
        """The dense output at the points ``x`` (1-D, within [t[0], t[-1]]): (3, len(x))."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        out = np.empty((3, x.size))
        dense_output(x, self.t, self.t_old, self.h, self.y_old,
                     np.ascontiguousarray(self.F[:, ::-1]), out)
        return out


def solve(kind: int, params, event: int, event_params, y0, t_bound: float, rtol: float,
          atol, dim: int, t0: float = 0.0, capacity: int = 1024) -> Solution:
    """:func:`integrate` from Python: the arguments as sequences (``atol`` one per component
    of y, y0 padded with zeros to 3), the output arrays grown ×4 until they hold every
    step, and trimmed to them."""
    y = np.zeros(3)
    y[:len(y0)] = y0
    tol = np.zeros(3)
    tol[:len(atol)] = atol
    tol[len(atol):] = tol[len(atol) - 1]
    args = (int(kind), np.asarray(params, np.float64), int(event),
            np.append(np.asarray(event_params, np.float64), [0.0, 0.0])[:2], y, float(t0),
            float(t_bound), float(rtol), tol, int(dim))
    while True:
        status, n, t, ys, t_old, h, y_old, F = integrate(*args, capacity)
        if status != FULL:
            return Solution(int(status), t[:n + 1].copy(), ys[:n + 1].copy(), t_old[:n].copy(),
                            h[:n].copy(), y_old[:n].copy(), F[:n].copy())
        capacity *= 4
