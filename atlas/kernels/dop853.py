"""DOP853 for the stable manifold of the saddle (π, 0), compiled: :func:`stable_manifold`.

The exact basin boundaries without torque (:mod:`atlas.boundaries.manifold`) are one curve,
the left branch L of (π, 0), integrated in reversed time at rtol = atol = 1e-13 with dense
output together with Q(τ) = ∫ θ̇² dτ: eq. (1) with τ = 0 reversed, (θ, θ̇, Q)' = (−θ̇,
ω0² sin θ + 2αθ̇, θ̇²). The method is scipy's ``solve_ivp(method="DOP853")`` step for step
(scipy's import alone took a tenth of an ``atlas run``): the Dormand–Prince 8(5,3) pair with
its 7th-order dense output (Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed., §II.5–6; the
coefficients of Hairer's ``dop853.f``), held as a :class:`Tableau` that checks its own
consistency; that code's step-size control as scipy implements it (error norm
|err5|²/√(|err5|² + 0.01|err3|²), safety 0.9, factors in [0.2, 10], exponent −1/8) and its
initial step (§II.4); a terminal event min(E − e_stop, θ_min − θ) located on the dense output
by bisection to 4 ulp, where the solution ends, as ``solve_ivp``'s does. Accuracy: scipy's
DOP853 on the same problem to rounding (tests/kernels/test_dop853.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from atlas.kernels import cached_njit

__all__ = ["stable_manifold", "FINISHED", "EVENT", "STEP_TOO_SMALL", "FULL", "Tableau",
           "TABLEAU"]

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


@nb.njit
def _rhs(y, alpha, omega0, out):
    """Eq. (1) in reversed time, and θ̇² for Q."""
    out[0] = -y[1]
    out[1] = omega0 * omega0 * math.sin(y[0]) + 2.0 * alpha * y[1]
    out[2] = y[1] * y[1]


@nb.njit
def _event(y, omega0, e_stop, theta_min):
    """min(E − e_stop, θ_min − θ), E = ½θ̇² + 2ω0² sin²(θ/2): both grow along L."""
    s = math.sin(0.5 * y[0])
    energy = 0.5 * y[1] * y[1] + 2.0 * omega0 * omega0 * s * s
    return min(energy - e_stop, theta_min - y[0])


@nb.njit
def _rms(v, scale):
    total = 0.0
    for i in range(v.size):
        total += (v[i] / scale[i]) ** 2
    return math.sqrt(total / v.size)


@nb.njit
def _initial_step(t0, y0, f0, t_bound, rtol, atol, alpha, omega0):
    """The first step (Hairer, Nørsett & Wanner §II.4, as scipy's select_initial_step)."""
    interval = abs(t_bound - t0)
    scale = atol + np.abs(y0) * rtol
    d0, d1 = _rms(y0, scale), _rms(f0, scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    f1 = np.empty(3)
    _rhs(y0 + h0 * f0, alpha, omega0, f1)
    d2 = _rms(f1 - f0, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


@nb.njit
def _combine(K, weights, rows, h, y, out):
    """out = y + h·Σ_j weights[j]·K[j] over the first ``rows`` stages."""
    for i in range(3):
        acc = 0.0
        for j in range(rows):
            acc += K[j, i] * weights[j]
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
    :class:`atlas.boundaries.manifold._DenseOutput` did with numpy (the same operations in the
    same order: the same doubles)."""
    for i in range(tau.size):
        step = dense_step(tau[i], t, h.size - 1)
        x = (tau[i] - t_old[step]) / h[step]
        for c in range(y_old.shape[1]):
            out[c, i] = dense_component(F, step, c, x, y_old)


@cached_njit(nogil=True)
def stable_manifold(y0, t0, t_bound, rtol, atol, alpha, omega0, e_stop, theta_min, capacity):
    """Integrate (θ, θ̇, Q) from ``y0`` at reversed time ``t0`` [s] towards ``t_bound`` until
    the event (module docstring) with DOP853 at ``rtol``, ``atol``; α [s⁻¹], ω0 [rad s⁻¹].

    Returns (status, n steps, t (n + 1) step ends — the last one the event —, y (n + 1, 3)
    there, and per step t_old, h, y_old (n, 3) and F (n, 7, 3): step i's dense output is
    y_old[i] + the polynomial of F[i] in x = (τ − t_old[i])/h[i], F[i, 0] the lowest term).
    At most ``capacity`` steps."""
    ts = np.empty(capacity + 1)
    ys = np.empty((capacity + 1, 3))
    t_olds, hs = np.empty(capacity), np.empty(capacity)
    y_olds, Fs = np.empty((capacity, 3)), np.empty((capacity, _POWER, 3))
    K = np.empty((16, 3))
    y = y0.copy()
    t = t0
    f = np.empty(3)
    _rhs(y, alpha, omega0, f)
    h_abs = _initial_step(t0, y, f, t_bound, rtol, atol, alpha, omega0)
    g = _event(y, omega0, e_stop, theta_min)
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
            K[0] = f
            for s in range(1, _STAGES):
                _combine(K, _A[s], s, h, y, stage)
                _rhs(stage, alpha, omega0, K[s])
            _combine(K, _B, _STAGES, h, y, y_new)
            _rhs(y_new, alpha, omega0, f_new)
            K[_STAGES] = f_new
            err5, err3 = 0.0, 0.0
            for i in range(3):
                scale = atol + max(abs(y[i]), abs(y_new[i])) * rtol
                e5, e3 = 0.0, 0.0
                for j in range(_STAGES + 1):
                    e5 += K[j, i] * _E5[j]
                    e3 += K[j, i] * _E3[j]
                err5 += (e5 / scale) ** 2
                err3 += (e3 / scale) ** 2
            if err5 == 0.0 and err3 == 0.0:
                norm = 0.0
            else:
                norm = h_abs * err5 / math.sqrt((err5 + 0.01 * err3) * 3.0)
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
            _combine(K, _A[s], s, h, y, stage)
            _rhs(stage, alpha, omega0, K[s])
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
        g_new = _event(y_new, omega0, e_stop, theta_min)
        n += 1
        if g <= 0.0 <= g_new:  # the event, crossed upwards: bisect on the dense output
            lo, hi = t, t_new
            while hi - lo > 4.0 * _EPS * max(abs(lo), abs(hi), 1.0):
                mid = 0.5 * (lo + hi)
                if _event(_dense(mid, t, h, y, F), omega0, e_stop, theta_min) >= 0.0:
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
