"""The Wada tests against answers known by hand: Attractors.jl's synthetic matrices for the
merging method (Daza, Wagemakers & Sanjuán, Sci. Rep. 8, 9954, 2018), and for the grid
method (Daza, Wagemakers, Sanjuán & Yorke, Sci. Rep. 5, 16579, 2015) labelling functions
whose boundaries are known: three sectors meeting at one point (not Wada), three bands
(not Wada), and stripes finer than the grid cycling through three labels (every boundary
segment meets all three)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.fractal import wada_grid, wada_merge
from atlas.fractal.wada import boundary_cells

FILL = -32768


def bands(labels_by_row, n=12):
    return np.array(labels_by_row)[:, None] * np.ones((1, n), int)


def test_merging_smooth_bands_as_attractors_jl():
    """Attractors.jl's wada_tests.jl: rows of 1 (4), 2 (4), 3 (4) in a 12 × 12 matrix. The
    boundary of "1 or not" is rows 4–5 (1-based), of "3 or not" rows 8–9: 4 rows apart; the
    24 cells of rows 8–9 lie beyond r = 1 and r = 2 of rows 4–5 (Attractors.jl: 12·2/12²
    of all the cells)."""
    m = wada_merge(bands([1] * 4 + [2] * 4 + [3] * 4), r=1)
    assert m.d_max == 4.0 and m.d_min == 4.0 and m.wada is False
    assert m.beyond * 24 == 24  # all 24 cells of one boundary, beyond the other's
    assert wada_merge(bands([1] * 4 + [2] * 4 + [3] * 4), r=2).beyond == 1.0


def test_merging_interleaved_bands_as_attractors_jl():
    """1 2 3 1 2 3 …: every merged picture's boundary is every row but one at an edge: the
    boundaries are one cell apart at most, nothing beyond r = 1 (Attractors.jl: 0.0)."""
    m = wada_merge(bands([1, 2, 3] * 4), r=1)
    assert m.d_max == 1.0 and m.beyond == 0.0 and m.wada is True


def test_merging_three_sectors_grows_with_the_picture():
    """Three 120° sectors of a disc of radius R cells: each merged boundary is two rays; the
    farthest point of one from another is the end of a ray, at R sin 60° ... R from it: the
    distance is of the order of the picture and doubles when the grid does."""
    def sectors(n):
        y, x = (np.mgrid[0:n, 0:n] - (n - 1) / 2) / n
        return (np.floor((np.arctan2(y, x) + math.pi) / (2 * math.pi / 3)) % 3).astype(int)

    small, large = wada_merge(sectors(100)), wada_merge(sectors(200))
    assert small.d_min > 20 and large.d_min == pytest.approx(2 * small.d_min, rel=0.05)


def test_unlabelled_cells_take_their_nearest_label_or_are_a_basin():
    labels = bands([1, 2, 3] * 4)
    holed = labels.copy()
    holed[5, 5] = FILL
    assert wada_merge(holed).d_max == wada_merge(labels).d_max
    assert len(wada_merge(holed, unlabelled="basin").basins) == 4


def test_boundary_cells_by_hand():
    """A 3 × 3 neighbourhood with another label makes a boundary cell; the fill is neither
    a label nor a boundary cell."""
    labels = np.zeros((5, 5), int)
    labels[2, 2] = 1
    expected = np.zeros((5, 5), bool)
    expected[1:4, 1:4] = True
    assert np.array_equal(boundary_cells(labels), expected)
    labels[2, 2] = FILL
    assert not boundary_cells(labels).any()


X = np.linspace(-1, 1, 41)
Y = np.linspace(-1, 1, 41)


def grid_of(label):
    return label(*np.meshgrid(X, Y))


def test_grid_method_three_sectors_are_not_wada():
    """Three sectors meeting at the origin: only the cells next to the junction see three
    labels; refinement along a segment between two sectors away from it finds no third.
    Boundary cells: 3 rays of about 20 cells, 2–3 cells wide; W_3: a handful of them."""
    def sector(x, y):
        return (np.floor((np.arctan2(y, x) + math.pi) / (2 * math.pi / 3)) % 3).astype(int)

    w = wada_grid(grid_of(sector), X, Y, sector, max_refinements=6)
    assert w.w[0] == 0.0 and w.w[2] < 0.1 and w.w[1] > 0.9
    assert w.history.shape == (7, 3) and w.refinements == 6
    assert np.all(np.diff(w.history[:, 2]) >= 0)


def test_grid_method_sees_stripes_finer_than_the_grid():
    """label = ⌊x/δ⌋ mod 3 with δ = h/9.5 (h: the grid's spacing): neighbouring grid points
    are 9 or 10 stripes apart, so the grid shows some neighbourhoods with two labels only;
    a segment of length h holds 9 stripes or more, so after 4 refinements (points h/16
    apart, closer than δ) every boundary cell has seen all three: W_3 = 1."""
    h = X[1] - X[0]

    def stripes(x, y):
        return (np.floor((x + 1) / (h / 9.5)) % 3).astype(int) + 0 * np.asarray(y, int)

    w = wada_grid(grid_of(stripes), X, Y, stripes, max_refinements=6)
    assert w.history[0, 2] < 0.9 and w.w[2] == 1.0 and w.refinements <= 4


def test_grid_method_ignores_unlabelled_points():
    """A callable that labels nothing beyond the grid points: the refinement adds no label
    and counts the points it could not label."""
    labels = grid_of(lambda x, y: (x > 0.01).astype(int) + (y > 0.01).astype(int))

    def none(x, y):
        return np.full(np.shape(x), FILL)

    w = wada_grid(labels, X, Y, none, max_refinements=2)
    assert w.n_unlabelled == w.n_labelled > 0
    assert np.array_equal(w.history[0], w.history[-1])


def test_grid_method_counts_a_basin_the_grid_does_not_show():
    """A thin basin 2 along x = 0.01, narrower than the grid's spacing, between basins 0
    and 1: the grid shows two labels; the refinement finds the third on every segment that
    crosses x = 0.01. With n_basins=3 W_3 counts them; with the grid's own count (two)
    every boundary cell is done before any refinement."""
    h = X[1] - X[0]

    def thin(x, y):
        x = np.asarray(x)
        return np.where(np.abs(x - 0.01) < h / 20, 2, (x > 0.01).astype(int)) \
            + 0 * np.asarray(y, int)

    labels = grid_of(thin)
    assert set(np.unique(labels)) == {0, 1}
    w = wada_grid(labels, X, Y, thin, n_basins=3, max_refinements=5)
    assert w.w[2] > 0.3 and w.history[0, 2] == 0.0
    two = wada_grid(labels, X, Y, thin, max_refinements=5)
    assert two.n_basins == 2 and two.refinements == 0 and two.w[1] == 1.0
    assert two.n_labelled == 0


def test_newton_basins_are_wada_by_both_methods():
    """Newton's method for z³ = 1: the three basins share one boundary, the Julia set
    (every point of it is a boundary point of each basin; Daza et al. 2015 list it among
    the Wada systems). On 300² of [−1, 1]², the grid method's W_3 grows with each
    refinement past 0.95 after 7 (0.59 on the grid alone); the merged boundaries lie within
    a few cells of each other (4.5), where three sectors of a disc are tens apart."""
    from tests.fractal.maps import newton_basins

    labels = newton_basins(300)
    axis = np.linspace(-1, 1, 300)

    def newton(x, y):  # rows are the real part, columns the imaginary one
        z = np.asarray(y) + 1j * np.asarray(x)
        with np.errstate(all="ignore"):
            for _ in range(100):
                z = z - (z ** 3 - 1) / (3 * z ** 2)
        return np.argmin(np.abs(z[..., None] - np.exp(2j * np.pi * np.arange(3) / 3)), -1)

    w = wada_grid(labels, axis, axis, newton, max_refinements=7)
    assert w.history[0, 2] < 0.7 and w.w[2] > 0.95
    assert np.all(np.diff(w.history[:, 2]) > 0)
    assert wada_merge(labels).d_max <= 6
