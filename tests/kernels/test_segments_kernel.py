"""The compiled polylines (atlas.kernels.segments, through
atlas.boundaries.segments.Segments) against brute force: the distance to every segment, the
parity of crossings counted segment by segment (for points by columns and scattered), and the
refinement of a dense output into a polyline against its own tolerances and against the
breadth-first numpy loop it replaced (the same doubles)."""

import math

import numpy as np
import pytest

from atlas.boundaries.segments import Segments, segment_distance
from atlas.kernels import segments as kernel


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
    best, best_tag = _brute_nearest(runs, px, py)
    np.testing.assert_allclose(dist, best, rtol=4e-16, atol=0)  # sqrt of squares vs hypot
    unique = np.abs(dist - best) <= 4e-16 * best
    assert np.all(tag[unique & (best > 1e-9)] == best_tag[unique & (best > 1e-9)])
    assert np.all(dist[:5] == 0.0)


def _brute_nearest(runs, px, py):
    """(distance, tag) of the nearest segment, over every segment of every run."""
    best = np.full(px.size, np.inf)
    best_tag = np.zeros(px.size, np.int64)
    for x, y, k in runs:
        d = segment_distance(px[:, None], py[:, None], x[None, :-1], y[None, :-1],
                             x[None, 1:], y[None, 1:]).min(axis=1)
        best_tag = np.where(d < best, k, best_tag)
        best = np.minimum(best, d)
    return best, best_tag


def test_nearest_does_not_depend_on_the_order_of_the_points():
    """Each search starts from the previous point's nearest leaf (a bound only): a grid's
    points row by row (neighbours: tight bounds, several parallel tasks of _CHUNK points)
    and shuffled (loose bounds) get the same doubles and tags, the brute-force minimum."""
    rng = np.random.default_rng(9)
    runs = _runs(rng)
    seg = Segments(runs)
    px, py = (g.ravel() for g in np.meshgrid(np.linspace(-4, 6, 40), np.linspace(-3, 6, 30)))
    assert px.size > 4 * kernel._CHUNK
    dist, tag = seg.nearest(px, py)
    shuffled = rng.permutation(px.size)
    dist_s, tag_s = seg.nearest(px[shuffled], py[shuffled])
    np.testing.assert_array_equal(dist_s, dist[shuffled])
    np.testing.assert_array_equal(tag_s, tag[shuffled])
    best, best_tag = _brute_nearest(runs, px, py)
    np.testing.assert_allclose(dist, best, rtol=4e-16, atol=0)
    np.testing.assert_array_equal(tag, best_tag)


def _search(seg, px, py, dist2, tag, searched=(np.inf, -np.inf)):
    """The chords' search (every segment a straight piece, no slack), from bounds."""
    n, none = seg.ax.size, np.zeros(0)
    kernel.nearer_curves(px, py, seg.ax, seg.ay, seg.bx, seg.by, seg.tag, seg.xlo, seg.xhi,
                         seg.ylo, seg.yhi, seg.start, *searched, 0.0, np.full(n, -1, np.int64),
                         np.zeros((n, 2)), np.zeros(n), np.zeros((1, 7, 2)), np.zeros((1, 2)),
                         dist2, tag, none, none)


def test_nearer_segments_continue_a_search_of_fewer_segments():
    """A search of the segments with a vertex in θ ∈ [a, b], continued on all of them from
    its squared distances and skipping the boxes within [a, b] (less the longest segment),
    gives the doubles and tags of one search of all: for points whose nearest segment lies
    beyond [a, b] as well as within. Without the bounds, the skipped boxes are missed."""
    rng = np.random.default_rng(10)
    runs = _runs(rng)
    a, b = -0.5, 1.5
    fewer = []
    for x, y, k in runs:  # the runs of vertices in [a, b], one vertex beyond either end
        inside = np.flatnonzero((x >= a) & (x <= b))
        cut = np.flatnonzero(np.diff(inside) > 1)
        for part in np.split(inside, cut + 1):
            lo, hi = max(part[0] - 1, 0), min(part[-1] + 2, x.size)
            fewer.append((x[lo:hi], y[lo:hi], k))
    seg, part = Segments(runs), Segments(fewer)
    longest = max(np.hypot(np.diff(x), np.diff(y)).max() for x, y, _ in runs)
    px, py = rng.uniform(-4, 6, 2000), rng.uniform(-3, 6, 2000)
    dist, tag = seg.nearest(px, py)
    dist2, near = np.full(px.size, np.inf), np.zeros(px.size, np.int64)
    _search(part, px, py, dist2, near)
    beyond = np.sqrt(dist2) > dist  # nearest segment not among the fewer
    assert 100 < beyond.sum() < px.size - 100
    searched = (a + longest, b - longest)
    _search(seg, px, py, dist2, near, searched)
    np.testing.assert_array_equal(np.sqrt(dist2), dist)
    np.testing.assert_array_equal(near, tag)
    unbounded, unbounded_tag = np.full(px.size, np.inf), np.zeros(px.size, np.int64)
    _search(seg, px, py, unbounded, unbounded_tag, searched)
    assert np.all(unbounded >= dist2) and np.any(unbounded > dist2)


