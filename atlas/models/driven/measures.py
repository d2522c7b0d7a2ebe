"""The fractal measures of one driven pendulum's basin map, as ``atlas run`` stores them
(:mod:`atlas.fractal`, on the map of a parameter point and its :class:`DrivenPoint`):

- basin entropy S_b and boundary basin entropy S_bb [nats] in boxes of :data:`BOX` × BOX
  grid points, over the labelled ones (an orbit without a label is no basin; Daza et al.,
  *Sci. Rep.* 6, 31416, 2016), with the sufficient test of a fractal boundary S_bb > ln 2
  (it cannot pass with two basins, whose boxes hold ln 2 at most);
- the uncertainty exponent α of the fraction of ε-uncertain initial conditions,
  f(ε) ∝ ε^α, from :data:`UNCERTAIN_POINTS` seeded random points of the window each labelled
  with the map's own rule at ±ε (ε a fraction of the window's sides, :data:`EPSILONS`), α
  with the standard error of its least-squares fit, and the boundary's box-counting dimension
  D = 2 − α (Grebogi, McDonald, Ott & Yorke, *Phys. Lett. A* 99, 415, 1983);
- the Wada grid method's W_1 … W_N (Daza, Wagemakers, Sanjuán & Yorke, *Sci. Rep.* 5, 16579,
  2015) on the map thinned to at most :data:`WADA_CELLS` points per axis, each boundary
  cell refined up to :data:`WADA_REFINEMENTS` times by the map's own labels; and the merging
  method's largest and smallest Hausdorff distance [grid cells of the thinned map] between a
  basin's boundary and the others' (Daza, Wagemakers & Sanjuán, *Sci. Rep.* 8, 9954, 2018).

Every label these use is a label of the RK4 stroboscopic map, as the map's own.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.fractal import basin_entropy, uncertainty_exponent, wada_grid, wada_merge
from atlas.models.driven.description import ATTRACTOR_FILL

__all__ = ["measure", "BOX", "UNCERTAIN_POINTS", "EPSILONS", "WADA_CELLS",
           "WADA_REFINEMENTS", "SEED"]

#: The box of the basin entropy [grid points per side].
BOX = 5
#: Random initial conditions of the uncertainty exponent, and its seed (also the Wada's).
UNCERTAIN_POINTS, SEED = 2000, 0
#: The perturbations ε of the uncertainty exponent, fractions of the window's sides.
EPSILONS = np.geomspace(1e-6, 1e-2, 9)
#: The most points per axis of the map the Wada grid method runs on, and its refinements.
WADA_CELLS, WADA_REFINEMENTS = 150, 5


def measure(point, labels: np.ndarray, x0: np.ndarray, v0: np.ndarray, n_attractors: int
            ) -> dict:
    """The measures of one parameter point (module notes): ``point`` its DrivenPoint,
    ``labels`` its map (rows over ``v0`` [rad s⁻¹], columns over ``x0`` [rad]; fill where
    no label), ``n_attractors`` N. NaN where a measure is undefined (fewer than two
    attractors, or a map too small for one box)."""
    def label(x, y):
        return point.label(np.asarray(x, float), np.asarray(y, float))[0]

    out = {"basin_entropy": math.nan, "boundary_basin_entropy": math.nan,
           "fractal_boundary": math.nan, "uncertainty_exponent": math.nan,
           "uncertainty_exponent_error": math.nan, "boundary_dimension": math.nan,
           "uncertain_fraction": np.full(len(EPSILONS), np.nan),
           "wada": np.full(n_attractors, np.nan), "wada_merge_distance_max": math.nan,
           "wada_merge_distance_min": math.nan}
    if min(labels.shape) >= BOX and np.any(labels != ATTRACTOR_FILL):
        entropy = basin_entropy(labels, BOX, trim=True, fill=ATTRACTOR_FILL,
                                unlabelled="exclude")  # no label is no basin
        out.update(basin_entropy=entropy.sb, boundary_basin_entropy=entropy.sbb,
                   fractal_boundary=float(entropy.fractal))
    if n_attractors < 2:
        return out
    window = ((float(x0[0]), float(x0[-1])), (float(v0[0]), float(v0[-1])))
    try:
        exponent = uncertainty_exponent(label, window, EPSILONS, n_points=UNCERTAIN_POINTS,
                                        seed=SEED, fill=ATTRACTOR_FILL)
    except ValueError:  # fewer than two ε met an uncertain point: no exponent to fit
        pass
    else:
        out.update(uncertainty_exponent=exponent.alpha,
                   uncertainty_exponent_error=exponent.alpha_error,
                   boundary_dimension=exponent.dimension,
                   uncertain_fraction=np.asarray(exponent.f, float))
    step = max(1, math.ceil(max(labels.shape) / WADA_CELLS))
    thin = labels[::step, ::step]
    present = np.unique(thin[thin != ATTRACTOR_FILL])
    if len(present) >= 2:
        grid = wada_grid(thin, x0[::step], v0[::step], label, n_basins=n_attractors,
                         max_refinements=WADA_REFINEMENTS, fill=ATTRACTOR_FILL)
        out.update(wada=np.asarray(grid.w, float)[:n_attractors])
    if len(present) >= 3:  # the merging method compares three basins or more
        merged = wada_merge(thin, fill=ATTRACTOR_FILL)
        out.update(wada_merge_distance_max=float(merged.d_max),
                   wada_merge_distance_min=float(merged.d_min))
    return out
