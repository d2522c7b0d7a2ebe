"""Basin entropy (Daza et al., Sci. Rep. 6, 31416, 2016) and Puy et al.'s fractality test
(CNSNS 95, 105588, 2021) against values known without atlas.fractal: matrices whose box
entropies are computed by hand, a plain loop over boxes, and Attractors.jl's published
bounds for the Grebogi map."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from atlas.fractal import basin_entropy, fractal_test
from tests.fractal.maps import grebogi_basins

LN2 = math.log(2)
FILL = -32768


def h(*p):
    """−Σ p ln p."""
    return -sum(q * math.log(q) for q in p if q > 0)


def naive(labels, box, exclude=False):
    """S_b, S_bb, N, N_b by a loop over boxes and a Counter per box (the definition as
    written; unlabelled cells, the fill, one more basin or left out)."""
    total, n, nb = 0.0, 0, 0
    for i in range(0, labels.shape[0] - box + 1, box):
        for j in range(0, labels.shape[1] - box + 1, box):
            cells = [int(v) for v in labels[i:i + box, j:j + box].ravel()
                     if not (exclude and v == FILL)]
            if not cells:
                continue
            c = Counter(cells)
            s = h(*(k / len(cells) for k in c.values()))
            total, n, nb = total + s, n + 1, nb + (len(c) > 1)
    return total / n, (total / nb if nb else math.nan), n, nb


def test_stripes_of_width_one_give_ln2_in_every_box():
    """Columns alternating 0, 1 and boxes of 2 × 2: each box half and half, S_i = ln 2."""
    stripes = np.tile(np.arange(12) % 2, (12, 1))
    e = basin_entropy(stripes, 2)
    assert e.sb == pytest.approx(LN2, abs=1e-15) and e.sbb == pytest.approx(LN2, abs=1e-15)
    assert (e.n_boxes, e.n_boundary_boxes, e.n_basins) == (36, 36, 2)
    assert not e.fractal  # S_bb = ln 2 is not above it


def test_checkerboard_by_hand():
    """A checkerboard: boxes of 2 hold 2 + 2 (ln 2); boxes of 3 hold 5 + 4 (H(5/9, 4/9));
    boxes of 1 hold one label (0, and no boundary box: S_bb undefined)."""
    board = np.indices((12, 12)).sum(axis=0) % 2
    assert basin_entropy(board, 2).sb == pytest.approx(LN2, abs=1e-15)
    assert basin_entropy(board, 3).sb == pytest.approx(h(5 / 9, 4 / 9), abs=1e-15)
    one = basin_entropy(board, 1)
    assert one.sb == 0.0 and math.isnan(one.sbb) and one.n_boundary_boxes == 0


@pytest.mark.parametrize("n_labels", [2, 3, 5])
def test_iid_labels_approach_ln_n(n_labels):
    """N labels drawn independently and uniformly: every box is a boundary box, and the
    plug-in entropy of a box of n cells is ln N − (N − 1)/(2n) + O(n⁻²) (Miller 1955's
    bias), here 100 cells a box and 900 boxes."""
    labels = np.random.default_rng(1).integers(0, n_labels, (300, 300))
    e = basin_entropy(labels, 10)
    expected = math.log(n_labels) - (n_labels - 1) / 200
    assert e.sb == pytest.approx(expected, abs=0.004)
    assert e.sbb == e.sb and e.n_boundary_boxes == e.n_boxes == 900
    # a box of two labels has S_i ≤ ln 2: with two basins the ln 2 test never says fractal
    assert e.fractal == (n_labels > 2)


def test_unlabelled_cells_are_a_basin_or_left_out():
    """One box [[0, 0], [1, fill]]: as a basin, p = (1/2, 1/4, 1/4); left out, (2/3, 1/3);
    a box of fill only is not counted when left out. An explicit mask does the same."""
    m = np.array([[0, 0, FILL, FILL], [1, FILL, FILL, FILL]])
    basin = basin_entropy(m, 2)
    assert basin.sb == pytest.approx((h(.5, .25, .25) + 0) / 2)
    assert basin.n_boxes == 2 and basin.n_basins == 3
    out = basin_entropy(m, 2, unlabelled="exclude")
    assert out.sb == pytest.approx(h(2 / 3, 1 / 3)) and out.n_boxes == 1
    assert out.n_basins == 2
    masked = basin_entropy(np.where(m == FILL, 7, m), 2, unlabelled="exclude", mask=m == FILL)
    assert masked == out
    # negative labels are labels (the undriven pendulum's wells k < 0; Attractors.jl's -1)
    assert basin_entropy(np.where(m == FILL, -1, m), 2) == basin
    assert basin_entropy(m, 2, fill=None).n_basins == 3


@pytest.mark.parametrize("box", [3, 6])
def test_agrees_with_a_loop_over_boxes(box):
    """Random matrices of three labels in patches with scattered unlabelled cells, against
    the definition coded as a plain loop (both treatments of the fill)."""
    rng = np.random.default_rng(box)
    labels = np.kron(rng.integers(0, 3, (6, 6)), np.ones((5, 5), int))
    labels[rng.random(labels.shape) < 0.05] = FILL
    for exclude in (False, True):
        e = basin_entropy(labels, box, unlabelled="exclude" if exclude else "basin")
        sb, sbb, n, nb = naive(labels, box, exclude)
        assert (e.sb, e.sbb) == pytest.approx((sb, sbb), abs=1e-12)
        assert (e.n_boxes, e.n_boundary_boxes) == (n, nb)


def test_a_box_that_does_not_tile_the_matrix_is_refused_unless_trimmed():
    """As Attractors.jl (an ArgumentError there): 50 × 50 is not tiled by 7; trim=True drops
    the last row and column of cells."""
    labels = np.random.default_rng(0).integers(0, 2, (50, 50))
    with pytest.raises(ValueError, match="not tiled"):
        basin_entropy(labels, 7)
    assert basin_entropy(labels, 7, trim=True).n_boxes == 49
    assert basin_entropy(labels, 7, trim=True) == basin_entropy(labels[:49, :49], 7)


def test_straight_and_circular_boundaries_are_not_fractal():
    """A straight line and a circle between two basins: S_bb below ln 2 (a smooth boundary
    between two basins can reach ln 2 only where every boundary box is split evenly)."""
    y, x = np.mgrid[0:300, 0:300]
    for labels in ((y > 0.37 * x + 40.3).astype(int),
                   ((x - 151.3) ** 2 + (y - 148.6) ** 2 < 100 ** 2).astype(int)):
        e = basin_entropy(labels, 6)
        assert e.sbb < LN2 and not e.fractal and e.n_boundary_boxes > 50


def test_grebogi_map_matches_attractors_jl():
    """Attractors.jl's test (uncertainty_tests.jl, "Basin entropy and Fractal test"): the
    Grebogi map on a 300² grid of [0, 2π] × [−0.5, 0.5], boxes of 6: 0.40 ≤ S_b ≤ 0.42,
    0.60 ≤ S_bb ≤ 0.61; its fractal test with ε = 5 says fractal."""
    basins = grebogi_basins(300)
    e = basin_entropy(basins, 6)
    assert 0.40 <= e.sb <= 0.42 and 0.60 <= e.sbb <= 0.61
    assert fractal_test(basins, 5).fractal


def test_puy_test_calls_a_circle_smooth_at_the_published_value():
    """Puy et al. 2021: S_bb of a smooth boundary sampled by balls is 0.4395093 in two
    dimensions (small balls, fine grid), up to a bias below 0.224 ε^−1.006. A circle of
    radius 150 cells, balls of radius 20: within 3σ + bias of it, and called smooth."""
    y, x = np.mgrid[0:400, 0:400]
    circle = ((x - 200.3) ** 2 + (y - 190.7) ** 2 < 150 ** 2).astype(int)
    t = fractal_test(circle, 20, seed=0)
    assert not t.fractal
    assert abs(t.sbb - 0.4395093) <= 3 * t.sbb_error + t.bias
    assert t.n_balls == 1000


def test_puy_test_calls_the_henon_basin_smooth():
    """Attractors.jl's second case: the Hénon map (a = 1.4, b = 0.3) on [−2, 2]², 300²,
    bounded orbits against escapes, ε = 5: smooth."""
    g = np.linspace(-2, 2, 300)
    x, y = np.meshgrid(g, g, indexing="ij")
    with np.errstate(all="ignore"):
        for _ in range(100):
            x, y = 1 - 1.4 * x * x + y, 0.3 * x
    labels = np.where(np.isfinite(x) & (np.abs(x) < 10), 1, -1)
    assert not fractal_test(labels, 5).fractal
