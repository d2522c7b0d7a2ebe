"""The checks of traced boundaries: against the exact stable manifold, and the point reflection.

:func:`check_against_stable_manifold` measures the distance [rad-ish] of every traced point
(the RK4 map's boundary at step dt) from the exact boundary it belongs to: the DOP853
reference (:class:`atlas.boundaries.manifold.StableManifold`, rtol = atol = 1e-13), its foot
points by Newton's method on the dense output (accurate to ≈ 1e-13). Its maximum, the
``discrepancy``, is RK4's O(dt⁴) offset (≈ 6e-10 at α = 0.1 s⁻¹, ω0 = 1 rad s⁻¹,
dt = 0.01 s), bounded by :data:`DISCREPANCY_BOUND`; the same curve gives the polyline's own
error. :func:`symmetry_error` compares the located right branch of −π with the reflection of
the located left branch of π (bounded by :data:`SYMMETRY_BOUND` · tol): the trace reflects
the left branch's points and locates every 8th of them again on its own, so the pairs that
differ are those.
Derivation: docs/design/separatrices.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.boundaries.manifold import StableManifold, to_left_branch
from atlas.boundaries.predictor import reference
from atlas.boundaries.window import Window
from atlas.physics.pendulum import Pendulum

__all__ = ["ManifoldCheck", "check_against_stable_manifold", "check", "symmetry_error",
           "DISCREPANCY_BOUND", "SYMMETRY_BOUND"]

#: Largest accepted distance [rad-ish] between bisected points and the DOP853 manifold.
DISCREPANCY_BOUND = 1e-8
#: Largest accepted distance between the bisected right branch of −π and the point reflection of
#: the bisected left branch of π, in units of tol (expected: below 1, see :func:`symmetry_error`).
SYMMETRY_BOUND = 4.0


@dataclass(frozen=True)
class ManifoldCheck:
    """Result of :func:`check_against_stable_manifold`.

    distance:       per point, the distance [rad-ish] to the DOP853 stable manifold.
    polyline_error: largest distance from the DOP853 manifold to the polyline through the
                    points, between consecutive vertices of each branch.
    """

    distance: np.ndarray
    polyline_error: float

    @property
    def discrepancy(self) -> float:
        return float(self.distance.max(initial=0.0))


def check_against_stable_manifold(ds: xr.Dataset) -> ManifoldCheck:
    """Recompute the check of a traced ``/separatrices`` node without torque (see
    :func:`check`) against the same reference: per-point distances to the DOP853 stable
    manifold, polyline error."""
    if float(ds.attrs.get("torque", 0.0)) != 0.0:
        raise ValueError("a /separatrices node with torque: its check is the tilted trace's "
                         "discrepancy, against atlas.boundaries.tilted (this one is the "
                         "untilted manifold's)")
    p = Pendulum(float(ds.attrs["alpha"]), float(ds.attrs["omega0"]))
    window = Window(tuple(ds.attrs["theta_window"]), tuple(ds.attrs["theta_dot_window"]))
    return check(reference(p, window), ds["saddle_n"].values, ds["branch"].values,
                 ds["vertex"].values, ds["theta"].values, ds["theta_dot"].values)


def check(m: StableManifold, saddle_n, branch, vertex, theta, theta_dot) -> ManifoldCheck:
    """Traced separatrix points against the exact stable manifolds of
    :mod:`atlas.boundaries.manifold`.

    Each point of the branch (n, left|right) is mapped into the frame of L, the left branch of
    π (:func:`atlas.boundaries.manifold.to_left_branch`, an isometry), and its distance to L is
    that of its foot point on ``m``'s dense output
    (:meth:`~atlas.boundaries.manifold.StableManifold.foot_points`, accurate to ≈ 1e-13).
    ``branch`` holds flag values (0 left, 1 right); ``vertex`` orders the points of a branch,
    and the polyline joins consecutive vertices only (a branch may leave the window and come
    back: the points in between are not stored); the manifold is sampled at 15 points between
    the foot points of each pair, and their largest distance to the chord is
    ``polyline_error``.
    """
    saddle_n, branch, vertex = (np.asarray(a, np.int64) for a in (saddle_n, branch, vertex))
    theta, theta_dot = np.asarray(theta, float), np.asarray(theta_dot, float)
    if theta.size == 0:
        return ManifoldCheck(np.zeros(0), 0.0)
    x, v = to_left_branch(saddle_n, branch == 1, theta, theta_dot)
    t, distance = m.foot_points(x, v)

    # polyline: sample the manifold between consecutive vertices, distance to the chord
    order = np.lexsort((vertex, branch, saddle_n))
    same = ((np.diff(saddle_n[order]) == 0) & (np.diff(branch[order]) == 0)
            & (np.diff(vertex[order]) == 1))
    i0, i1 = order[:-1][same], order[1:][same]
    frac = np.linspace(0.0, 1.0, 17)[1:-1]
    ts = t[i0, None] + (t[i1] - t[i0])[:, None] * frac
    cx, cv = m.at(ts)
    ax, av, bx, bv = x[i0, None], v[i0, None], x[i1, None], v[i1, None]
    ex, ev = bx - ax, bv - av
    s = np.clip(((cx - ax) * ex + (cv - av) * ev) / (ex * ex + ev * ev), 0.0, 1.0)
    chord = np.hypot(ax + s * ex - cx, av + s * ev - cv)
    return ManifoldCheck(distance, float(chord.max(initial=0.0)))


def symmetry_error(branch: np.ndarray, vertex: np.ndarray, point: np.ndarray) -> float:
    """Largest distance [rad-ish] between a located point of the right branch of −π (branch 1)
    and the point reflection of the located point of the left branch of π (branch 0) with the
    same vertex index; NaN if they share none (one source only).

    The predicted vertices of the right branch are the reflections of those of the left one,
    and the normal of a pair is one vector (the vector field is odd), so both brackets lie on
    one line; if the label boundary is symmetric, as eq. (1) is, both brackets — each
    narrower than tol — hold its crossing with that line and the midpoints differ by less than
    tol. The bisection's sample points are symmetric about the vertex too, so labels that are
    odd in floating point give an error at rounding level; labels that break the symmetry
    show as an error of order tol or more."""
    left, right = branch == 0, branch == 1
    _, i, j = np.intersect1d(vertex[left], vertex[right], return_indices=True)
    if i.size == 0:
        return math.nan
    gap = point[left][i] + point[right][j]
    return float(np.hypot(gap[:, 0], gap[:, 1]).max())
