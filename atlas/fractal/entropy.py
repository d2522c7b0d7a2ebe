"""Basin entropy: how uncertain the final state is, box by box, and the ln 2 fractality test.

Daza, Wagemakers, Georgeot, Guéry-Odelin & Sanjuán, "Basin entropy: a new tool to analyze
uncertainty in dynamical systems", *Sci. Rep.* 6, 31416 (2016). Cover the matrix of labels
with N boxes of ε × ε cells. In box i, with m_i distinct labels of relative frequencies
p_ij, the Gibbs entropy is S_i = −Σ_j p_ij ln p_ij (natural log, nats). Then

* the basin entropy S_b = (1/N) Σ_i S_i (over every box),
* the basin boundary entropy S_bb = (1/N_b) Σ_i S_i (over the N_b boxes with m_i ≥ 2).

S_b lies in [0, ln K] for K basins; S_bb > ln 2 is a sufficient condition for a fractal
boundary (a smooth boundary between two basins has S_bb ≤ ln 2 whatever the box; the
converse does not hold: a fractal boundary may have S_bb below ln 2). Both depend on the box
size ε and the grid's resolution: compare values at one ε and one grid.

:func:`fractal_test` is the statistical test of Puy, Daza, Wagemakers & Sanjuán, "A test for
fractal boundaries based on the basin entropy", *Commun. Nonlinear Sci. Numer. Simul.* 95,
105588 (2021): S_bb over random balls of radius ε on the boundary against the smooth
boundary's value 0.4395093 in two dimensions (the table of Attractors.jl's
``basins_fractal_test``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from atlas.fractal.labels import FILL, labelled_matrix

__all__ = ["BasinEntropy", "FractalTest", "SMOOTH_SBB_2D", "basin_entropy", "box_entropies",
           "fractal_test"]

#: S_bb of a smooth boundary between two basins, sampled by balls in two dimensions, in the
#: limit of small balls on a fine grid (Puy et al. 2021; Attractors.jl's table).
SMOOTH_SBB_2D = 0.4395093


@dataclass(frozen=True)
class BasinEntropy:
    """The basin entropy of a label matrix at one box size.

    ``sb``, ``sbb``: S_b and S_bb [nats] (``sbb`` is NaN where no box holds two labels);
    ``box``: the box's (rows, columns) in cells; ``n_boxes``: boxes counted (N: those with at
    least one counted cell); ``n_boundary_boxes``: those with two labels or more (N_b);
    ``n_basins``: distinct labels counted; ``fractal``: S_bb > ln 2 (sufficient, not
    necessary, for a fractal boundary); ``unlabelled``: how unlabelled cells were taken."""

    sb: float
    sbb: float
    box: tuple[int, int]
    n_boxes: int
    n_boundary_boxes: int
    n_basins: int
    fractal: bool
    unlabelled: str


def _entropies(counts: np.ndarray) -> np.ndarray:
    """−Σ p ln p along the last axis of label counts (rows with no count: 0)."""
    total = counts.sum(axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = counts / total
        terms = np.where(counts > 0, -p * np.log(np.where(counts > 0, p, 1.0)), 0.0)
    return terms.sum(axis=-1)


def _box_counts(labels, box, mask, unlabelled, trim, fill) -> np.ndarray:
    """The count of each label code in each box: an array (box rows, box columns, codes)."""
    codes, counted = labelled_matrix(labels, mask, unlabelled, fill)
    b0, b1 = (box, box) if np.isscalar(box) else tuple(box)
    b0, b1 = int(b0), int(b1)
    if b0 < 1 or b1 < 1:
        raise ValueError(f"a box has at least one cell a side, not {(b0, b1)}")
    rows, cols = codes.shape
    if (rows % b0 or cols % b1) and not trim:
        raise ValueError(f"a {rows} x {cols} matrix is not tiled by {b0} x {b1} boxes "
                         "(trim=True drops the cells left over)")
    n0, n1 = rows // b0, cols // b1
    codes = codes[:n0 * b0, :n1 * b1].reshape(n0, b0, n1, b1)
    keep = counted[:n0 * b0, :n1 * b1].reshape(n0, b0, n1, b1)
    k = int(codes.max()) + 1 if codes.size else 1
    box_index = np.broadcast_to(np.arange(n0)[:, None, None, None] * n1
                                + np.arange(n1)[None, None, :, None], codes.shape)
    return np.bincount((box_index * k + codes)[keep], minlength=n0 * n1 * k
                       ).reshape(n0, n1, k)


def box_entropies(labels, box, *, mask=None, unlabelled: str = "basin", trim: bool = False,
                  fill: int | None = FILL) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per box of ``box`` cells (an int, or (rows, columns)) tiling ``labels`` from its first
    cell: the entropy S_i [nats], the number of distinct labels m_i and the number of counted
    cells, each as a matrix of boxes. A shape not divisible by the box is an error (as in
    Attractors.jl) unless ``trim``: then the last rows and columns that fill no whole box are
    dropped."""
    counts = _box_counts(labels, box, mask, unlabelled, trim, fill)
    return _entropies(counts), (counts > 0).sum(axis=-1), counts.sum(axis=-1)


