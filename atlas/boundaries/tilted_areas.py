"""The exact basin areas of the pendulum with torque: the fraction of a window in each well's
basin and in the running basin, exact for the DOP853 dense output of the stable branches.

Well 0's basin (canonical frame, τ > 0) is a curved polygon of the branches' polynomial
pieces (:class:`atlas.boundaries.branches.FundamentalBranches`): the tongue Γ_0 closed along
the band's lower edge (bistable), or the strip between Γ_{−1} and Γ_0 closed along both
edges; it is clipped to the window for each translate by 2πk
(:func:`atlas.kernels.dense_curves.window_areas`). The error is the change from rtol 1e-12 to
1e-13 plus the coordinates' rounding at the window's scale. Units: θ [rad], θ̇ [rad s⁻¹];
fractions of the window's area. Derivation: docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

import math

import numpy as np

from atlas.boundaries.basins import ExactAreas
from atlas.boundaries.branches import FundamentalBranches

__all__ = ["window_areas"]

_TWO_PI = 2.0 * math.pi


def _polygon(f: FundamentalBranches, bistable: bool) -> np.ndarray:
    """Well 0's basin ∩ {bottom < θ̇ < top} (canonical) as a closed curved polygon
    (:mod:`atlas.kernels.dense_curves` pieces): the tongue Γ_0 closed along θ̇ = bottom,
    or the strip between Γ_{−1} and Γ_0 closed along θ̇ = bottom and θ̇ = top."""
    from atlas.kernels.dense_curves import reversed_pieces, segment

    gamma = f.pieces
    first, last = gamma[0, :, 0], gamma[-1, :, :].sum(axis=1)
    if bistable:
        return np.concatenate([gamma, segment(*last, *first)])
    before = gamma.copy()
    before[:, 0, 0] -= _TWO_PI
    return np.concatenate([gamma, segment(*last, last[0] - _TWO_PI, last[1]),
                           reversed_pieces(before),
                           segment(first[0] - _TWO_PI, first[1], *first)])

def _fractions(f: FundamentalBranches, bistable: bool, ks, window):
    """Area fraction of ``window`` (canonical) in well k's basin, for each k in ``ks``:
    the curved polygon clipped to the window, exact for the dense output
    (:func:`atlas.kernels.dense_curves.window_areas`)."""
    from atlas.kernels.dense_curves import window_areas as clipped_areas

    (a, b), (lo, hi) = window
    shifts = _TWO_PI * np.array(ks, np.float64)
    areas = np.empty(shifts.size)
    clipped_areas(_polygon(f, bistable), shifts, a, b, lo, hi, areas)
    return areas / ((b - a) * (hi - lo))

def _area_translates(f: FundamentalBranches, theta_lo: float, theta_hi: float) -> range:
    """Canonical k whose Γ_k may reach θ ∈ [theta_lo, theta_hi] (from the step ends, a
    step's width to spare)."""
    lo, hi = f.theta_range
    return range(math.floor((theta_lo - hi - 1.0) / _TWO_PI),
                 math.ceil((theta_hi - lo + 1.0) / _TWO_PI) + 1)

def window_areas(b) -> ExactAreas:
    """The exact area fraction of the window of ``b`` (a
    :class:`~atlas.boundaries.tilted.TiltedBoundaries`) in each well's basin and in the
    running basin (:class:`atlas.boundaries.exact.ExactAreas`;
    docs/design/tilted-boundaries.md): exact
    for the dense output of the branches at rtol, their error the change from
    RTOL_CHECK plus the rounding of the coordinates at the window's scale (as
    :func:`atlas.boundaries.manifold.basin_areas` has it for small windows). The
    fractions sum to 1 (to their errors)."""
    window = b.canonical_window()
    (t0, t1), (lo, hi) = window
    ks = _area_translates(b.fundamental, t0, t1)
    if not b.bistable:  # the strip of well k lies between Γ_{k−1} and Γ_k
        ks = range(ks.start, ks.stop + 1)
    fine = _fractions(b.fundamental, b.bistable, ks, window)
    coarse = _fractions(b.fundamental_check, b.bistable, ks, window)
    # the coordinates' own rounding at the window's scale (the window's edges, and the
    # translated curves', each to an ulp, over the window's sides): the same for both
    # tolerances, so their change does not show it (a small window's floor)
    big_u = max(abs(t0), abs(t1)) + _TWO_PI * max(abs(ks.start), abs(ks.stop)) + math.pi
    big_v = max(abs(lo), abs(hi))
    rounding = 16 * np.finfo(float).eps * (big_u / (t1 - t0) + big_v / (hi - lo))
    error = np.abs(fine - coarse) + rounding
    running = running_error = 0.0
    if b.bistable:
        running = 1.0 - float(fine.sum())
        running_error = float(abs(fine.sum() - coarse.sum()) + rounding)
    keep = fine > 0.0
    k = b.sign * np.array(ks, np.int64)[keep]
    order = np.argsort(k)
    return ExactAreas(k=k[order], fraction=fine[keep][order], running=running,
                      error=error[keep][order], running_error=running_error)
