"""Tipping probabilities between consecutive parameter points of a 1-D study (Kaszás, Feudel
& Tél, "Tipping phenomena in typical dynamical systems subjected to parameter drift", Sci.
Rep. 9, 8654, 2019, doi:10.1038/s41598-019-44863-3): for a state spread uniformly over the
window part of basin A at point pᵢ, the share of it lying in basin B at pᵢ₊₁,

    P(A → B) = area(A(pᵢ) ∩ B(pᵢ₊₁) ∩ window) / area(A(pᵢ) ∩ window),

from the exact overlaps of the basin polygons (:func:`atlas.stability.polygons.window_basins`,
shapely/GEOS in double precision). Each row sums to 1 (to the polygons' chord error); a basin
that does not meet the window at pᵢ has a row of NaN. Basins are wells k and the running basin
(:data:`atlas.boundaries.basins.RUNNING_SIDE`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["tipping_matrix"]


def tipping_matrix(before: dict, after: dict, labels) -> np.ndarray:
    """P[a, b] over ``labels`` (basins: well k, or RUNNING_SIDE) from ``before`` and
    ``after`` ({basin: shapely geometry ∩ window}, missing basins empty)."""
    n = len(labels)
    out = np.full((n, n), np.nan)
    for i, a in enumerate(labels):
        source = before.get(int(a))
        if source is None or source.is_empty or source.area == 0.0:
            continue
        for j, b in enumerate(labels):
            target = after.get(int(b))
            out[i, j] = 0.0 if target is None or target.is_empty else \
                source.intersection(target).area / source.area
    return out
