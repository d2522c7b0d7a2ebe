"""The uncertainty exponent: how the share of ε-uncertain initial conditions scales with ε.

Grebogi, McDonald, Ott & Yorke, "Final state sensitivity: an obstruction to
predictability", *Phys. Lett. A* 99, 415 (1983); McDonald, Grebogi, Ott & Yorke, "Fractal
basin boundaries", *Physica D* 17, 125 (1985). An initial condition x is ε-uncertain if x and
a perturbation of it by ε reach different attractors. The fraction f(ε) of ε-uncertain
points scales as f(ε) ∝ ε^α: α is the uncertainty exponent, and the box-counting dimension
of the basin boundary is D = d − α (d = 2, the phase plane's dimension). A smooth boundary
has α = 1 (D = 1); a fractal one 0 < α < 1; α near 0 means the final state can hardly be
predicted at any precision.

Two estimators:

* :func:`uncertainty_exponent_grid`, on a matrix of labels, as Attractors.jl's
  ``uncertainty_exponent``: ε is a box's side in cells, and f(ε) the share of the ε × ε boxes
  tiling the matrix that hold two labels or more (the box-counting version of the definition).
* :func:`uncertainty_exponent`, on a ``label(x, y)`` callable: n random points of a window
  (seeded), each labelled with its two perturbations x ± ε·e (e a random direction per
  point, ε a fraction of the window's sides), at ε log-spaced over a range.

Both fit ln f = α ln ε + c by ordinary least squares over the ε with f > 0 and return α with
the fit's standard error. That error measures the scatter about the line only; the choice of
the ε range, the grid's resolution, the number of samples (f's binomial error) and the
labels' own errors near the boundary move α by more (compare two ranges).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from atlas.fractal.labels import FILL, labelled_matrix

__all__ = ["UncertaintyExponent", "fit_exponent", "uncertainty_exponent",
           "uncertainty_exponent_grid"]


@dataclass(frozen=True, eq=False)
class UncertaintyExponent:
    """The uncertainty exponent and what it was fitted to.

    ``alpha``: the slope of ln f against ln ε; ``alpha_error``: its standard error from the
    fit (scatter only: see the module's note); ``intercept``: c; ``dimension``: D = 2 − α,
    the boundary's box-counting dimension; ``eps``: the ε values (cells for the grid
    estimator, fractions of the window's sides for the callable one); ``f``: f(ε);
    ``n_uncertain`` and ``n_tested``: per ε the uncertain count and the count tested (boxes
    or points); ``fitted``: which ε entered the fit (f > 0)."""

    alpha: float
    alpha_error: float
    intercept: float
    dimension: float
    eps: np.ndarray
    f: np.ndarray
    n_uncertain: np.ndarray
    n_tested: np.ndarray
    fitted: np.ndarray

    @property
    def f_error(self) -> np.ndarray:
        """f's binomial standard error per ε, √(f(1 − f)/n)."""
        return np.sqrt(self.f * (1 - self.f) / np.maximum(self.n_tested, 1))


def fit_exponent(eps, f) -> tuple[float, float, float, np.ndarray]:
    """Least squares ln f = α ln ε + c over the ε with f > 0: (α, its standard error, c, the
    boolean array of the ε fitted). The standard error is √(s²/Σ(ln ε − mean)²) with s² the
    residuals' variance on n − 2 degrees of freedom (NaN with fewer than three points)."""
    eps, f = np.asarray(eps, float), np.asarray(f, float)
    used = f > 0
    x, y = np.log(eps[used]), np.log(f[used])
    if len(x) < 2:
        raise ValueError("fewer than two ε with an uncertain point: no exponent")
    a, c = np.polyfit(x, y, 1)
    if len(x) > 2:
        s2 = float(np.sum((y - (a * x + c)) ** 2) / (len(x) - 2))
        err = math.sqrt(s2 / float(np.sum((x - x.mean()) ** 2)))
    else:
        err = math.nan
    return float(a), err, float(c), used


def uncertainty_exponent_grid(labels, eps=None, *, mask=None, unlabelled: str = "basin",
                              fill: int | None = FILL, scale: str = "cells") -> UncertaintyExponent:
    """α from a matrix of labels, box-counting as Attractors.jl's ``uncertainty_exponent``:
    for each ε in ``eps`` (box sides in cells; default 2 … max(shape) // 20 as Attractors.jl)
    the ε × ε boxes tiling the matrix from its first cell (the cells left over at the far
    edges ignored) are tested; a box is uncertain if it holds two labels or more; f(ε) is the
    uncertain share of the boxes tested.

    Attractors.jl fits ln N_u against ln(1/ε) for the dimension and returns 2 − D; that
    differs from this fit of f = N_u/N only by the boxes a remainder leaves out (N is not
    exactly (L/ε)²). Unlabelled cells (``mask`` True, by default those that hold ``fill``): one
    more basin (``unlabelled="basin"``, as Attractors.jl) or left out (``"exclude"``: a box
    is uncertain if its labelled cells hold two labels; a box with none is not tested).

    ``scale``: the ε the fit sees. "cells" (default, Attractors.jl's): the box's side ε in
    cells. Then a smooth boundary gives α above 1 on small boxes: a box of ε cells samples
    the plane at cell centres spanning ε − 1 spacings, so N_u ∝ (ε − 1)/ε² for a straight
    line, and the slope of ln f is ε/(ε − 1) (about 1.2 over ε = 2 … 20). "span": the fit
    takes ε − 1 (the distance between the box's outer cell centres, in cells), which
    removes that bias for a smooth boundary (α = 1 for a straight line); ``eps`` in the
    result is then ε − 1, and boxes of one cell are refused."""
    codes, counted = labelled_matrix(labels, mask, unlabelled, fill)
    rows, cols = codes.shape
    if eps is None:
        eps = range(2, max(rows, cols) // 20 + 1)
    eps = np.asarray(list(eps), int)
    if np.any(eps < 1) or np.any(eps > min(rows, cols)):
        raise ValueError(f"box sides must lie in 1 … {min(rows, cols)} cells")
    big = np.iinfo(np.int64).max
    lo = np.where(counted, codes, big)
    hi = np.where(counted, codes, -1)
    nu, nt = [], []
    for e in eps:
        n0, n1 = rows // e, cols // e
        a = lo[:n0 * e, :n1 * e].reshape(n0, e, n1, e).min(axis=(1, 3))
        b = hi[:n0 * e, :n1 * e].reshape(n0, e, n1, e).max(axis=(1, 3))
        tested = b >= 0
        nt.append(int(tested.sum()))
        nu.append(int((tested & (b > a)).sum()))
    nu, nt = np.array(nu), np.array(nt)
    f = nu / np.maximum(nt, 1)
    if scale not in ("cells", "span"):
        raise ValueError(f"scale must be 'cells' or 'span', not {scale!r}")
    x = eps.astype(float) - (1.0 if scale == "span" else 0.0)
    if np.any(x <= 0):
        raise ValueError("scale='span' needs boxes of two cells a side or more")
    alpha, err, c, used = fit_exponent(x, f)
    return UncertaintyExponent(alpha, err, c, 2.0 - alpha, x, f, nu, nt, used)


def uncertainty_exponent(label: Callable, window, eps=None, *, n_points: int = 2000,
                         eps_range: tuple[float, float] = (1e-5, 1e-2), n_eps: int = 7,
                         seed=0, fill: int | None = FILL) -> UncertaintyExponent:
    """α from a labelling function, by random sampling (Grebogi et al. 1983; McDonald et
    al. 1985).

    ``label(x, y)`` takes two float arrays of one shape and returns integer labels of that
    shape (``fill``, atlas's −32768: no label); ``window`` is ((x_lo, x_hi), (y_lo, y_hi)).
    ``n_points`` points are drawn uniformly in the window (``seed``); for each ε (``eps``,
    or ``n_eps`` values log-spaced over ``eps_range``), each point x is labelled with x + δ
    and x − δ,
    δ = ε (L_x cos φ, L_y sin φ) with L the window's sides and φ a random angle per point
    (the same points and angles for every ε). A point is ε-uncertain if either perturbation's
    label differs from its own; a point whose own label or either perturbation's is ``fill``
    is not counted (``n_tested`` says how many were). ε is thus a fraction of the window's
    sides (dimensionless); α does not depend on that scaling."""
    (x_lo, x_hi), (y_lo, y_hi) = window
    lx, ly = x_hi - x_lo, y_hi - y_lo
    if eps is None:
        eps = np.geomspace(eps_range[0], eps_range[1], n_eps)
    eps = np.asarray(eps, float)
    rng = np.random.default_rng(seed)
    x = x_lo + lx * rng.random(n_points)
    y = y_lo + ly * rng.random(n_points)
    phi = 2 * math.pi * rng.random(n_points)
    dx, dy = lx * np.cos(phi), ly * np.sin(phi)
    xs = np.concatenate([x] + [x + s * e * dx for e in eps for s in (1, -1)])
    ys = np.concatenate([y] + [y + s * e * dy for e in eps for s in (1, -1)])
    got = np.asarray(label(xs, ys)).reshape(2 * len(eps) + 1, n_points)
    own, moved = got[0], got[1:].reshape(len(eps), 2, n_points)
    ok = (own != fill) & np.all(moved != fill, axis=1)
    uncertain = ok & np.any(moved != own, axis=1)
    nu, nt = uncertain.sum(axis=1), ok.sum(axis=1)
    f = nu / np.maximum(nt, 1)
    alpha, err, c, used = fit_exponent(eps, f)
    return UncertaintyExponent(alpha, err, c, 2.0 - alpha, eps, f, nu, nt, used)
