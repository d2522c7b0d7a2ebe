"""A branch-free polynomial sin that Numba inlines and LLVM vectorises.

``math.sin`` is a scalar libm call that blocks vectorisation of the lane loops
(:mod:`atlas.kernels.lanes`). Here sin x is float arithmetic only: a Cody–Waite reduction by π
(Cody & Waite 1980; :func:`reduce_pi`), then an odd polynomial of degree 21 interpolating
(sin r − r)/r³ at Chebyshev nodes (Muller, *Elementary Functions*, 3rd ed., ch. 3–4;
:func:`sin_poly`). :func:`sin_cos_vers` gives sin, cos and 1 − cos from one reduction.

Accuracy (tests/kernels/test_fastsin.py, against ``numpy.sin``): |fast_sin(x) − sin x| ≤
``ERROR_BOUND`` = 1e-15 for |x| ≤ ``EXACT_RANGE`` = 2²⁰ (measured 5.6e-16); ``sin_poly`` within
the same bound for |r| ≤ ``POLY_RANGE`` = 2. NaN and ±inf give NaN.
Derivation and ranges: docs/design/kernels.md#fastsin.
"""

from __future__ import annotations

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels.rk4 import FASTMATH

#: Max abs error of fast_sin vs sin for |x| ≤ EXACT_RANGE (and of sin_poly on |r| ≤ POLY_RANGE).
ERROR_BOUND = 1e-15
EXACT_RANGE = 2.0**20
POLY_RANGE = 2.0

#: Fast-math flags for sin and for every kernel that inlines it: the kernels' FASTMATH without
#: 'reassoc', which lets LLVM refactor ((x − qP1) − qP2) − qP3 into x − q·fl(P1 + P2 + P3) and
#: so collapses the Cody–Waite reduction (the error then grows like |x|·4e-17). Inlining is at
#: Numba-IR level, so the *caller's* flags are the ones that apply.
SIN_FASTMATH = FASTMATH - {"reassoc"}

INV_PI = 0.3183098861837907
# π split for Cody–Waite: P1, P2 have 27 significant bits (q·P1, q·P2 exact for |q| < 2²⁶).
PI_1 = 3.141592651605606
PI_2 = 1.9841871479187034e-09
PI_3 = 1.1442377452219664e-17

# Q(s) ≈ (sin r − r)/r³ with s = r², degree 9 in r² so that r + r³Q(r²) has degree 21 and
# stays within 1 ulp-level on |r| ≤ 2 (room for the shared-reduction stage offsets). The
# coefficients interpolate Q at 10 Chebyshev nodes of s ∈ [0, 4].
_S1 = -0.16666666666666666
_S2 = 0.008333333333332407
_S3 = -0.0001984126984061516
_S4 = 2.755731905079675e-06
_S5 = -2.505208589490734e-08
_S6 = 1.6057424462445849e-10
_S7 = -7.579285380733132e-13
_S8 = 1.163299988373214e-15
_S9 = 2.0674854745012456e-16
_S10 = -1.1636878843346596e-17


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def reduce_pi(x):
    """Return (r, sign) with x = qπ + r, r ∈ [−π/2, π/2] (to one rounding), sign = (−1)^q."""
    q = np.floor(x * INV_PI + 0.5)
    r = ((x - q * PI_1) - q * PI_2) - q * PI_3
    half = 0.5 * q
    return r, 1.0 - 4.0 * (half - np.floor(half))


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def sin_poly(r):
    """sin r for |r| ≤ POLY_RANGE by the odd polynomial r + r³·Q(r²) (Horner in r²)."""
    s = r * r
    q = _S9 + s * _S10
    q = _S8 + s * q
    q = _S7 + s * q
    q = _S6 + s * q
    q = _S5 + s * q
    q = _S4 + s * q
    q = _S3 + s * q
    q = _S2 + s * q
    q = _S1 + s * q
    return r + (r * s) * q


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def fast_sin(x):
    """sin x [x in rad], branch-free and vectorisable; max abs error ERROR_BOUND for
    |x| ≤ EXACT_RANGE (module docstring). NaN/±inf → NaN."""
    r, sign = reduce_pi(x)
    return sign * sin_poly(r)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def sin_near(reduced, delta):
    """sin(x + δ) from ``reduced = reduce_pi(x)``, valid to ERROR_BOUND while
    |r + δ| ≤ POLY_RANGE, i.e. for every |δ| ≤ POLY_RANGE − π/2 ≈ 0.43 rad."""
    r, sign = reduced
    return sign * sin_poly(r + delta)


@nb.njit(inline="always", fastmath=SIN_FASTMATH)
def sin_cos_vers(x):
    """(sin x, cos x, 1 − cos x) [x in rad] from one Cody–Waite reduction x = qπ + r:
    sin x = ±sin r, cos x = ±(1 − 2 sin²(r/2)), and 1 − cos x = 2 sin²(r/2) for even q,
    2 − 2 sin²(r/2) for odd q (|r/2| ≤ π/4, so neither has cancellation). Branch-free
    (the parity choice is a select), max abs error ERROR_BOUND for |x| ≤ EXACT_RANGE."""
    r, sign = reduce_pi(x)
    h = sin_poly(0.5 * r)
    vers = 2.0 * (h * h)
    vers_x = vers if sign > 0.0 else 2.0 - vers
    return sign * sin_poly(r), sign * (1.0 - vers), vers_x
