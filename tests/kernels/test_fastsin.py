"""The polynomial sin of the lane kernel: error bound over the whole range it is documented
for, compiled with the kernels' fast-math flags, and NaN propagation."""

import math

import numba as nb
import numpy as np
import pytest

from atlas.kernels.fastsin import (
    ERROR_BOUND,
    EXACT_RANGE,
    POLY_RANGE,
    SIN_FASTMATH,
    fast_sin,
    reduce_pi,
    sin_cos_vers,
    sin_near,
    sin_poly,
)


# Loops compiled with the flags of the kernels that inline fast_sin, so the test measures the
# code the kernels run (inlining happens at Numba-IR level: the caller's flags apply).
@nb.njit(fastmath=SIN_FASTMATH)
def _fast_sin_all(x, out):
    for i in range(x.size):
        out[i] = fast_sin(x[i])


@nb.njit(fastmath=SIN_FASTMATH)
def _sin_poly_all(x, out):
    for i in range(x.size):
        out[i] = sin_poly(x[i])


@nb.njit(fastmath=SIN_FASTMATH)
def _sin_near_all(x, delta, out):
    for i in range(x.size):
        out[i] = sin_near(reduce_pi(x[i]), delta[i])


@nb.njit(fastmath=SIN_FASTMATH)
def _sin_cos_vers_all(x, out):
    for i in range(x.size):
        out[0, i], out[1, i], out[2, i] = sin_cos_vers(x[i])


def _max_error(f, x):
    out = np.empty_like(x)
    f(x, out)
    return np.max(np.abs(out - np.sin(x)))


def _near_multiples_of_half_pi(k_max, width=1e-6, n=21):
    k = np.arange(-k_max, k_max + 1)
    return np.add.outer(k * (math.pi / 2), np.linspace(-width, width, n)).ravel()


@pytest.mark.slow
@pytest.mark.parametrize("bound", [4.0 * math.pi, 100.0, 1e4, EXACT_RANGE])
def test_fast_sin_error_bound(bound):
    rng = np.random.default_rng(1)
    x = np.concatenate([
        np.linspace(-bound, bound, 1_000_001),
        rng.uniform(-bound, bound, 1_000_000),
        _near_multiples_of_half_pi(min(int(bound / (math.pi / 2)), 100_000)),
        [bound, -bound, 0.0, 1e-300, -1e-300, 5e-324],
    ])
    x = x[np.abs(x) <= bound]
    assert _max_error(_fast_sin_all, x) <= ERROR_BOUND


def test_fast_sin_is_odd_and_exact_at_zero():
    x = np.linspace(0.0, 50.0, 100_001)
    pos, neg = np.empty_like(x), np.empty_like(x)
    _fast_sin_all(x, pos)
    _fast_sin_all(-x, neg)
    np.testing.assert_array_equal(pos, -neg)
    assert pos[0] == 0.0


def test_polynomial_and_shared_reduction_bound():
    r = np.linspace(-POLY_RANGE, POLY_RANGE, 2_000_001)
    assert _max_error(_sin_poly_all, r) <= ERROR_BOUND
    # sin(x + δ) from one reduction of x, |δ| ≤ POLY_RANGE − π/2: the RK4 stage angles
    # multiples of 2⁻²⁰ below 2⁶ in magnitude, so that the reference argument x + δ is exact
    rng = np.random.default_rng(2)
    ulp = 2.0**-20
    x = rng.integers(-60 * 2**20, 60 * 2**20, 1_000_000) * ulp
    d_max = int((POLY_RANGE - math.pi / 2) * 2**20)
    delta = rng.integers(-d_max, d_max + 1, x.size) * ulp
    out = np.empty_like(x)
    _sin_near_all(x, delta, out)
    assert np.max(np.abs(out - np.sin(x + delta))) <= ERROR_BOUND


def test_nonfinite_gives_nan():
    x = np.array([np.nan, np.inf, -np.inf, -np.nan])
    out = np.zeros_like(x)
    _fast_sin_all(x, out)
    assert np.isnan(out).all()
    assert math.isnan(fast_sin(math.nan)) and math.isnan(fast_sin(math.inf))


@pytest.mark.parametrize("bound", [4.0 * math.pi, 1e4, EXACT_RANGE])
def test_sin_cos_vers_error_bound(bound):
    """sin x, cos x and 1 − cos x from one reduction, each within ERROR_BOUND (abs); the
    versine also relatively accurate near x = 0 (no cancellation: 2 sin²(x/2))."""
    rng = np.random.default_rng(3)
    x = np.concatenate([np.linspace(-bound, bound, 500_001), rng.uniform(-bound, bound, 500_000),
                        _near_multiples_of_half_pi(min(int(bound / (math.pi / 2)), 20_000))])
    x = x[np.abs(x) <= bound]
    out = np.empty((3, x.size))
    _sin_cos_vers_all(x, out)
    assert np.max(np.abs(out[0] - np.sin(x))) <= ERROR_BOUND
    assert np.max(np.abs(out[1] - np.cos(x))) <= ERROR_BOUND
    vers = 2.0 * np.sin(0.5 * x) ** 2
    assert np.max(np.abs(out[2] - vers)) <= 2 * ERROR_BOUND  # |1 − cos x| ≤ 2
    small = np.linspace(-1e-3, 1e-3, 20_001)
    out = np.empty((3, small.size))
    _sin_cos_vers_all(small, out)
    exact = 2.0 * np.sin(0.5 * small) ** 2
    assert np.max(np.abs(out[2] - exact) / np.maximum(exact, 1e-300)) < 1e-14
