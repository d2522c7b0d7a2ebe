"""The compiled polyline queries (atlas.kernels.segments, through
atlas.boundaries.segments.Segments) against brute force: the distance to every segment, and
the parity of crossings counted segment by segment."""

import math

import numpy as np
import pytest

from atlas.boundaries.segments import Segments, segment_distance


def _runs(rng):
    """Three folded polylines (spirals and a wiggle), tags 3, 4, 5, short segments."""
    runs = []
    for tag, (cx, cy) in zip((3, 4, 5), ((0.0, 0.0), (2.0, 1.0), (-1.0, 2.5))):
        t = np.linspace(0.0, 6 * math.pi, 3000 + 500 * tag)
        r = 0.2 + 0.1 * t
        runs.append((cx + r * np.cos(t), cy + r * np.sin(t) + 0.01 * rng.standard_normal(t.size),
                     tag))
    return runs


def test_nearest_is_the_brute_force_minimum():
    rng = np.random.default_rng(4)
    runs = _runs(rng)
    seg = Segments(runs)
    px, py = rng.uniform(-4, 6, 700), rng.uniform(-3, 6, 700)
    px[:5], py[:5] = runs[0][0][100:105], runs[0][1][100:105]  # on vertices: distance 0
    dist, tag = seg.nearest(px, py)
    best = np.full(px.size, np.inf)
    best_tag = np.zeros(px.size, np.int64)
    for x, y, k in runs:
        d = segment_distance(px[:, None], py[:, None], x[None, :-1], y[None, :-1],
                             x[None, 1:], y[None, 1:]).min(axis=1)
        best_tag = np.where(d < best, k, best_tag)
        best = np.minimum(best, d)
    np.testing.assert_allclose(dist, best, rtol=4e-16, atol=0)  # sqrt of squares vs hypot
    unique = np.abs(dist - best) <= 4e-16 * best
    assert np.all(tag[unique & (best > 1e-9)] == best_tag[unique & (best > 1e-9)])
    assert np.all(dist[:5] == 0.0)


def test_empty_segments_are_infinitely_far():
    dist, tag = Segments([]).nearest(np.array([0.0]), np.array([1.0]))
    assert dist[0] == math.inf and tag[0] == 0


@pytest.mark.parametrize("bistable", [True, False])
def test_sides_are_the_parity_of_crossings(bistable):
    rng = np.random.default_rng(5)
    runs = _runs(rng)
    seg = Segments(runs)
    px = np.repeat(rng.uniform(-3, 5, 40), 30)  # columns of equal θ, as a grid's
    py = rng.uniform(-3, 5, px.size)
    flip = np.array([-np.inf, 0.5, -np.inf])  # tag 4 flipped left of θ = 0.5
    out = seg.sides(px, py, 3, 5, flip, bistable, 99)
    parity = np.zeros((px.size, 3), bool)
    parity[:, 1] = px < 0.5
    for x, y, k in runs:
        xl, xr = np.minimum(x[:-1], x[1:]), np.maximum(x[:-1], x[1:])
        lo_is_a = x[:-1] <= x[1:]
        yl, yr = np.where(lo_is_a, y[:-1], y[1:]), np.where(lo_is_a, y[1:], y[:-1])
        inside = (xl[None] <= px[:, None]) & (px[:, None] < xr[None]) & (xr > xl)[None]
        with np.errstate(divide="ignore", invalid="ignore"):
            yc = (yr - yl)[None] / (xr - xl)[None] * (px[:, None] - xl[None]) + yl[None]
        parity[:, k - 3] ^= (np.count_nonzero(inside & (yc > py[:, None]), axis=1) % 2) == 1
    if bistable:
        expect = np.where(parity.any(axis=1), 3 + 2 - np.argmax(parity[:, ::-1], axis=1), 99)
    else:
        expect = 3 + np.count_nonzero(~parity, axis=1)
    np.testing.assert_array_equal(out, expect)
    assert np.unique(out).size >= 2  # the points do fall on different sides
