"""Curves made of polynomial pieces, compiled: DOP853's dense output as a curve of its own.

A *piece* is a plane curve (θ(x), θ̇(x)), x ∈ [0, 1], each coordinate a polynomial of degree
≤ 7 held by its monomial coefficients (``C[i, c, p]``: piece i, coordinate c, power p): one
step of a DOP853 solution (:func:`from_dense`: its 7th-order dense output, Hairer, Nørsett &
Wanner, *Solving ODEs I*, §II.6), or a straight segment. A closed chain of pieces is a
*curved polygon*. On such curves, exactly for the polynomials (to rounding):

- :func:`real_roots`: every root of a polynomial in (0, 1), isolated between the roots of its
  derivatives (Collins & Loos' derivative sequence) and found in its bracket by Newton's
  method kept inside it, to rounding;
- :func:`window_areas`: the area of a curved polygon, shifted by multiples of 2π in θ, inside
  a box. Each piece is cut where it crosses a line of any of the boxes, so that each part
  lies inside a box or wholly beyond one of its lines; then the area is the chord polygon's
  (Sutherland–Hodgman, :func:`atlas.kernels.polygon.window_areas`) plus, for each part
  inside, the lune between it and its chord, ½∫((θ − θ₀) dθ̇ − (θ̇ − θ̇₀) dθ), a polynomial of
  degree 13 integrated exactly by 7-point Gauss–Legendre quadrature;
- :func:`nearest`: the nearest point of a set of pieces (and their translates by 2πk in θ)
  to a point, from the roots of the derivative of the squared distance;
- :func:`nearest_between`: the nearest pair of points of two sets of pieces (a limit cycle
  and the basin boundaries), by Newton's method from the nearest samples.

Used by :mod:`atlas.boundaries.tilted` for the tilted basins' exact areas and minimal fatal
shocks (of the rest states and of the running cycle): a branch of some 300 steps instead of
a polyline of 10⁵ vertices (docs/design/tilted-boundaries.md).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import cached_njit
from atlas.kernels.polygon import window_areas as chord_areas

__all__ = ["DEGREE", "from_dense", "segment", "reversed_pieces", "real_roots", "window_areas",
           "nearest", "nearest_between", "ranges"]

#: Degree of a piece's polynomials (DOP853's dense output).
DEGREE = 7
_N = DEGREE + 1  # coefficients per coordinate
#: Most coefficients a polynomial of :func:`real_roots` may have (the squared distance to a
#: piece has degree 2·DEGREE).
_MAX_COEFFS = 2 * DEGREE + 1
_BISECTIONS = 64
_EPS = np.finfo(np.float64).eps
# 7-point Gauss–Legendre nodes and weights on [0, 1] (exact for degree 13)
_GL_X, _GL_W = np.polynomial.legendre.leggauss(7)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


# --------------------------------------------------------------------------- polynomials

@nb.njit(inline="always")
def _horner(c, n, x):
    """Σ c[p] x^p over the first ``n`` coefficients."""
    y = 0.0
    for p in range(n - 1, -1, -1):
        y = y * x + c[p]
    return y


@nb.njit
def _bracketed_root(c, terms, lo, hi, f_lo):
    """The root of Σ c[p] x^p (``terms`` coefficients) in [lo, hi], where it is monotone and
    changes sign (f(lo) = ``f_lo``): Newton's method kept inside the shrinking bracket,
    bisecting where a step would leave it, until the bracket or the step reaches rounding."""
    x = 0.5 * (lo + hi)
    for _ in range(_BISECTIONS):
        f, d = 0.0, 0.0
        for p in range(terms - 1, -1, -1):
            d = d * x + f
            f = f * x + c[p]
        if f == 0.0:
            return x
        if (f > 0.0) == (f_lo > 0.0):
            lo = x
        else:
            hi = x
        step = f / d if d != 0.0 else np.inf
        nxt = x - step
        if not lo < nxt < hi:
            nxt = 0.5 * (lo + hi)
        if nxt == x or hi - lo <= 4.0 * _EPS * max(abs(lo), abs(hi)):
            return nxt
        x = nxt
    return x


@cached_njit(nogil=True)
def real_roots(c, n, out):
    """The roots in the open interval (0, 1) of the polynomial Σ c[p] x^p (``n``
    coefficients, n ≤ 15), in increasing order, into ``out``; returns how many. The roots of
    each derivative split (0, 1) into intervals where the one below is monotone, so each of
    its roots lies alone in an interval whose ends differ in sign, where Newton's method kept
    inside the bracket finds it to rounding (a polynomial monotone on all of [0, 1], the usual
    piece, skips the derivatives); a root that is also a root of the derivative (a
    tangency, or an inflection on 0) is kept where the polynomial is exactly 0 there."""
    deg = n - 1
    while deg > 0 and c[deg] == 0.0:
        deg -= 1
    if deg == 0:
        return 0
    # monotone on [0, 1] (|c1| beats every other term of the derivative): one sign change
    bound = 0.0
    for p in range(2, deg + 1):
        bound += p * abs(c[p])
    if abs(c[1]) > bound:
        f_lo, f_hi = c[0], _horner(c, deg + 1, 1.0)
        if f_lo * f_hi >= 0.0:
            return 0
        out[0] = _bracketed_root(c, deg + 1, 0.0, 1.0, f_lo)
        return 1
    deriv = np.zeros((_MAX_COEFFS, _MAX_COEFFS))
    for p in range(deg + 1):
        deriv[0, p] = c[p]
    for j in range(1, deg):  # deriv[j]: the j-th derivative, deg − j + 1 coefficients
        for p in range(deg - j + 1):
            deriv[j, p] = deriv[j - 1, p + 1] * (p + 1)
    points = np.empty(_MAX_COEFFS + 2)
    found = np.empty(_MAX_COEFFS + 2)
    m = 0  # roots of the current derivative (none for the linear one's derivative)
    for j in range(deg - 1, -1, -1):
        terms = deg - j + 1
        points[0] = 0.0
        for i in range(m):
            points[i + 1] = found[i]
        points[m + 1] = 1.0
        count = 0
        for i in range(m + 1):
            lo, hi = points[i], points[i + 1]
            f_lo = _horner(deriv[j], terms, lo)
            f_hi = _horner(deriv[j], terms, hi)
            if i > 0 and f_lo == 0.0:  # exactly on 0 at a root of the derivative
                if count == 0 or found[count - 1] != lo:
                    found[count] = lo
                    count += 1
                continue
            if f_lo * f_hi >= 0.0:
                continue
            found[count] = _bracketed_root(deriv[j], terms, lo, hi, f_lo)
            count += 1
        m = count
    for i in range(m):
        out[i] = found[i]
    return m


@cached_njit(nogil=True)
def from_dense(y_old, F, span, out):
    """The monomial coefficients of each step's dense output as a piece, x ∈ [0, 1] running
    over the first span[s] of step s (1: the whole step; less for a step cut short by an
    event): ``F`` (steps × 7 × components, highest power first, as
    :func:`atlas.kernels.dop853.dense_component` reads it) and ``y_old`` (steps ×
    components) into ``out`` (steps × 2 × 8) for the first two components: the same nested
    product, y = (((F₀ξ + F₁)(1 − ξ) + F₂)ξ + …)·ξ + y_old with ξ = span·x, expanded."""
    poly = np.empty(_N)
    for s in range(F.shape[0]):
        for c in range(2):
            poly[:] = 0.0
            for p in range(F.shape[1]):
                poly[0] += F[s, p, c]
                if p % 2 == 0:  # times x
                    for q in range(_N - 1, 0, -1):
                        poly[q] = poly[q - 1]
                    poly[0] = 0.0
                else:  # times (1 − x)
                    for q in range(_N - 1, 0, -1):
                        poly[q] -= poly[q - 1]
            poly[0] += y_old[s, c]
            scale = 1.0
            for q in range(_N):
                out[s, c, q] = poly[q] * scale
                scale *= span[s]


def segment(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """The straight piece from (x0, y0) to (x1, y1): (1, 2, 8)."""
    out = np.zeros((1, 2, _N))
    out[0, :, 0] = (x0, y0)
    out[0, :, 1] = (x1 - x0, y1 - y0)
    return out


def _reversal() -> np.ndarray:
    """The matrix taking the coefficients of p(x) to those of p(1 − x)."""
    m = np.zeros((_N, _N))
    for p in range(_N):  # (1 − x)^p = Σ_q C(p, q) (−x)^q
        for q in range(p + 1):
            m[q, p] = math.comb(p, q) * (-1.0) ** q
    return m


_REVERSE = _reversal()


def reversed_pieces(C: np.ndarray) -> np.ndarray:
    """The same curve traversed backwards: the pieces in reversed order, each p(1 − x)."""
    return np.ascontiguousarray(C[::-1] @ _REVERSE.T)


def _bernstein() -> np.ndarray:
    """The matrix taking monomial coefficients a_p to Bernstein coefficients
    b_k = Σ_{p ≤ k} C(k, p)/C(7, p) a_p on [0, 1]."""
    m = np.zeros((_N, _N))
    for k in range(_N):
        for p in range(k + 1):
            m[k, p] = math.comb(k, p) / math.comb(DEGREE, p)
    return m


_BERNSTEIN = _bernstein()


@cached_njit(nogil=True)
def ranges(C, out):
    """Bounds on each coordinate of each piece over x ∈ [0, 1]: out[i, c] = (min, max) of its
    Bernstein coefficients (the curve lies in their convex hull)."""
    for i in range(C.shape[0]):
        for c in range(2):
            lo, hi = np.inf, -np.inf
            for k in range(_N):
                b = 0.0
                for p in range(k + 1):
                    b += _BERNSTEIN[k, p] * C[i, c, p]
                lo = min(lo, b)
                hi = max(hi, b)
            out[i, c, 0] = lo
            out[i, c, 1] = hi


# --------------------------------------------------------------------------- areas

@nb.njit
def _lune(C, i, x0, x1, gx, gw, dt, dv):
    """½∫ ((θ − θ(x0)) dθ̇ − (θ̇ − θ̇(x0)) dθ) along piece i from x0 to x1: the signed area
    between that part and its chord (``dt``, ``dv``: scratch for the derivatives)."""
    t0 = _horner(C[i, 0], _N, x0)
    v0 = _horner(C[i, 1], _N, x0)
    for p in range(1, _N):
        dt[p - 1] = C[i, 0, p] * p
        dv[p - 1] = C[i, 1, p] * p
    total = 0.0
    for g in range(gx.size):
        x = x0 + (x1 - x0) * gx[g]
        t = _horner(C[i, 0], _N, x) - t0
        v = _horner(C[i, 1], _N, x) - v0
        total += gw[g] * (t * _horner(dv, _N - 1, x) - v * _horner(dt, _N - 1, x))
    return 0.5 * (x1 - x0) * total


@nb.njit
def _cuts(C, i, box, levels, n_levels, c, cuts, m, shifted, roots):
    """Append to ``cuts`` (m used) the parameters in (0, 1) where coordinate ``c`` of piece
    i crosses any of ``levels`` within its range ``box``; returns the new m (``shifted``,
    ``roots``: scratch)."""
    for j in range(n_levels):
        level = levels[j]
        if level < box[c, 0] or level > box[c, 1]:
            continue
        for p in range(_N):
            shifted[p] = C[i, c, p]
        shifted[0] -= level
        r = real_roots(shifted, _N, roots)
        for q in range(r):
            cuts[m] = roots[q]
            m += 1
    return m


@cached_njit(nogil=True)
def window_areas(C, shifts, a, b, lo, hi, out):
    """out[i] = the area of the closed curved polygon ``C`` (pieces × 2 × 8, each piece
    ending where the next begins, the last where the first begins) shifted by shifts[i] in θ
    (θ + shifts[i]) inside the box [a, b] × [lo, hi] (module docstring). The polygon must be
    simple; its orientation does not matter."""
    n = C.shape[0]
    box = np.empty((n, 2, 2))
    ranges(C, box)
    levels = np.empty(2 * shifts.size)
    for s in range(shifts.size):
        levels[2 * s] = a - shifts[s]
        levels[2 * s + 1] = b - shifts[s]
    speeds = np.array([lo, hi])
    # the chord polygon through every cut, and the lunes of the parts inside some box
    cap = 4 * n + 64
    px, py = np.empty(cap), np.empty(cap)
    lune_sum = np.zeros(shifts.size)
    m_total = 0
    cuts = np.empty(2 * _MAX_COEFFS * (levels.size + 2) + 2)
    shifted, roots = np.empty(_N), np.empty(_MAX_COEFFS)
    dt, dv = np.empty(_N - 1), np.empty(_N - 1)
    for i in range(n):
        # a piece wholly beyond the window's θ̇ range, or beside every translate's θ range,
        # adds nothing but its chord (which lies beyond with it): its start, uncut
        beside = box[i, 1, 1] < lo or box[i, 1, 0] > hi
        if not beside:
            beside = True
            for s in range(shifts.size):
                if box[i, 0, 1] >= a - shifts[s] and box[i, 0, 0] <= b - shifts[s]:
                    beside = False
                    break
        if beside:
            if m_total + 1 > px.size:
                grown = 2 * px.size + 64
                nx, ny = np.empty(grown), np.empty(grown)
                nx[:m_total] = px[:m_total]
                ny[:m_total] = py[:m_total]
                px, py = nx, ny
            px[m_total], py[m_total] = C[i, 0, 0], C[i, 1, 0]
            m_total += 1
            continue
        m = 0
        cuts[m] = 0.0
        m += 1
        m = _cuts(C, i, box[i], levels, levels.size, 0, cuts, m, shifted, roots)
        m = _cuts(C, i, box[i], speeds, 2, 1, cuts, m, shifted, roots)
        cuts[m] = 1.0
        m += 1
        cuts[:m].sort()
        if m_total + m > px.size:
            grown = max(2 * px.size, m_total + m + 64)
            nx, ny = np.empty(grown), np.empty(grown)
            nx[:m_total] = px[:m_total]
            ny[:m_total] = py[:m_total]
            px, py = nx, ny
        for q in range(m - 1):
            x0, x1 = cuts[q], cuts[q + 1]
            if x1 <= x0:
                continue
            px[m_total] = _horner(C[i, 0], _N, x0)
            py[m_total] = _horner(C[i, 1], _N, x0)
            m_total += 1
            if C[i, 0, 2:].any() or C[i, 1, 2:].any():  # curved: its lune, where inside
                xm = 0.5 * (x0 + x1)
                tm = _horner(C[i, 0], _N, xm)
                vm = _horner(C[i, 1], _N, xm)
                if lo <= vm <= hi:
                    lune = 0.0
                    for s in range(shifts.size):
                        if a - shifts[s] <= tm <= b - shifts[s]:
                            if lune == 0.0:
                                lune = _lune(C, i, x0, x1, _GL_X, _GL_W, dt, dv)
                            lune_sum[s] += lune
    px, py = px[:m_total].copy(), py[:m_total].copy()
    # the chord polygon's orientation (+1 counter-clockwise), centred for rounding
    cx, cy = px.mean(), py.mean()
    signed = 0.0
    for k in range(m_total):
        j = k + 1 if k + 1 < m_total else 0
        signed += (px[k] - cx) * (py[j] - cy) - (px[j] - cx) * (py[k] - cy)
    orientation = 1.0 if signed >= 0.0 else -1.0
    chord_areas(px, py, shifts, a, b, lo, hi, out)
    for s in range(shifts.size):
        out[s] = abs(out[s] + orientation * lune_sum[s])


# --------------------------------------------------------------------------- nearest point

@nb.njit
def _project(C, i, shift, x, y, scratch):
    """(distance, x ∈ [0, 1]) of the nearest point of piece i translated by ``shift`` in θ
    to (x, y): the squared distance (θ − x)² + (θ̇ − y)², a polynomial of degree 14, is
    smallest at an end or at a real root of its derivative (:func:`real_roots`); ``scratch``
    (4 × 15) holds the polynomials."""
    sq, dsq, roots, u = scratch[0], scratch[1], scratch[2], scratch[3]
    sq[:] = 0.0
    for c in range(2):
        for p in range(_N):
            u[p] = C[i, c, p]
        u[0] += (shift - x) if c == 0 else -y
        for p in range(_N):
            for q in range(_N):
                sq[p + q] += u[p] * u[q]
    for p in range(_MAX_COEFFS - 1):
        dsq[p] = sq[p + 1] * (p + 1)
    dsq[_MAX_COEFFS - 1] = 0.0
    r = real_roots(dsq, _MAX_COEFFS - 1, roots)
    best, where = np.inf, 0.0
    for q in range(r + 2):
        t = 0.0 if q == r else (1.0 if q == r + 1 else roots[q])
        d = math.hypot(_horner(C[i, 0], _N, t) + shift - x, _horner(C[i, 1], _N, t) - y)
        if d < best:
            best, where = d, t
    return best, where


@cached_njit(nogil=True)
def nearest(C, shifts, x, y, best):
    """The nearest point of the pieces ``C``, each translated by every shifts[j] in θ, to
    (x, y), if nearer than ``best`` (a distance known to be reached, e.g. by a point of the
    curves; inf if none): (distance, θ, θ̇), (best, nan, nan) if none is nearer. Exact for
    the polynomials: on each piece that may come nearer (its range box), the squared
    distance, a polynomial of degree 14, is smallest at an end or at a root of its
    derivative (:func:`real_roots`)."""
    n = C.shape[0]
    box = np.empty((n, 2, 2))
    ranges(C, box)
    out_d, out_t, out_v = best, np.nan, np.nan
    # the pieces' ends first: a distance reached, which prunes the pieces below
    for j in range(shifts.size):
        for i in range(n):
            for c in range(2):
                end = 0.0
                for p in range(_N):
                    end += C[i, c, p]
                if c == 0:
                    th = end + shifts[j]
                else:
                    v = end
            d = math.hypot(th - x, v - y)
            if d < out_d:
                out_d, out_t, out_v = d, th, v
    scratch = np.empty((4, _MAX_COEFFS))
    for j in range(shifts.size):
        for i in range(n):
            gx = max(box[i, 0, 0] + shifts[j] - x, 0.0, x - box[i, 0, 1] - shifts[j])
            gy = max(box[i, 1, 0] - y, 0.0, y - box[i, 1, 1])
            if math.hypot(gx, gy) >= out_d:
                continue
            d, t = _project(C, i, shifts[j], x, y, scratch)
            if d < out_d:
                out_d = d
                out_t, out_v = _horner(C[i, 0], _N, t) + shifts[j], _horner(C[i, 1], _N, t)
    return out_d, out_t, out_v


# --------------------------------------------------------------------------- nearest pair

#: Samples per piece of :func:`nearest_between`'s first guess on a pair of pieces.
_PAIR_SAMPLES = 9
_PAIR_NEWTON = 12
_BLOCK = 8  # pieces of A whose common range box is tested first


@nb.njit(inline="always")
def _point_and_derivatives(C, i, x, out):
    """out = (θ, θ̇, θ', θ̇', θ'', θ̇'') of piece i at x (derivatives in x)."""
    for c in range(2):
        f, d, dd = 0.0, 0.0, 0.0
        for p in range(_N - 1, -1, -1):
            dd = dd * x + 2.0 * d
            d = d * x + f
            f = f * x + C[i, c, p]
        out[c], out[2 + c], out[4 + c] = f, d, dd


_GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))


@nb.njit
def _distance_along(A, i, s, B, k, shift, scratch):
    """The distance from A's piece i at s to B's piece k translated by ``shift``."""
    return _project(B, k, shift, _horner(A[i, 0], _N, s), _horner(A[i, 1], _N, s),
                    scratch)[0]


@nb.njit
def _pair_by_projection(A, i, B, k, shift, scratch):
    """(s, t): the nearest pair of piece i of A and piece k of B (translated by ``shift``)
    where Newton's method in (s, t) does not converge (nearly parallel pieces): the
    distance from A(s) to piece k (:func:`_project`, exact) minimised over s ∈ [0, 1] by
    golden section, to rounding (one minimum: pieces far shorter than their curvature
    radius)."""
    lo, hi = 0.0, 1.0
    x1, x2 = lo + _GOLDEN * (hi - lo), hi - _GOLDEN * (hi - lo)
    f1 = _distance_along(A, i, x1, B, k, shift, scratch)
    f2 = _distance_along(A, i, x2, B, k, shift, scratch)
    for _ in range(80):
        if hi - lo <= 4.0 * _EPS:
            break
        if f1 <= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = lo + _GOLDEN * (hi - lo)
            f1 = _distance_along(A, i, x1, B, k, shift, scratch)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = hi - _GOLDEN * (hi - lo)
            f2 = _distance_along(A, i, x2, B, k, shift, scratch)
    s = 0.5 * (lo + hi)
    return s, _project(B, k, shift, _horner(A[i, 0], _N, s), _horner(A[i, 1], _N, s),
                       scratch)[1]


@cached_njit(nogil=True)
def nearest_between(A, B, shifts, best):
    """The nearest pair of points of the pieces ``A`` and of the pieces ``B`` translated by
    every shifts[j] in θ, if nearer than ``best`` (inf: none known): (distance, θ_A, θ̇_A,
    θ_B, θ̇_B), (best, nan, nan, nan, nan) if none is nearer. Every pair of pieces whose range
    boxes may come nearer than the best found is sampled at 9 × 9 points, and the nearest
    sample pair refined by Newton's method on the squared distance |A(s) − B(t)|² in (s, t),
    kept in [0, 1]²; where Newton does not converge (nearly parallel pieces, an indefinite
    Hessian, a minimum on an edge of [0, 1]²), the exact distance from A(s) to the piece of
    B is minimised over s by golden section (:func:`_pair_by_projection`). Exact for the
    polynomials where a pair's distance has one minimum (pieces far shorter than their
    curvature radius, as DOP853 steps are)."""
    na, nb_ = A.shape[0], B.shape[0]
    box_a, box_b = np.empty((na, 2, 2)), np.empty((nb_, 2, 2))
    ranges(A, box_a)
    ranges(B, box_b)
    m = _PAIR_SAMPLES
    sa, sb = np.empty((na, m, 2)), np.empty((nb_, m, 2))
    for i in range(na):
        for q in range(m):
            for c in range(2):
                sa[i, q, c] = _horner(A[i, c], _N, q / (m - 1))
    # the longest gap between a piece's consecutive samples: every point of the piece lies
    # within (a little more than) half of it from a sample (B's: made with its samples)
    gap_a, gap_b = np.zeros(na), np.zeros(nb_)
    for i in range(na):
        for q in range(m - 1):
            gap_a[i] = max(gap_a[i], math.hypot(sa[i, q + 1, 0] - sa[i, q, 0],
                                                sa[i, q + 1, 1] - sa[i, q, 1]))
    sampled = np.zeros(nb_, np.bool_)  # B's samples are made when a piece is first near
    out = np.array([best, np.nan, np.nan, np.nan, np.nan])
    pa, pb = np.empty(6), np.empty(6)
    scratch = np.empty((4, _MAX_COEFFS))
    # the range boxes of blocks of _BLOCK consecutive pieces of A
    block = np.empty(((na + _BLOCK - 1) // _BLOCK, 2, 2))
    for b in range(block.shape[0]):
        for c in range(2):
            block[b, c, 0] = box_a[b * _BLOCK:(b + 1) * _BLOCK, c, 0].min()
            block[b, c, 1] = box_a[b * _BLOCK:(b + 1) * _BLOCK, c, 1].max()
    far = False
    # A's whole range, to keep only the pieces of B that may come nearer than the best
    a_lo_t, a_hi_t = box_a[:, 0, 0].min(), box_a[:, 0, 1].max()
    a_lo_v, a_hi_v = box_a[:, 1, 0].min(), box_a[:, 1, 1].max()
    near_k = np.empty(nb_ * shifts.size, np.int64)
    near_j = np.empty(nb_ * shifts.size, np.int64)
    for sweep in range(2):  # the sample pairs (a distance reached), then Newton
        count = 0
        for j in range(shifts.size):
            for k in range(nb_):
                gx = max(box_b[k, 0, 0] + shifts[j] - a_hi_t, 0.0,
                         a_lo_t - box_b[k, 0, 1] - shifts[j])
                gy = max(box_b[k, 1, 0] - a_hi_v, 0.0, a_lo_v - box_b[k, 1, 1])
                if gx * gx + gy * gy < out[0] * out[0]:
                    near_k[count], near_j[count] = k, j
                    count += 1
        for c in range(count):
            k, j = near_k[c], near_j[c]
            shift = shifts[j]
            if not sampled[k]:
                for q in range(m):
                    for d in range(2):
                        sb[k, q, d] = _horner(B[k, d], _N, q / (m - 1))
                for q in range(m - 1):
                    gap_b[k] = max(gap_b[k], math.hypot(sb[k, q + 1, 0] - sb[k, q, 0],
                                                        sb[k, q + 1, 1] - sb[k, q, 1]))
                sampled[k] = True
            for i in range(na):
                if i % _BLOCK == 0:  # a block of A's pieces at once: skip it if it is far
                    b = i // _BLOCK
                    gx = max(box_b[k, 0, 0] + shift - block[b, 0, 1], 0.0,
                             block[b, 0, 0] - box_b[k, 0, 1] - shift)
                    gy = max(box_b[k, 1, 0] - block[b, 1, 1], 0.0,
                             block[b, 1, 0] - box_b[k, 1, 1])
                    far = gx * gx + gy * gy >= out[0] * out[0]
                if far:
                    continue
                gx = max(box_b[k, 0, 0] + shift - box_a[i, 0, 1], 0.0,
                         box_a[i, 0, 0] - box_b[k, 0, 1] - shift)
                gy = max(box_b[k, 1, 0] - box_a[i, 1, 1], 0.0,
                         box_a[i, 1, 0] - box_b[k, 1, 1])
                if gx * gx + gy * gy >= out[0] * out[0]:
                    continue
                # the nearest sample pair
                d2, s0, t0 = np.inf, 0.0, 0.0
                for qa in range(m):
                    for qb in range(m):
                        dx = sa[i, qa, 0] - sb[k, qb, 0] - shift
                        dy = sa[i, qa, 1] - sb[k, qb, 1]
                        if dx * dx + dy * dy < d2:
                            d2, s0, t0 = dx * dx + dy * dy, qa / (m - 1), qb / (m - 1)
                if sweep == 0:  # a distance reached, to prune the second sweep
                    if math.sqrt(d2) < out[0]:
                        out[0] = math.sqrt(d2)
                        out[1], out[2] = _horner(A[i, 0], _N, s0), _horner(A[i, 1], _N, s0)
                        out[3] = _horner(B[k, 0], _N, t0) + shift
                        out[4] = _horner(B[k, 1], _N, t0)
                    continue
                if math.sqrt(d2) - 0.6 * (gap_a[i] + gap_b[k]) >= out[0]:
                    continue  # no point of this pair comes nearer than the best found
                # Newton in (s, t) from it
                s, t = s0, t0
                converged = False
                for _ in range(_PAIR_NEWTON):
                    _point_and_derivatives(A, i, s, pa)
                    _point_and_derivatives(B, k, t, pb)
                    rx, ry = pa[0] - pb[0] - shift, pa[1] - pb[1]
                    gs = rx * pa[2] + ry * pa[3]
                    gt = -(rx * pb[2] + ry * pb[3])
                    hss = pa[2] * pa[2] + pa[3] * pa[3] + rx * pa[4] + ry * pa[5]
                    htt = pb[2] * pb[2] + pb[3] * pb[3] - rx * pb[4] - ry * pb[5]
                    hst = -(pa[2] * pb[2] + pa[3] * pb[3])
                    det = hss * htt - hst * hst
                    if det <= 0.0 or hss <= 0.0:
                        break
                    s_raw = s - (htt * gs - hst * gt) / det
                    t_raw = t - (hss * gt - hst * gs) / det
                    s_new, t_new = min(max(s_raw, 0.0), 1.0), min(max(t_raw, 0.0), 1.0)
                    if s_new != s_raw or t_new != t_raw:
                        break  # the minimum is on an edge of [0, 1]²: minimise in s below
                    if abs(s_new - s) <= 1e-14 and abs(t_new - t) <= 1e-14:
                        converged = True
                    s, t = s_new, t_new
                    if converged:
                        break
                s1, t1 = s, t
                if not converged:  # the distance to piece k along A(s), minimised in s
                    s1, t1 = _pair_by_projection(A, i, B, k, shift, scratch)
                # the nearest of Newton's end, its start and the minimisation in s
                for s_end, t_end in ((s, t), (s0, t0), (s1, t1)):
                    a_t = _horner(A[i, 0], _N, s_end)
                    a_v = _horner(A[i, 1], _N, s_end)
                    b_t = _horner(B[k, 0], _N, t_end) + shift
                    b_v = _horner(B[k, 1], _N, t_end)
                    d = math.hypot(a_t - b_t, a_v - b_v)
                    if d < out[0]:
                        out[0], out[1], out[2], out[3], out[4] = d, a_t, a_v, b_t, b_v
    return out