def test_a_bound_no_segment_beats_is_kept():
    rng = np.random.default_rng(11)
    seg = Segments(_runs(rng))
    px, py = rng.uniform(-4, 6, 600), rng.uniform(-3, 6, 600)
    dist, tag = seg.nearest(px, py)
    dist2 = np.where(np.arange(px.size) % 2 == 0, 0.25 * dist**2, np.inf)
    near = np.full(px.size, 77)
    _search(seg, px, py, dist2, near)
    kept = np.arange(px.size) % 2 == 0
    np.testing.assert_array_equal(dist2[kept], 0.25 * dist[kept] ** 2)
    assert np.all(near[kept] == 77)
    np.testing.assert_array_equal(np.sqrt(dist2[~kept]), dist[~kept])
    np.testing.assert_array_equal(near[~kept], tag[~kept])


def test_empty_segments_are_infinitely_far():
    dist, tag = Segments([]).nearest(np.array([0.0]), np.array([1.0]))
    assert dist[0] == math.inf and tag[0] == 0


@pytest.mark.parametrize("bistable", [True, False])
@pytest.mark.parametrize("per_column", [100, 30, 1])
def test_sides_are_the_parity_of_crossings(bistable, per_column):
    """Columns of equal θ as a grid's (100 a column: taken column by column), fewer (30:
    swept) and scattered points (1: swept): the parity of the crossings above each."""
    rng = np.random.default_rng(5)
    runs = _runs(rng)
    seg = Segments(runs)
    px = np.repeat(rng.uniform(-3, 5, 1200 // per_column), per_column)
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


@pytest.mark.parametrize("bistable", [True, False])
def test_both_sweeps_give_the_same_sides(bistable):
    """Column by column and swept give the same side to every point, whatever the layout
    (ray_sides picks one by the points a column)."""
    rng = np.random.default_rng(8)
    seg = Segments(_runs(rng))
    flip = np.array([0.0, -np.inf, 1.5])
    for px in (rng.uniform(-3, 5, 900), np.repeat(rng.uniform(-3, 5, 9), 100),
               np.zeros(5), np.array([seg.ax[7]])):  # scattered, a grid, one column, a vertex
        py = rng.uniform(-3, 5, px.size)
        order = np.argsort(px)
        sides = []
        for sweep in (kernel._column_sides, kernel._swept_sides):
            out = np.empty(px.size, np.int64)
            sweep(order, px, py, seg.ax, seg.ay, seg.bx, seg.by, seg.tag, seg.xlo, seg.xhi,
                  seg.start, 3, 5, flip, bistable, 99, out)
            sides.append(out)
        np.testing.assert_array_equal(sides[0], sides[1])
        np.testing.assert_array_equal(seg.sides(px, py, 3, 5, flip, bistable, 99), sides[0])


# --------------------------------------------------------------------------- refine

@pytest.fixture(scope="module")
def branch():
    """The dense output of a stable branch of the bSTAB pendulum's saddle (DOP853)."""
    from atlas.boundaries.branches import integrate_branch as _branch
    from atlas.physics.pendulum import Pendulum

    dense, sol, _ = _branch(Pendulum(0.05, 1.0, 0.5), -1, 1e-13, -12.0, 12.0)
    return dense, sol.t


def _breadth_first(dense, t, tol, longest):
    """The refinement as numpy did it before it was compiled: a generation of chords at a
    time, every chord still unmeasured measured at once, cut, its new vertices evaluated."""
    y = dense(t)
    dev = np.full(t.size - 1, np.nan)
    for _ in range(kernel.MAX_GENERATIONS + 1):
        todo = np.flatnonzero(np.isnan(dev))
        if todo.size == 0:
            return t, y, float(dev.max(initial=0.0))
        mid = dense(0.5 * (t[todo] + t[todo + 1]))
        (ax, ay), (bx, by) = y[:, todo], y[:, todo + 1]
        worst = segment_distance(mid[0], mid[1], ax, ay, bx, by)
        pieces = np.ones(dev.size, np.int64)
        pieces[todo] = np.maximum(np.ceil(np.sqrt(worst / tol) * 1.2),
                                  np.ceil(np.hypot(bx - ax, by - ay) / longest))
        whole = pieces[todo] == 1
        dev[todo[whole]] = worst[whole]
        offset = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        t = np.append(np.repeat(t[:-1], pieces)
                      + offset * np.repeat(np.diff(t) / pieces, pieces), t[-1])
        new = np.append(offset > 0, False)
        grown = np.empty((2, t.size))
        grown[:, ~new] = y
        grown[:, new] = dense(t[new])
        y = grown
        dev = np.where(np.repeat(pieces, pieces) == 1, np.repeat(dev, pieces), np.nan)
    raise AssertionError("the generations ran out")


def _refine(dense, t, tol, longest):
    return kernel.refine(t, dense.t, dense.t_old, dense.h, np.ascontiguousarray(dense.y_old),
                         dense.F, tol, longest)


@pytest.mark.parametrize("tol, longest", [(1e-8, 0.004), (1e-6, 0.05), (1e-10, 1.0)])
def test_refine_meets_its_tolerances(branch, tol, longest):
    """Every chord within ``tol`` of the dense output at its middle time and no longer than
    ``longest``; the vertices are the dense output at the times (bit for bit), which hold
    the given ones; the error returned is the largest chord distance."""
    dense, steps = branch
    times, xy, error, ok = _refine(dense, steps, tol, longest)
    assert ok and times.size > 2 * steps.size
    np.testing.assert_array_equal(xy, dense(times))
    assert np.all(np.diff(times) > 0) and np.isin(steps, times).all()
    mid = dense(0.5 * (times[:-1] + times[1:]))
    chord = segment_distance(mid[0], mid[1], xy[0, :-1], xy[1, :-1], xy[0, 1:], xy[1, 1:])
    assert error == chord.max() <= tol
    assert np.hypot(*np.diff(xy, axis=1)).max() <= longest
    assert chord.max() > 0.1 * tol  # not refined far beyond the tolerance either


@pytest.mark.parametrize("tol, longest", [(1e-8, 0.004), (1e-6, 0.05)])
def test_refine_is_the_breadth_first_refinement(branch, tol, longest):
    """Depth first, chord by chord, the same vertices as a generation at a time."""
    dense, steps = branch
    times, xy, error, ok = _refine(dense, steps, tol, longest)
    old_times, old_xy, old_error = _breadth_first(dense, steps, tol, longest)
    assert ok and error == old_error
    np.testing.assert_array_equal(times, old_times)
    np.testing.assert_array_equal(xy, old_xy)


# --------------------------------------------------------------------------- curves

def test_dense_jet_is_the_dense_output_and_its_derivatives(branch):
    """The jet's value is the dense output's (the same doubles); its two derivatives in x
    agree with central differences of the dense output's own polynomial (to their
    truncation, h² of the next derivatives)."""
    import numba

    from atlas.kernels.dop853 import dense_component

    dense, _ = branch
    component = numba.njit(lambda F, step, c, x, y_old: dense_component(F, step, c, x, y_old))
    jet = numba.njit(lambda F, step, c, x: kernel._dense_jet(F, step, c, x))
    rng = np.random.default_rng(3)
    h = 1e-4
    for step in rng.integers(0, dense.h.size, 20):
        for c in (0, 1):
            x = float(rng.uniform(0.1, 0.9))
            value, first, second = jet(dense.F, step, c, x)
            assert value + dense.y_old[step, c] == component(dense.F, step, c, x, dense.y_old)
            at = [component(dense.F, step, c, x + d * h, dense.y_old) for d in (-1, 0, 1)]
            scale = max(abs(first), abs(second), 1e-3)
            assert abs(first - (at[2] - at[0]) / (2 * h)) < 1e-6 * scale
            assert abs(second - (at[2] - 2 * at[1] + at[0]) / h**2) < 1e-4 * scale


def test_the_foot_of_a_straight_piece_is_its_nearest_point():
    """Every segment a straight piece and no slack: each point's foot is the chord's nearest
    point, at the distance found, which is the brute-force minimum over the chords."""
    rng = np.random.default_rng(9)
    t = np.cumsum(rng.uniform(0.001, 0.01, 400))
    runs = [(t, np.sin(3 * t), 2), (t + 0.5, np.cos(2 * t), 5)]
    seg = Segments(runs)
    px, py = rng.uniform(0, 3, 300), rng.uniform(-1, 1, 300)
    d2, tag = np.full(300, np.inf), np.zeros(300, np.int64)
    fx, fy = np.full(300, np.nan), np.full(300, np.nan)
    n = seg.ax.size
    kernel.nearer_curves(px, py, seg.ax, seg.ay, seg.bx, seg.by, seg.tag, seg.xlo, seg.xhi,
                         seg.ylo, seg.yhi, seg.start, np.inf, -np.inf, 0.0,
                         np.full(n, -1, np.int64), np.zeros((n, 2)), np.zeros(n),
                         np.zeros((1, 7, 2)), np.zeros((1, 2)), d2, tag, fx, fy)
    best, best_tag = _brute_nearest(runs, px, py)
    np.testing.assert_allclose(np.sqrt(d2), best, rtol=4e-16, atol=0)
    np.testing.assert_array_equal(tag, best_tag)
    np.testing.assert_allclose(np.hypot(fx - px, fy - py), np.sqrt(d2), rtol=1e-12)


def test_walk_keeps_its_chords_within_the_spacing_and_curvature(branch):
    """The walked vertices run from the first time to the last, each chord at most the
    spacing and at most spacing/√κ (κ the orbit's curvature at its start, from the vector
    field), and a budget of vertices too small says so."""
    from atlas.physics.pendulum import Pendulum

    dense, steps = branch
    p = Pendulum(0.05, 1.0, 0.5)
    spacing = 0.05
    args = (dense.t, dense.t_old, dense.h, dense.y_old, dense.F, 0.0, float(steps[-1]),
            spacing, p.alpha, p.omega0, p.torque, np.zeros((0, 4)), np.inf, 0.9, 0.3)
    times, ok = kernel.walk(*args, 10**6)
    assert ok and times[0] == 0.0 and times[-1] == steps[-1] and np.all(np.diff(times) > 0)
    x, v = dense(times)
    chord = np.hypot(np.diff(x), np.diff(v))
    (f0, f1), (g0, g1) = p.field_jet(x[:-1], v[:-1])
    kappa = np.abs(f0 * g1 - f1 * g0) / np.hypot(f0, f1) ** 3
    assert np.all(chord <= spacing * (1 + 1e-12))
    assert np.all(chord <= spacing / np.sqrt(kappa) * (1 + 1e-9))
    assert chord.max() > 0.5 * spacing  # and not far below it
    _, ok = kernel.walk(*args, 10)
    assert not ok


def test_the_pruned_curve_search_is_the_wide_one():
    """A leaf measures only the arcs that may be the nearest (the nearest chord + slack bounds
    them): the same distances, nearest curves and feet as a search that measures every arc
    within half a radian of the best (slack 0.5), over the swing window's boundaries at
    τ = 0.5, half the points within 1e-3 of a vertex (where neighbouring arcs compete)."""
    import math

    from atlas.boundaries.tilted import TiltedBoundaries
    from atlas.kernels.segments import nearer_curves
    from atlas.physics.pendulum import Pendulum

    p = Pendulum(0.05, 1.0, 0.5)
    tb = TiltedBoundaries(p, (-math.pi + p.rest_angle, math.pi + p.rest_angle), (-10.0, 10.0))
    index = tb._index(-4.0, 4.0)
    F, y_old, _ = tb.fundamental.packed
    rng = np.random.default_rng(7)
    n = 20_000
    px, py = rng.uniform(-2.5, 2.5, n), rng.uniform(-3.0, 3.0, n)
    near = rng.integers(index.ax.size, size=n // 2)
    px[: n // 2] = index.ax[near] + rng.normal(0.0, 1e-3, n // 2)
    py[: n // 2] = index.ay[near] + rng.normal(0.0, 1e-3, n // 2)

    def search(slack):
        d2, k = np.full(n, np.inf), np.zeros(n, np.int64)
        fx, fy = np.full(n, np.nan), np.full(n, np.nan)
        nearer_curves(px, py, index.ax, index.ay, index.bx, index.by, index.tag, index.xlo,
                      index.xhi, index.ylo, index.yhi, index.start, math.inf, -math.inf,
                      slack, index.step, index.span, index.shift, F, y_old, d2, k, fx, fy)
        return d2, k, fx, fy

    for pruned, wide in zip(search(tb._slack), search(0.5)):
        np.testing.assert_array_equal(pruned, wide)
