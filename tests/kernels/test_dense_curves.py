"""The compiled curves of polynomial pieces (atlas.kernels.dense_curves) against independent
references: roots against numpy's eigenvalue roots, pieces against the DOP853 dense output
they expand, areas of a parabolic segment clipped to boxes in closed form, nearest points in
closed form."""

import math

import numpy as np
import pytest

from atlas.kernels.dense_curves import (
    from_dense,
    nearest,
    ranges,
    real_roots,
    reversed_pieces,
    segment,
    window_areas,
)
from atlas.kernels.dop853 import BAND, REVERSED, solve


def _roots(coeffs):
    c = np.zeros(15)
    c[:len(coeffs)] = coeffs
    out = np.empty(15)
    return out[:real_roots(c, len(coeffs), out)]


@pytest.mark.parametrize("seed", range(20))
def test_real_roots_are_numpys_in_the_unit_interval(seed):
    """Random polynomials of degree ≤ 14 with roots in and out of (0, 1), some 1e-6 apart:
    the same roots as numpy's companion-matrix roots, to 1e-9."""
    rng = np.random.default_rng(seed)
    inside = np.sort(rng.uniform(0.02, 0.98, rng.integers(0, 5)))
    if inside.size and seed % 3 == 0:
        inside = np.sort(np.append(inside, inside[0] + 1e-6))
    outside = rng.uniform(1.2, 3.0, rng.integers(0, 4)) * rng.choice([-1, 1])
    complex_pair = [0.5 + 0.3j, 0.5 - 0.3j] if seed % 2 else []
    coeffs = np.real(np.poly(np.concatenate([inside, outside, complex_pair])))[::-1]
    if coeffs.size > 15 or coeffs.size < 2:
        pytest.skip("degree out of range")
    found = _roots(coeffs)
    assert found.size == inside.size
    np.testing.assert_allclose(found, inside, atol=1e-9)


def test_a_tangency_or_no_root_gives_no_crossing():
    assert _roots([0.25, -1.0, 1.0]).size in (0, 1)  # (x − ½)², touching 0
    assert _roots([1.0, 0.0, 1.0]).size == 0
    assert _roots([0.0, 1.0]).size == 0  # the root 0 is not in the open interval


def test_pieces_are_the_dense_output():
    """Each step of a DOP853 solution as a piece: the same points as the dense output, the
    last piece ending at the event."""
    sol = solve(REVERSED, (0.05, 1.0, 0.5, 0.0), BAND, (-6.0, 6.0), [2.6, -1e-7], 1e3, 1e-12,
                (1e-12,), dim=2)
    span = np.ones(sol.h.size)
    span[-1] = (sol.t[-1] - sol.t_old[-1]) / sol.h[-1]
    pieces = np.empty((sol.h.size, 2, 8))
    from_dense(np.ascontiguousarray(sol.y_old), np.ascontiguousarray(sol.F[:, ::-1]), span,
               pieces)
    x = np.linspace(0.0, 1.0, 9)
    for i in range(0, sol.h.size, 7):
        tau = sol.t_old[i] + x * span[i] * sol.h[i]
        direct = sol.at(tau)[:2]
        mine = np.array([np.polyval(pieces[i, c, ::-1], x) for c in range(2)])
        assert np.all(np.abs(mine - direct) <= 1e-12 * (1 + np.abs(direct)))
    end = [np.polyval(pieces[-1, c, ::-1], 1.0) for c in range(2)]
    np.testing.assert_allclose(end, sol.y[-1, :2], atol=1e-12)


def _parabola_segment(reverse=False):
    """{x² ≤ y ≤ 1}: the parabola y = x² from (−1, 1) to (1, 1) as one piece, closed by the
    chord y = 1; area 4/3."""
    arc = np.zeros((1, 2, 8))
    arc[0, 0, :2] = (-1.0, 2.0)  # x = −1 + 2s
    arc[0, 1, :3] = (1.0, -4.0, 4.0)  # y = (−1 + 2s)²
    polygon = np.concatenate([arc, segment(1.0, 1.0, -1.0, 1.0)])
    return reversed_pieces(polygon) if reverse else polygon