def basin_entropy(labels, box, *, mask=None, unlabelled: str = "basin", trim: bool = False,
                  fill: int | None = FILL) -> BasinEntropy:
    """S_b and S_bb of ``labels`` (a 2-D integer matrix) with boxes of ``box`` cells (an int,
    or (rows, columns)), as Daza et al. 2016 and Attractors.jl's ``basin_entropy``.

    Unlabelled cells (``mask`` True, by default the cells that hold ``fill``, atlas's
    −32768: :mod:`atlas.fractal.labels`) are by default one more basin
    (``unlabelled="basin"``, as Attractors.jl, which counts −1 as an ID); with
    ``unlabelled="exclude"`` they are left out: a box's frequencies are over its labelled
    cells, and a box with none is not counted in N. ``trim``: see :func:`box_entropies`."""
    counts = _box_counts(labels, box, mask, unlabelled, trim, fill)
    s, m, n = _entropies(counts), (counts > 0).sum(axis=-1), counts.sum(axis=-1)
    boxes = n > 0
    boundary = m >= 2
    n_boxes, n_boundary = int(boxes.sum()), int(boundary.sum())
    total = float(s[boxes].sum())
    sb = total / n_boxes if n_boxes else math.nan
    sbb = total / n_boundary if n_boundary else math.nan
    b = (int(box), int(box)) if np.isscalar(box) else (int(box[0]), int(box[1]))
    return BasinEntropy(sb, sbb, b, n_boxes, n_boundary,
                        int((counts.sum(axis=(0, 1)) > 0).sum()),
                        bool(n_boundary and sbb > math.log(2)), unlabelled)


@dataclass(frozen=True)
class FractalTest:
    """Puy et al.'s test: ``sbb`` [nats], the mean entropy of ``n_balls`` random balls of
    ``radius`` cells that hold two labels or more, its standard error ``sbb_error``, the
    smooth boundary's value ``smooth`` and the bias bound ``bias`` = 0.224 ε^−1.006 of a ball
    of radius ε; ``fractal``: S_bb outside [smooth − error, smooth + error + bias]."""

    sbb: float
    sbb_error: float
    smooth: float
    bias: float
    radius: float
    n_balls: int
    n_tries: int
    fractal: bool


def fractal_test(labels, radius: float = 20, n_balls: int = 1000, *, mask=None,
                 unlabelled: str = "basin", fill: int | None = FILL, seed=0,
                 max_tries: int | None = None) -> FractalTest:
    """Puy et al. 2021's test for a fractal boundary, as Attractors.jl's
    ``basins_fractal_test``: balls of ``radius`` cells (the cells whose centres lie within
    ``radius`` of the ball's, Euclidean) are dropped at random (``seed``) wholly inside the
    matrix until ``n_balls`` of them hold two labels or more; their mean entropy Ŝ_bb and its
    standard error σ = std/√n are compared with the smooth boundary's 0.4395093: the boundary
    is called smooth where 0.4395093 − σ ≤ Ŝ_bb ≤ 0.4395093 + σ + 0.224 ε^−1.006 (the
    second term: the bias of a ball of radius ε cells), fractal otherwise. The answer may
    depend on ε; Puy et al. ask for a grid of ≥ 50 ε a side.

    (Attractors.jl's mean includes one zero that its loop never fills: a bias of −Ŝ/n_balls
    that this one does not have.)"""
    if n_balls < 100:
        raise ValueError("n_balls must be at least 100 to gather enough statistics")
    codes, counted = labelled_matrix(labels, mask, unlabelled, fill)
    rows, cols = codes.shape
    r = int(math.floor(radius))
    if 2 * r + 1 > min(rows, cols):
        raise ValueError(f"a ball of radius {radius} does not fit a {rows} x {cols} matrix")
    di, dj = np.nonzero(np.hypot(*np.meshgrid(np.arange(-r, r + 1), np.arange(-r, r + 1),
                                               indexing="ij")) <= radius)
    di, dj = di - r, dj - r
    k = int(codes.max()) + 1
    rng = np.random.default_rng(seed)
    max_tries = max_tries or 1000 * n_balls
    found, tries = [], 0
    while sum(len(f) for f in found) < n_balls and tries < max_tries:
        batch = min(max(4 * n_balls, 1000), max_tries - tries)
        ci = rng.integers(r, rows - r, batch)
        cj = rng.integers(r, cols - r, batch)
        tries += batch
        c = codes[ci[:, None] + di, cj[:, None] + dj]
        w = counted[ci[:, None] + di, cj[:, None] + dj]
        counts = np.zeros((batch, k), np.int64)
        np.add.at(counts, (np.repeat(np.arange(batch), c.shape[1])[w.ravel()], c.ravel()[
            w.ravel()]), 1)
        s = _entropies(counts)
        found.append(s[(counts > 0).sum(axis=1) >= 2])
    s = np.concatenate(found)[:n_balls]
    if len(s) < n_balls:
        raise ValueError(f"only {len(s)} boundary balls in {tries} tries")
    sbb, err = float(s.mean()), float(s.std(ddof=1) / math.sqrt(len(s)))
    bias = 0.224 * radius ** -1.006
    smooth = SMOOTH_SBB_2D
    return FractalTest(sbb, err, smooth, bias, float(radius), len(s), tries,
                       bool(sbb < smooth - err or sbb > smooth + err + bias))
