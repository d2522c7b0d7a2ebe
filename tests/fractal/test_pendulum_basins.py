"""The measures on atlas's own basins: the undriven pendulum θ̈ + 0.2θ̇ + sin θ = 0, whose
basin boundaries are the smooth stable manifolds of the saddles (α = 1, D = 1, not fractal),
and the driven pendulum θ̈ + 0.2θ̇ + sin θ = 1.66 cos t, whose three basins are Wada
(Wagemakers, Daza & Sanjuán, DCDS-B 26, 2021, Fig. 2(a); Basins.jl's test of the grid
method on this case: W_3 ≥ 0.9 on 100 × 100 of [−π, π] × [−2, 4] after 5 refinements)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.fractal import (
    basin_entropy,
    fractal_test,
    uncertainty_exponent,
    uncertainty_exponent_grid,
    wada_grid,
    wada_merge,
)
from atlas.models.driven.points import stored_point
from tests.helpers import write_config

pytestmark = pytest.mark.slow  # runs atlas (compiled kernels; seconds once cached)

LN2 = math.log(2)
WINDOW = ((-math.pi, math.pi), (-2.0, 4.0))
CONFIG = """\
name: driven
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {amplitude: 1.66, frequency: 1.0}
grid:
  theta0: {start: -pi, stop: pi, num: 100}
  theta_dot0: {start: -2, stop: 4, num: 100}
integrator: {dt: pi/100, t_max: 600}
"""


@pytest.fixture(scope="module")
def driven(tmp_path_factory):
    """The 100 × 100 atlas of the Wada case (t_max 600 s), and its labelling as a callable
    ``label(θ0, θ̇0)`` (stored_point: the run's own rule, from its attractors)."""
    tmp = tmp_path_factory.mktemp("fractal")
    cfg = atlas.load_config(write_config(tmp / "wada.yaml", CONFIG))
    tree = atlas.run(cfg, output=None, quiet=True)
    ds = tree.to_dataset(inherit=False)
    params = atlas.layout.points(ds)[0]
    point = stored_point(atlas.layout.point_group(tree, "attractors", params), params, 600.0)
    return (ds["attractor"].values, ds["theta0"].values, ds["theta_dot0"].values,
            lambda x, v: point.label(x, v)[0])


def test_undriven_pendulum_boundaries_are_smooth():
    """The undriven pendulum's wells on 200² of [−π, π] × [−4, 4] (atlas.label): α = 1
    within 0.05 from the grid (scale "span"; 0.97) and from random points (0.99; ε up to
    0.1 of the window gives 0.95: neighbouring boundaries within ε); S_bb < ln 2 and Puy's
    test says smooth."""
    theta = np.linspace(-math.pi, math.pi, 200)
    theta_dot = np.linspace(-4, 4, 200)

    def label(x, v):
        return np.asarray(atlas.label(x, v, alpha=0.1, omega0=1.0).attractor)

    labels = label(theta[None, :], theta_dot[:, None])
    assert len(np.unique(labels)) >= 3
    grid = uncertainty_exponent_grid(labels, range(2, 16), scale="span")
    assert grid.alpha == pytest.approx(1.0, abs=0.05)
    points = uncertainty_exponent(label, ((-math.pi, math.pi), (-4, 4)), n_points=30_000,
                                  eps_range=(3e-4, 3e-2), n_eps=5)
    assert points.alpha == pytest.approx(1.0, abs=max(0.05, 3 * points.alpha_error))
    assert basin_entropy(labels, 5).sbb < LN2
    assert not fractal_test(labels, 5).fractal


def test_driven_pendulum_is_wada_by_the_grid_method(driven):
    """Basins.jl's test: W_3 ≥ 0.9 after 5 refinements, on the same grid; W_3 grows with
    each refinement and no boundary cell stays with one basin."""
    labels, theta, theta_dot, label = driven
    w = wada_grid(labels, theta, theta_dot, label, max_refinements=5)
    assert w.n_basins == 3 and w.w[2] >= 0.9 and w.w[0] == 0.0
    assert np.all(np.diff(w.history[:, 2]) > 0)


def test_driven_pendulum_is_wada_by_the_merging_method(driven):
    """The three merged boundaries lie within a few cells of each other (Basins.jl's test
    finds 2 to 6 grid spacings with its own boundary sets and Euclidean coordinates); three
    smooth bands on the same grid are tens of cells apart."""
    labels = driven[0]
    m = wada_merge(labels)
    assert m.d_max <= 6
    assert wada_merge(np.repeat(np.arange(3), [33, 33, 34])[:, None]
                      * np.ones((1, 100), int)).d_min >= 30


def test_driven_pendulum_boundary_is_fractal(driven):
    """S_bb > ln 2 (boxes of 5 and 10 cells; sufficient for a fractal boundary) and Puy's
    test; the uncertainty exponent from random points well below 1 (D well above 1)."""
    labels, _, _, label = driven
    for box in (5, 10):
        e = basin_entropy(labels, box, unlabelled="exclude")
        assert e.fractal and e.sbb > LN2 and e.n_basins == 3
    assert fractal_test(labels, 5).fractal
    u = uncertainty_exponent(label, WINDOW, n_points=2000, eps_range=(1e-6, 1e-2), n_eps=5)
    assert u.alpha < 0.5 and u.dimension > 1.5
