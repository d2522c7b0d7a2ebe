"""The compiled polygon areas (atlas.kernels.polygon) against independent references: exact
areas of shapes whose intersection with a box is known in closed form, and Sutherland–Hodgman
clipping vertex by vertex (the clipped polygon built, then the shoelace formula)."""

import math

import numpy as np
import pytest

from atlas.kernels.polygon import clip, window_areas


def _direct(x, y, shift, a, b, lo, hi):
    """Area of (x + shift, y) ∩ box by clipping four times and the shoelace formula."""
    px, py = clip(x + shift, y, 1, lo, True)
    px, py = clip(px, py, 1, hi, False)
    px, py = clip(px, py, 0, a, True)
    px, py = clip(px, py, 0, b, False)
    if px.size < 3:
        return 0.0
    return 0.5 * abs(float(np.dot(px, np.roll(py, -1)) - np.dot(np.roll(px, -1), py)))


def test_disc_in_a_box_exact():
    """A unit disc (fine polygon) centred at θ = 2πk against the box [−1/2, 1/2]²: the
    square is inside the disc, area 1 for the copy shifted onto it, 0 for the others; and
    against [0, 2] × [−2, 2], half the polygon's area."""
    t = np.linspace(0.0, 2 * math.pi, 20001)[:-1]
    x, y = np.cos(t) + 2 * math.pi, np.sin(t)
    polygon = 0.5 * 20000 * math.sin(2 * math.pi / 20000)
    out = np.empty(3)
    window_areas(x, y, np.array([-2 * math.pi, 0.0, -4 * math.pi]), -0.5, 0.5, -0.5, 0.5, out)
    assert out == pytest.approx([1.0, 0.0, 0.0], abs=1e-13)
    window_areas(x, y, np.array([-2 * math.pi]), 0.0, 2.0, -2.0, 2.0, out[:1])
    assert out[0] == pytest.approx(polygon / 2, rel=1e-13)


def test_folded_polygon_matches_direct_clipping():
    """A long, folded, spiralling polygon (like a tilted tongue) shifted by many multiples
    of 2π: the same areas as clipping it vertex by vertex, to rounding."""
    s = np.linspace(0.0, 30.0, 40001)
    upper = np.column_stack([s * 3.0 + np.sin(5 * s), 4 * np.cos(s) + 0.5])
    lower = np.column_stack([s * 3.0 + np.sin(5 * s) + 0.3, 4 * np.cos(s) - 0.5])[::-1]
    x, y = np.concatenate([upper[:, 0], lower[:, 0]]), np.concatenate([upper[:, 1], lower[:, 1]])
    shifts = -2 * math.pi * np.arange(-2, 16, dtype=float)
    a, b, lo, hi = -2.5, 2 * math.pi - 2.5, -3.0, 3.5
    out = np.empty(shifts.size)
    window_areas(x, y, shifts, a, b, lo, hi, out)
    ref = [_direct(x, y, sh, a, b, lo, hi) for sh in shifts]
    assert np.abs(out - ref).max() < 1e-11
    assert np.count_nonzero(np.array(ref) > 0.1) >= 10  # the copies do meet the box


def test_a_polygon_beside_the_box_has_no_area_there():
    """Copies wholly left or right of the box: exactly 0 (not the rounding of the
    telescoped sums), as clipping gives."""
    t = np.linspace(0.0, 2 * math.pi, 5001)[:-1]
    x, y = 0.7 * np.cos(t) + 0.123, 3.0 * np.sin(3 * t) * np.cos(t) + 0.31
    out = np.empty(4)
    window_areas(x, y, np.array([-10.0, 10.0, -100.0, 100.0]), -1.0, 1.0, -5.0, 5.0, out)
    assert np.all(out == 0.0)
