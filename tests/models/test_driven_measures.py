"""The fractal measures ``atlas run`` stores for a driven pendulum's atlas
(:mod:`atlas.models.driven.measures`): each equal to :mod:`atlas.fractal` applied anew to the
stored map and to the file's own labelling (the plumbing: tiles' rows assembled in order,
the right labeller, the right window), the published facts of θ̈ + 0.2θ̇ + sin θ =
1.66 cos t (a fractal boundary, three Wada basins: Wagemakers, Daza & Sanjuán, DCDS-B 26,
2021), and what ``atlas info`` and ``atlas plot`` make of them."""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.cli import main
from atlas.fractal import basin_entropy, uncertainty_exponent, wada_merge
from atlas.layout import point_group, points
from atlas.models.driven import measures
from atlas.models.driven.points import stored_point
from tests.helpers import write_config

CONFIG = """\
name: measured
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {{amplitude: 1.66, frequency: 1.0}}
grid:
  theta0: {{start: -pi, stop: pi, num: 60}}
  theta_dot0: {{start: -2, stop: 4, num: 60}}
integrator: {{dt: pi/100, t_max: 600}}
execution: {{tile_orbits: 700}}
output: {output}
"""


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("measured")
    cfg = atlas.load_config(write_config(tmp / "m.yaml", CONFIG.format(output=tmp / "m.h5")))
    atlas.run(cfg, quiet=True)
    return tmp / "m.h5"


def test_the_stored_measures_are_the_fractal_modules_on_the_stored_map(measured):
    """Entropy and the merging method recomputed from the map read back (tiles of 11 rows:
    assembled in order), the uncertainty exponent from the file's own labelling, rebuilt
    (the same seeded points): equal to what the run stored."""
    tree = atlas.open(measured)
    ds = tree.to_dataset(inherit=False)
    labels = ds["attractor"].values
    entropy = basin_entropy(labels, measures.BOX, trim=True, fill=-32768, unlabelled="exclude")
    assert float(ds["basin_entropy"]) == entropy.sb
    assert float(ds["boundary_basin_entropy"]) == entropy.sbb
    assert float(ds["wada_merge_distance_max"]) == wada_merge(labels, fill=-32768).d_max
    params = points(ds)[0]
    point = stored_point(point_group(tree, "attractors", params), params,
                         float(ds.attrs["t_max"]))
    window = ((-math.pi, math.pi), (-2.0, 4.0))
    again = uncertainty_exponent(lambda x, y: point.label(x, y)[0], window,
                                 measures.EPSILONS, n_points=measures.UNCERTAIN_POINTS,
                                 seed=measures.SEED, fill=-32768)
    np.testing.assert_array_equal(ds["uncertain_fraction"].values, again.f)
    assert float(ds["uncertainty_exponent"]) == again.alpha
    assert float(ds["boundary_dimension"]) == pytest.approx(2 - again.alpha, abs=1e-15)


def test_the_published_facts_come_out(measured):
    """A fractal boundary (S_bb > ln 2, α well below a smooth boundary's 1) and three Wada
    basins: the grid method's W_3 ≥ 0.9, as Basins.jl's test of this case asks."""
    ds = atlas.open(measured).to_dataset(inherit=False)
    assert float(ds["boundary_basin_entropy"]) > math.log(2)
    assert float(ds["fractal_boundary"]) == 1
    alpha = float(ds["uncertainty_exponent"])
    assert 0 < alpha < 0.5 and float(ds["uncertainty_exponent_error"]) < 0.05
    wada = ds["wada"].values
    assert wada.shape == (3,) and wada[2] >= 0.9, wada
    assert wada.sum() == pytest.approx(1.0)


def test_info_and_plot_show_them(measured, capsys):
    assert main(["info", str(measured)]) == 0
    out = capsys.readouterr().out
    assert "boundary basin entropy S_bb" in out and "> ln 2" in out
    assert "uncertainty exponent alpha" in out and "the fit's standard error only" in out
    assert "Wada grid method: W_1" in out and "W_3" in out
    assert main(["plot", str(measured)]) == 0
    assert measured.with_name("m_uncertainty.png").exists()
