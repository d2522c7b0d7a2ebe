"""The uncertainty exponent (Grebogi, McDonald, Ott & Yorke, Phys. Lett. A 99, 415, 1983)
against references known without atlas.fractal: exact power laws, straight and circular
boundaries (α = 1), the undriven pendulum's smooth basins, and Attractors.jl's published
bounds for the Grebogi map and Newton's method (with its estimator recoded here as a loop)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.fractal import uncertainty_exponent, uncertainty_exponent_grid
from atlas.fractal.uncertainty import fit_exponent
from tests.fractal.maps import grebogi_basins, grebogi_label, newton_basins

FILL = -32768


def attractors_jl_alpha(labels, eps):
    """Attractors.jl's ``uncertainty_exponent`` as written there: per ε the ε-boxes from the
    first cell (remainder dropped) with more than one label, N_u; D from the least-squares
    line of log10 N_u against −log10 ε; α = 2 − D."""
    n_u = []
    for e in eps:
        count = 0
        for i in range(0, labels.shape[0] - labels.shape[0] % e, e):
            for j in range(0, labels.shape[1] - labels.shape[1] % e, e):
                count += len(np.unique(labels[i:i + e, j:j + e])) > 1
        n_u.append(count)
    d = np.polyfit(-np.log10(np.array(eps, float)), np.log10(n_u), 1)[0]
    return 2 - d


def test_an_exact_power_law_is_fitted_exactly():
    eps = np.geomspace(1e-4, 1e-1, 6)
    alpha, err, c, used = fit_exponent(eps, 3.0 * eps ** 0.7)
    assert alpha == pytest.approx(0.7, abs=1e-12) and c == pytest.approx(math.log(3.0))
    assert err < 1e-10 and used.all()
    alpha, _, _, used = fit_exponent(np.r_[1e-5, eps], np.r_[0.0, 3.0 * eps ** 0.7])
    assert alpha == pytest.approx(0.7) and not used[0]  # f = 0 has no logarithm


def test_a_straight_boundary_on_a_grid():
    """A line of slope 0.37 across 600² cells. A box of ε cells samples the plane at cell
    centres spanning ε − 1 spacings, so the line meets N_u = C (ε − 1)/ε² boxes: with ε in
    cells (Attractors.jl's scale) the slope of ln f is that of ln(ε − 1) against ln ε
    (about 1.2 here, not 1); with scale="span" it is 1."""
    y, x = np.mgrid[0:600, 0:600]
    line = (y > 0.37 * x + 3.3).astype(int)
    eps = range(2, 21)
    cells = uncertainty_exponent_grid(line, eps)
    expected = np.polyfit(np.log(eps), np.log(np.array(eps) - 1.0), 1)[0]
    assert cells.alpha == pytest.approx(expected, abs=0.03)
    span = uncertainty_exponent_grid(line, eps, scale="span")
    assert span.alpha == pytest.approx(1.0, abs=0.03) and span.dimension == 2 - span.alpha
    assert span.eps[0] == 1.0 and np.array_equal(span.f, cells.f)


def test_a_circle_from_a_callable_has_alpha_one():
    """The disc x² + y² < 0.5 in [−1, 1]²: the uncertain points are those within ε|cos|
    of the circle, f ∝ ε: α = 1 (200 000 points, ε from 1e-4 to 1e-2 of the window)."""
    u = uncertainty_exponent(lambda x, y: (x * x + y * y < 0.5).astype(int),
                             ((-1, 1), (-1, 1)), n_points=200_000, eps_range=(1e-4, 1e-2),
                             n_eps=5)
    assert u.alpha == pytest.approx(1.0, abs=3 * u.alpha_error + 0.02)
    assert (u.n_tested == 200_000).all() and u.fitted.all()


def test_unlabelled_points_are_not_counted():
    """A callable that gives no label (the fill) left of x = −0.5: those points and those
    whose perturbations land there are not tested; the rest is still a straight boundary."""
    def label(x, y):
        return np.where(x < -0.5, FILL, (y > 0.2 * x).astype(int))

    u = uncertainty_exponent(label, ((-1, 1), (-1, 1)), n_points=100_000,
                             eps_range=(1e-3, 1e-2), n_eps=4)
    assert (u.n_tested < 80_000).all() and (u.n_tested > 70_000).all()
    assert u.alpha == pytest.approx(1.0, abs=0.1)
    grid = np.where(np.arange(300)[None, :] < 50, FILL,
                    (np.arange(300)[:, None] > 0.3 * np.arange(300)[None, :]).astype(int))
    out = uncertainty_exponent_grid(grid, range(2, 16), unlabelled="exclude", scale="span")
    assert out.alpha == pytest.approx(1.0, abs=0.05)
    # as a basin, the fill's own edge (x = 50) is boundary too
    basin = uncertainty_exponent_grid(grid, range(2, 16), scale="span")
    assert (basin.n_uncertain >= out.n_uncertain).all()
    assert (basin.n_uncertain > out.n_uncertain).any()


def test_grebogi_map_matches_attractors_jl():
    """Attractors.jl's "original paper" test: the Grebogi map on 251² cells of
    [0, 2π] × [−0.5, 0.5], ε = 3 … 15 cells: 0.2 ≤ α ≤ 0.3 ("in the paper the value is
    roughly 0.2"). Attractors.jl's own estimator, recoded here, gives a value in those
    bounds on these basins too (so the basins are the test's); it fits N_u, and differs
    from this fit of f = N_u/N by the boxes that a remainder leaves out (0.22 against
    0.27 here)."""
    basins = grebogi_basins(251)
    u = uncertainty_exponent_grid(basins, range(3, 16))
    assert 0.2 <= u.alpha <= 0.3
    assert 0.2 <= attractors_jl_alpha(basins, range(3, 16)) <= 0.3


def test_grebogi_map_from_a_callable_near_the_published_value():
    """The same map labelled point by point (10 000 random points, ε = 1e-6 … 1e-2 of the
    window): α near Grebogi et al.'s 0.2 (their Fig. 2: D ≈ 1.8)."""
    u = uncertainty_exponent(grebogi_label, ((0, 2 * math.pi), (-0.5, 0.5)),
                             n_points=10_000, eps_range=(1e-6, 1e-2), n_eps=5)
    assert 0.15 <= u.alpha <= 0.25 and u.alpha_error < 0.02


def test_newton_map_matches_attractors_jl():
    """Attractors.jl's "Newton map" test: Newton's method for z³ = 1 on 300² cells of
    [−1, 1]², ε = 5 … 30 cells: 0.55 ≤ α ≤ 0.65 (published box-counting dimension 1.42)."""
    basins = newton_basins(300)
    u = uncertainty_exponent_grid(basins, range(5, 31))
    assert 0.55 <= u.alpha <= 0.65
    assert 0.55 <= attractors_jl_alpha(basins, range(5, 31)) <= 0.65  # 0.61 against 0.65