def _clipped_parabola(a, b, lo, hi):
    """Area of {x² ≤ y ≤ 1} ∩ [a, b] × [lo, hi] by quadrature of the closed form."""
    x = np.linspace(max(a, -1.0), min(b, 1.0), 200001)
    height = np.clip(np.minimum(1.0, hi) - np.maximum(x * x, lo), 0.0, None)
    return float(np.sum(0.5 * (height[1:] + height[:-1]) * np.diff(x)))


@pytest.mark.parametrize("reverse", [False, True])
def test_parabolic_segment_clipped_to_boxes(reverse):
    """A box the parabola crosses twice within its single piece (y = 0.25 at x = ±½), a box
    it meets on one side, the whole segment, translates by 2π, and a box beside it."""
    polygon = _parabola_segment(reverse)
    two_pi = 2 * math.pi
    shifts = np.array([0.0, two_pi, -two_pi])
    out = np.empty(3)
    # the box [−0.5, 2] × [0.25, 0.81]: 0.56 + ∫_{0.5}^{0.9} (0.81 − x²) dx
    exact = 0.56 + 0.81 * 0.4 - (0.9**3 - 0.5**3) / 3
    window_areas(polygon, shifts, -0.5, 2.0, 0.25, 0.81, out)
    assert out[0] == pytest.approx(exact, abs=1e-14)
    assert out[1] == 0.0 and out[2] == 0.0
    window_areas(polygon, shifts, -0.5 + two_pi, 2.0 + two_pi, 0.25, 0.81, out)
    assert out[1] == pytest.approx(exact, abs=1e-13)
    window_areas(polygon, shifts, -3.0, 3.0, -1.0, 2.0, out)
    assert out[0] == pytest.approx(4.0 / 3.0, abs=1e-14)
    for box in [(-0.9, 0.3, 0.1, 0.95), (0.2, 0.7, 0.0, 0.3), (-1.0, 1.0, 0.5, 0.5001)]:
        window_areas(polygon, shifts[:1], *box, out[:1])
        assert out[0] == pytest.approx(_clipped_parabola(*box), abs=1e-9), box


def test_ranges_hold_the_curve():
    rng = np.random.default_rng(3)
    pieces = rng.normal(size=(10, 2, 8))
    box = np.empty((10, 2, 2))
    ranges(pieces, box)
    x = np.linspace(0.0, 1.0, 1001)
    for i in range(10):
        for c in range(2):
            y = np.polyval(pieces[i, c, ::-1], x)
            assert box[i, c, 0] <= y.min() + 1e-12 and y.max() <= box[i, c, 1] + 1e-12


def test_nearest_point_of_a_parabola():
    """From (0, 1), the nearest point of y = x² is at x² = ½, distance √¾; from a translate
    by 2π the same; a bound below it finds nothing."""
    polygon = _parabola_segment()[:1]
    d, x, y = nearest(polygon, np.array([0.0]), 0.0, 1.0, math.inf)
    assert d == pytest.approx(math.sqrt(0.75), abs=1e-14)
    assert abs(x) == pytest.approx(math.sqrt(0.5), abs=1e-7) and y == pytest.approx(0.5,
                                                                                    abs=1e-7)
    d2, x2, _ = nearest(polygon, np.array([-2 * math.pi, 2 * math.pi]), 2 * math.pi, 1.0,
                        math.inf)
    assert d2 == pytest.approx(d, abs=1e-13) and abs(x2 - 2 * math.pi) == pytest.approx(
        abs(x), abs=1e-7)
    d3, x3, _ = nearest(polygon, np.array([0.0]), 0.0, 1.0, 0.5)
    assert d3 == 0.5 and math.isnan(x3)
    # an end point is the nearest: from (3, 1) the end (1, 1)
    d4, x4, y4 = nearest(polygon, np.array([0.0]), 3.0, 1.0, math.inf)
    assert (d4, x4, y4) == pytest.approx((2.0, 1.0, 1.0), abs=1e-14)
