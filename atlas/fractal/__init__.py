"""Fractal measures of basins of attraction: basin entropy, uncertainty exponent, Wada tests.

Pure numerics on a 2-D matrix of labels (rows: the second coordinate, columns: the first, as
an atlas's ``attractor`` over (theta_dot0, theta0)) or on a ``label(x, y)`` callable that the
caller passes in; nothing here imports the rest of atlas.
"""

from atlas.fractal.entropy import BasinEntropy, FractalTest, basin_entropy, fractal_test
from atlas.fractal.uncertainty import (
    UncertaintyExponent,
    uncertainty_exponent,
    uncertainty_exponent_grid,
)
from atlas.fractal.wada import WadaGrid, WadaMerge, wada_grid, wada_merge

__all__ = ["BasinEntropy", "FractalTest", "basin_entropy", "fractal_test",
           "UncertaintyExponent", "uncertainty_exponent", "uncertainty_exponent_grid",
           "WadaGrid", "WadaMerge", "wada_grid", "wada_merge"]
