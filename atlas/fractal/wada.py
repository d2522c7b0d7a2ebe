"""The Wada property: is every boundary point of the basins a boundary point of all of them?

Two tests of Daza, Wagemakers, Sanjuán and Yorke:

* the grid method (:func:`wada_grid`), Daza, Wagemakers, Sanjuán & Yorke, "Testing for
  basins of Wada", *Sci. Rep.* 5, 16579 (2015), as Basins.jl's ``detect_wada_grid_method``:
  a boundary cell is a grid point whose 3 × 3 neighbourhood holds two labels or more; it
  starts with the labels of that neighbourhood and, at refinement q = 1, 2, …, labels the
  2^(q−1) new points that split the segment from it to a neighbour of another label into
  2^q equal parts, with the system's own ``label`` callable, until it has seen all N basins
  or q reaches a maximum. W_m is the share of boundary cells that have seen m basins. The
  basins are Wada if W_N → 1 as q grows (in practice: W_N near 1 after a few refinements);
  the basins are not Wada where W_N stays small. Labels only get added, so W_N can only
  grow with q.
* the merging method (:func:`wada_merge`), Daza, Wagemakers & Sanjuán, "Ascertaining when a
  basin is Wada: the merging method", *Sci. Rep.* 8, 9954 (2018): merge all basins but one
  into one; the boundary of the two-colour picture is the boundary of that basin. If the
  basins are Wada these N boundaries are one set, so the Hausdorff distances between them
  (in cells) stay a few cells, and do not grow with the grid's resolution; a basin with a
  boundary of its own gives a distance of the order of the picture. Pure on the matrix:
  no new labels.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from atlas.fractal.labels import FILL, UNLABELLED_MODES, labelled_matrix, unlabelled_cells

__all__ = ["WadaGrid", "WadaMerge", "boundary_cells", "wada_grid", "wada_merge"]

_SQUARE = np.ones((3, 3), bool)
# the 8 neighbours, edges first (a partner across an edge is the nearer one)
_NEIGHBOURS = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


@dataclass(frozen=True, eq=False)
class WadaGrid:
    """The grid method's answer. ``w``: W_1 … W_N after the last refinement (``w[m − 1]``:
    the share of boundary cells that saw m basins); ``history``: W after each refinement,
    row q (row 0: the grid's own 3 × 3 neighbourhoods); ``n_basins``: N; ``n_boundary``: the
    boundary cells tested; ``refinements``: refinements done; ``n_labelled``: points the
    callable labelled; ``n_unlabelled``: of those, the ones it gave no label (ignored)."""

    w: np.ndarray
    history: np.ndarray
    n_basins: int
    n_boundary: int
    refinements: int
    n_labelled: int
    n_unlabelled: int


def boundary_cells(labels, mask=None, fill: int | None = FILL) -> np.ndarray:
    """The boolean matrix of labelled cells whose 3 × 3 neighbourhood (clipped at the edges)
    holds a labelled cell of another label (``mask`` True, by default the cells that hold
    ``fill``: unlabelled, neither boundary nor neighbour)."""
    codes, counted = labelled_matrix(labels, mask, "exclude", fill)
    big = np.iinfo(np.int64).max
    lo = ndimage.minimum_filter(np.where(counted, codes, big), footprint=_SQUARE,
                                mode="nearest")
    hi = ndimage.maximum_filter(np.where(counted, codes, -1), footprint=_SQUARE,
                                mode="nearest")
    return counted & (lo < hi)


def wada_grid(labels, x, y, label: Callable, *, max_refinements: int = 5,
              n_basins: int | None = None, mask=None, fill: int | None = FILL) -> WadaGrid:
    """W_1 … W_N of the grid method (Daza et al. 2015) on the matrix ``labels`` (rows over
    ``y``, columns over ``x``: ``labels[i, j]`` is the label of (x[j], y[i])), refined with
    ``label(x, y)`` (float arrays in, integer labels of their shape out; ``fill``, atlas's
    −32768: no label; unlabelled cells of the matrix: ``mask`` True, by default ``fill``).

    Each boundary cell (:func:`boundary_cells`) starts with the labels of its 3 × 3
    neighbourhood and a partner: its first neighbour of another label (edge neighbours
    before diagonal ones). Refinement q labels the points k/2^q of the segment to the
    partner, k odd, for the cells that have not yet seen all N basins (N: ``n_basins``, by
    default the distinct labels of the matrix). Unlabelled cells and points are ignored.
    Refinement stops after ``max_refinements`` or once every cell has seen N basins."""
    labels = np.asarray(labels)
    x, y = np.asarray(x, float), np.asarray(y, float)
    if labels.shape != (len(y), len(x)):
        raise ValueError(f"labels of shape {labels.shape} for {len(y)} y and {len(x)} x")
    missing = unlabelled_cells(labels, mask, fill)
    values = np.unique(labels[~missing])
    n = len(values) if n_basins is None else int(n_basins)
    if n < 2:
        raise ValueError("the grid method needs two basins or more")
    rows, cols = np.nonzero(boundary_cells(labels, missing))
    known = list(values)  # the labels met so far: a column of `seen` each
    seen = np.zeros((len(rows), max(n, len(known))), bool)
    partner = np.full((len(rows), 2), -1)
    for di, dj in ((0, 0),) + _NEIGHBOURS:
        i, j = rows + di, cols + dj
        inside = (i >= 0) & (i < labels.shape[0]) & (j >= 0) & (j < labels.shape[1])
        ic, jc = np.clip(i, 0, labels.shape[0] - 1), np.clip(j, 0, labels.shape[1] - 1)
        ok = inside & ~missing[ic, jc]
        seen[np.nonzero(ok)[0], np.searchsorted(values, labels[ic, jc][ok])] = True
        new = ok & (partner[:, 0] < 0) & (labels[ic, jc] != labels[rows, cols])
        partner[new] = np.column_stack([ic, jc])[new]

    def shares():
        m = seen.sum(axis=1)
        if m.size and m.max() > n:
            raise ValueError(f"a boundary cell saw {m.max()} basins, more than n_basins={n}")
        return np.bincount(m, minlength=n + 1)[1:] / max(len(m), 1)

    history = [shares()]
    p1 = np.column_stack([x[cols], y[rows]])
    p2 = np.column_stack([x[partner[:, 1]], y[partner[:, 0]]]) if len(rows) else p1
    labelled = unlabelled = 0
    q = 0
    for q in range(1, max_refinements + 1):
        todo = np.nonzero(seen.sum(axis=1) < n)[0]
        if todo.size == 0:
            q -= 1
            break
        t = np.arange(1, 2 ** q, 2) / 2 ** q
        pts = p1[todo, None, :] + t[None, :, None] * (p2[todo] - p1[todo])[:, None, :]
        got = np.asarray(label(pts[..., 0].ravel(), pts[..., 1].ravel())).reshape(-1)
        labelled += got.size
        ok = np.ones(got.shape, bool) if fill is None else got != fill
        unlabelled += int((~ok).sum())
        for v in np.setdiff1d(got[ok], known):  # a basin the grid did not show
            known.append(v)
            if len(known) > seen.shape[1]:
                seen = np.column_stack([seen, np.zeros(len(seen), bool)])
        lookup = {v: c for c, v in enumerate(known)}
        column = np.array([lookup[v] for v in got[ok].tolist()], int)
        seen[np.repeat(todo, len(t))[ok], column] = True
        history.append(shares())
    history = np.array(history)
    return WadaGrid(history[-1], history, n, len(rows), q, labelled, unlabelled)


@dataclass(frozen=True, eq=False)
class WadaMerge:
    """The merging method's answer. ``basins``: the labels, in order; ``hausdorff``: the
    matrix of Hausdorff distances [cells] between the boundaries of the merged pictures
    (basin i against all others); ``d_max``, ``d_min``: its largest and smallest entry off
    the diagonal; ``r``: the distance asked about (None: none) and ``beyond``: the largest
    share, over ordered pairs, of one boundary's cells farther than r from the other's;
    ``wada``: d_max ≤ r (None without r)."""

    basins: np.ndarray
    hausdorff: np.ndarray
    d_max: float
    d_min: float
    r: float | None
    beyond: float | None
    wada: bool | None


def _edge(inside: np.ndarray) -> np.ndarray:
    """Cells of a two-colour picture with an 8-neighbour of the other colour (both sides)."""
    a = inside & ~ndimage.binary_erosion(inside, _SQUARE, border_value=1)
    b = ~inside & ~ndimage.binary_erosion(~inside, _SQUARE, border_value=1)
    return a | b


def wada_merge(labels, r: float | None = None, *, mask=None, unlabelled: str = "exclude",
               fill: int | None = FILL) -> WadaMerge:
    """Hausdorff distances between the boundaries of the merged basins (Daza et al. 2018).

    For each label k, the picture "k or not k" has a boundary: the cells with an 8-neighbour
    of the other colour (as Basins.jl's filter). The Hausdorff distance between two such
    boundaries A and B is max(max_{b∈B} d(b, A), max_{a∈A} d(a, B)), Euclidean, in cells
    (exact: scipy's Euclidean distance transform). Wada basins give small distances (a few
    cells) that do not grow as the grid is refined.

    Unlabelled cells (``mask`` True, by default those that hold ``fill``): with
    ``unlabelled="exclude"`` (default) each takes the label of its nearest labelled cell, so
    that a few scattered unresolved orbits do not make a basin of their own; with
    ``"basin"`` they are one more basin (as Attractors.jl's ``test_wada_merge``). ``r``: also
    return the largest share of a boundary's cells farther than ``r`` cells from another
    boundary (Attractors.jl divides that count by all the cells of the matrix; this by the
    boundary's) and whether every distance is within ``r``."""
    labels = np.asarray(labels)
    if unlabelled not in UNLABELLED_MODES:
        raise ValueError(f"unlabelled must be one of {UNLABELLED_MODES}, not {unlabelled!r}")
    missing = unlabelled_cells(labels, mask, fill)
    work = labels.astype(np.int64)
    if missing.any():
        if unlabelled == "exclude":
            if missing.all():
                raise ValueError("no labelled cell")
            _, (ii, jj) = ndimage.distance_transform_edt(missing, return_indices=True)
            work = work[ii, jj]
        else:
            work = np.where(missing, np.iinfo(np.int64).min, work)
    basins = np.unique(work)
    if len(basins) < 3:
        raise ValueError(f"the Wada property needs three basins or more, not {len(basins)}")
    edges = [_edge(work == b) for b in basins]
    distance = [ndimage.distance_transform_edt(~e) for e in edges]
    k = len(basins)
    h = np.zeros((k, k))
    beyond = 0.0
    for i in range(k):
        for j in range(k):
            if i != j:
                h[i, j] = h[j, i] = max(h[i, j], float(distance[i][edges[j]].max()))
                if r is not None:
                    beyond = max(beyond, float((distance[i][edges[j]] > r).mean()))
    off = h[~np.eye(k, dtype=bool)]
    return WadaMerge(basins, h, float(off.max()), float(off.min()), r,
                     None if r is None else beyond,
                     None if r is None else bool(off.max() <= r))
