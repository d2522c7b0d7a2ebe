"""The traced separatrices with torque 0 < |τ| < ω0²: every branch located on its own.

With a torque the point reflection is gone and the branches fold, so every boundary in the
window is located, not copied: vertices about ``max_spacing`` apart on the exact tilted
boundaries (:class:`atlas.boundaries.tilted.TiltedBoundaries`, DOP853), each located across
the curve, along the normal of the vector field, to a bracket narrower than ``tol``
[rad-ish]: by shooting its segment to its saddle (:mod:`atlas.boundaries.shooting`: the
saddle's stable manifold of the RK4 map crosses it; every 16th vertex of a run from the
exact curve, the others from splines of those, with Newton steps), and where that cannot certify
it, by bisection on certified RK4 labels (the tilted trap and the running barrier) between
the exact sides read at ±1e-3 (well k or the running basin) (:func:`_locate`). The
2π shift is checked on relocated copies (``shift_error``); ``discrepancy``, the located
points' largest distance from the exact boundaries, is the RK4 map's boundary shift (≈ 1e-9
at dt = 0.01 s) that sets d_cert.
Same ``/separatrices`` schema as without torque (:mod:`atlas.store.separatrices`).
Derivation: docs/design/separatrices.md.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.boundaries.basins import RUNNING_SIDE
from atlas.boundaries.bisection import (
    MAX_BRACKET,
    Labeller,
    bisect_between,
    field_normal,
    linger,
)
from atlas.boundaries.check import DISCREPANCY_BOUND, SYMMETRY_BOUND
from atlas.boundaries.crossings import PROBE, tilted_crossings
from atlas.boundaries.predictor import fine_spacing
from atlas.boundaries.segments import segment_distance
from atlas.boundaries.shooting import HALF_WIDTH, Shooter, left_to_labels
from atlas.boundaries.tilted import SLACK
from atlas.boundaries.window import Window
from atlas.physics.pendulum import Pendulum
from atlas.store import separatrices as schema

__all__ = ["trace_tilted", "trace_tilted_boundaries"]

_SHIFT_STRIDE = 8  # every 8th located vertex is located again on its 2π-shifted copy
_FIRST_VERTEX = 1e-3  # no vertex closer [rad-ish] to its saddle: the field vanishes there


def trace_tilted_boundaries(p: Pendulum, window: Window, exact, barrier, **settings
                            ) -> xr.Dataset:
    """:func:`trace_tilted` on the :class:`atlas.boundaries.tilted.TiltedBoundaries` behind
    ``exact`` (an :class:`atlas.boundaries.exact.TiltedExact`): the tilted family's entry in
    :data:`atlas.boundaries.trace.TRACES`."""
    return trace_tilted(p, window, exact.tilted, barrier, **settings)


def trace_tilted(p: Pendulum, window: Window, exact, barrier, *, tol: float,
                 max_spacing: float, dt: float, t_max: float, backend: str,
                 method: str) -> xr.Dataset:
    """The basin boundaries of the RK4 map for a pendulum with torque 0 < |τ| < ω0²
    (:func:`atlas.boundaries.trace.trace`'s settings; ``t_max`` [s] the atlas's, to which the
    lingering time at a saddle is added) over ``window``, predicted by ``exact``, the
    window's :class:`atlas.boundaries.tilted.TiltedBoundaries`; ``barrier``: the running
    barrier to label with (None: none).

    Vertices are taken along each branch in the window about ``max_spacing`` apart (the first
    polyline vertex at or beyond each multiple of it along the branch, so at most max_spacing
    + :data:`atlas.boundaries.tilted.MAX_SEGMENT`; none closer than 1e-3 to its saddle, where
    the vector field that gives the normal vanishes); vertices whose exact sides agree at
    ±1e-3 (a tongue thinner than that) are skipped and counted (``n_skipped``). Nothing is
    copied: every branch in the window is located on its own, so the 2π shift, the
    symmetry that holds with torque, is checked, not assumed: ``shift_error`` is the largest
    distance between a located point and the located point of the same source vertex on the
    neighbouring copy, shifted by 2π (the point reflection of the untilted pendulum does not
    hold: ``symmetry_error`` is NaN). Crossings of the axis θ0 = 0 are located the same way
    along θ̇ (:func:`atlas.boundaries.crossings.tilted_crossings`); a running side is stored
    as :data:`atlas.boundaries.exact.RUNNING_SIDE` in ``k_below``/``k_above``.

    ``saddle_n`` = 2j + 1 for the saddle π − θ* + 2πj, the one near (2j + 1)π; attributes as
    without torque, plus ``torque``, ``shift_error``, ``shift_pairs``, ``n_skipped`` and
    ``reference_error`` (the exact boundaries' own error: DOP853's, from rtol 1e-12 to 1e-13;
    sides and distances are the dense output's). ``polyline_error``, as without torque, is
    the largest distance of the exact boundary from the polyline through the stored points
    (:func:`_vertices`).
    """
    labels = Labeller(p, dt, t_max + linger(p, tol), backend, method, barrier)
    shooter = Shooter(p, tol, dt=dt, t_max=labels.t_max, method=method)
    saddle_j, branch, vertex, arc, base, sagitta = _vertices(exact, window, max_spacing)
    normal = np.column_stack(field_normal(p, base[:, 0], base[:, 1])) if base.size \
        else base.copy()
    # the exact sides at ±PROBE along the normal, from one search
    below, above = exact.side(base[:, 0] + np.array([[-PROBE], [PROBE]]) * normal[:, 0],
                              base[:, 1] + np.array([[-PROBE], [PROBE]]) * normal[:, 1])
    # a vertex whose exact sides agree at ±PROBE (a tongue thinner than that, or a fold)
    # has no boundary to bisect across there: it is left out, and counted
    keep = below != above
    skipped = int((~keep).sum())
    saddle_j, branch, vertex, arc = saddle_j[keep], branch[keep], vertex[keep], arc[keep]
    base, normal, below, above = base[keep], normal[keep], below[keep], above[keep]
    run = np.cumsum(np.r_[True, (np.diff(saddle_j) != 0) | (np.diff(branch) != 0)
                          | (np.diff(vertex) != 1)]) if vertex.size else vertex
    saddle_theta = p.saddle_angle + 2.0 * math.pi * saddle_j  # exact.saddle_theta(j)
    lo, hi, ok, at = _locate(shooter, labels, base, normal, below, above, saddle_theta, run,
                             arc, tol)
    point = base + at[:, None] * normal
    dist, _ = exact.distance(point[:, 0], point[:, 1]) if point.size else (np.zeros(0), None)
    # a vertex that could not be located leaves the shift unmeasured there: NaN, so that d_cert
    # is NaN and no label is certified for the exact equation on a partial measurement
    discrepancy = float(dist.max(initial=0.0)) if ok.all() else math.nan
    shift_error, shift_pairs = _shift_error(shooter, labels, base, normal, below, above,
                                            saddle_theta, point, ok, tol)

    crossing, crossing_width, k_below, k_above = tilted_crossings(exact, labels, shooter, window,
                                                                  tol)
    problems = []
    if not ok.all():
        problems.append(f"{int((~ok).sum())} of {ok.size} vertices could not be bisected to "
                        f"tol = {tol:g} on certified labels (unresolved orbits, a third "
                        f"basin in the bracket, or a boundary shift beyond {MAX_BRACKET:g}: "
                        "lower dt); the RK4 map's boundary shift is not measured (NaN), so no "
                        "label is certified for the exact equation")
    if discrepancy > DISCREPANCY_BOUND:
        problems.append(f"separatrix points are up to {discrepancy:.2e} from the DOP853 "
                        f"stable manifolds (bound {DISCREPANCY_BOUND:.0e}): lower dt")
    stored_n = (2 * saddle_j + 1).astype(np.int32)
    order = np.lexsort((vertex, branch, stored_n))
    return schema.node(
        theta=point[order, 0], theta_dot=point[order, 1], width=(hi - lo)[order],
        crossing=crossing, crossing_width=crossing_width, k_below=k_below, k_above=k_above,
        in_window=np.ones(crossing.size, np.int8), saddle_theta=saddle_theta[order],
        saddle_n=stored_n[order], branch=branch[order], vertex=vertex[order],
        saddle_name="theta of the saddle (pi - asin(torque/omega0^2) + 2 pi j, 0), n = 2j + 1",
        branch_comment="left: arrives with theta_dot > 0 from the left; right: arrives with "
                       "theta_dot < 0 from the right",
        k_comment=f"{RUNNING_SIDE}: the running basin",
        attrs={
            "alpha": p.alpha, "omega0": p.omega0, "torque": p.torque,
            "theta_window": np.array(window.theta),
            "theta_dot_window": np.array(window.theta_dot),
            "tol": float(tol), "max_spacing": float(max_spacing), "dt": float(dt),
            "t_max": labels.t_max,
            "n_boundaries": int(np.unique(stored_n).size),
            "symmetry_error": math.nan, "symmetry_bound": SYMMETRY_BOUND * tol,
            "shift_error": shift_error, "shift_pairs": np.int64(shift_pairs),
            "n_skipped": np.int64(skipped),
            "discrepancy": discrepancy, "discrepancy_bound": DISCREPANCY_BOUND,
            "polyline_error": sagitta,
            "reference_error": exact.reference_error,
            "n_orbits": labels.orbits + shooter.shots, "n_shots": shooter.shots,
            "rounding": shooter.rounding, "n_unresolved": labels.unresolved,
            "warnings": "\n".join(problems),
            "method": (
                f"basin boundaries of the RK4 map (step dt, method {method}) with torque: "
                "vertices on the exact stable branches of the tilted saddles "
                "(atlas.boundaries.tilted: "
                "DOP853 in reversed time, rtol = atol = 1e-13), at most max_spacing apart; "
                "each located across the curve to a bracket narrower than tol: by shooting "
                "its segment to the saddle (the stable manifold of the RK4 map crosses it: "
                "cone conditions in the saddle's box; Newton steps from the exact curve, "
                "every 16th vertex, and from splines, the others), else by bisection on "
                "certified RK4 labels (tilted trap, running barrier); every copy located on "
                "its own (shift_error: the 2 pi shift between copies); discrepancy = max "
                "distance of the points to the exact boundaries"),
        },
    )


def _vertices(exact, window: Window, max_spacing: float):
    """The vertices to locate: (saddle j, branch flag, vertex number along the branch — gaps
    outside the window —, arc length from the saddle [rad-ish], (θ, θ̇) (N, 2)) of every
    branch in the window, about ``max_spacing`` apart along it; and the polyline error, the
    largest distance of the branch from the chord of two consecutive vertices (its search
    polyline's vertices between them, points of the branch, against that chord; the
    located points lie ≈ 1e-9 from the vertices; a small window's extra points, ``fine``
    apart, are left out: their chords stray by less than fine²/8 per rad of curvature)."""
    parts = []  # (saddle j, branch, vertex numbers, θ, θ̇, arc lengths) per branch
    fine = fine_spacing(window)
    arcs = {}  # every translate of a branch has its arc lengths and picks: computed once
    sagitta = 0.0
    for j, name, vertices, on_curve in exact.branches():  # only the picks shifted to Γ_k
        if name not in arcs:
            theta, theta_dot = vertices()
            step = np.hypot(np.diff(theta), np.diff(theta_dot))
            along = np.concatenate([[0.0], np.cumsum(step)])
            picks = np.unique(np.searchsorted(along, np.arange(_FIRST_VERTEX, along[-1],
                                                               max_spacing)))
            arcs[name] = along, picks[picks < theta.size], theta, theta_dot
        along, picks, theta, theta_dot = arcs[name]
        pos, (x, v) = along[picks], vertices(picks)
        if fine < max_spacing:  # a small window: points on the branch, ``fine`` apart
            pos, x, v = _fine_points(window, fine, along, *vertices(), on_curve,
                                     SLACK * exact.chord_error, pos, x, v)
        number = np.flatnonzero(window.margin(x, v) >= 0)  # along the branch: gaps outside
        if fine >= max_spacing:  # the chords between consecutive picks in the window (their
            pair = number[:-1][np.diff(number) == 1]  # shape shift-invariant: Γ_0's)
            sagitta = max(sagitta, _sagitta(theta, theta_dot, picks[pair], picks[pair + 1]))
        parts.append((np.full(number.size, j, np.int64),
                      np.full(number.size, schema.BRANCHES.index(name), np.int8),
                      number.astype(np.int32), x[number], v[number], pos[number]))

    def cat(i, dtype):
        return np.concatenate([q[i] for q in parts]).astype(dtype) if parts \
            else np.zeros(0, dtype)

    base = np.column_stack([cat(3, float), cat(4, float)]).reshape(-1, 2)
    return cat(0, np.int64), cat(1, np.int8), cat(2, np.int32), cat(5, float), base, sagitta


def _sagitta(theta, theta_dot, a, b) -> float:
    """The largest distance [rad-ish] of the polyline vertices strictly between ``a[k]`` and
    ``b[k]`` (indices into ``theta``, ``theta_dot``, increasing; each pair's b the next's a
    or less) from the chord (a[k], b[k]), over k; 0 for no pair."""
    if not a.size:
        return 0.0
    m = np.arange(int(a.min()) + 1, int(b.max()))
    k = np.searchsorted(a, m, side="right") - 1
    keep = (k >= 0) & (m < b[np.maximum(k, 0)])
    m, k = m[keep], k[keep]
    if not m.size:
        return 0.0
    dist = segment_distance(theta[m], theta_dot[m], theta[a[k]], theta_dot[a[k]],
                            theta[b[k]], theta_dot[b[k]])
    return float(dist.max())


def _fine_points(window: Window, fine: float, along, theta, theta_dot, on_curve,
                 stray: float, pos, x, v):
    """The picks (arc length ``pos``, θ ``x``, θ̇ ``v``) of a branch's polyline (arc
    lengths ``along`` at its vertices ``theta``, ``theta_dot``), with points added on the
    branch itself (``on_curve``: :meth:`atlas.boundaries.tilted.TiltedBoundaries.branches`)
    along the chords that come within ``fine`` + ``stray`` [rad-ish] of the window (the
    branch strays from its chords by ``stray`` at most), ``fine`` apart along them (from ``fine``
    off the saddle: there the branch is the stable eigenvector, to O(START_DISTANCE²));
    sorted along the branch."""
    (t0, t1), (v0, v1) = window.box
    ax, av, bx, bv = theta[:-1], theta_dot[:-1], theta[1:], theta_dot[1:]
    reach = fine + stray
    near = ((np.maximum(ax, bx) >= t0 - reach) & (np.minimum(ax, bx) <= t1 + reach)
            & (np.maximum(av, bv) >= v0 - reach) & (np.minimum(av, bv) <= v1 + reach))
    extra = [np.arange(math.ceil(max(along[i], fine) / fine), math.floor(along[i + 1] / fine)
                       + 1) * fine for i in np.flatnonzero(near)]
    if not extra:
        return pos, x, v
    s = np.concatenate(extra)
    s = s[(s > 0) & (s <= along[-1])]
    seg = np.clip(np.searchsorted(along, s) - 1, 0, along.size - 2)
    f = (s - along[seg]) / np.where(along[seg + 1] > along[seg], along[seg + 1] - along[seg],
                                    1.0)
    sx, sv = on_curve(seg, f)
    order = np.argsort(np.concatenate([pos, s]), kind="stable")
    return (np.concatenate([pos, s])[order], np.concatenate([x, sx])[order],
            np.concatenate([v, sv])[order])


def _locate(shooter, labels, base, normal, below, above, saddle, run, arc, tol: float):
    """Locate every vertex by shooting (:meth:`atlas.boundaries.shooting.Shooter.locate`:
    one orbit per vertex, two for every 16th, from the exact curve and splines); those it
    cannot certify are bisected on certified labels, from ±HALF_WIDTH·tol around a shot's
    Newton estimate, else from ±FIRST_BRACKET·tol around the exact curve, widened ×8 while
    an end carries the other side (the RK4 map's boundary lies O(dt⁴) ≈ 1e-9 from the exact
    one). Returns (s_lo, s_hi, ok, s) along ``normal`` from ``base``: the bracket as
    :func:`atlas.boundaries.bisection.bisect_between`, and the point in it (a certified
    shot's Newton estimate — within its bracket, more accurate than its midpoint —, else
    the midpoint)."""
    lo, hi, ok, estimate = shooter.locate(base, normal, saddle, run, arc)
    shot = ok.copy()
    for again, centre, half_width in left_to_labels(shot, estimate, tol):
        g_lo, g_hi, ok[again] = bisect_between(
            labels, base[again] + centre[:, None] * normal[again], normal[again],
            below[again], above[again], tol=tol, half_width=half_width)
        lo[again], hi[again] = centre + g_lo, centre + g_hi
    return lo, hi, ok, np.where(shot, estimate, 0.5 * (lo + hi))


def _shift_error(shooter, labels, base, normal, below, above, saddle, point, ok,
                 tol: float):
    """The 2π shift: every ``_SHIFT_STRIDE``-th located vertex, shifted by 2π and located
    again on its own (the next saddle's stable manifold: shot from the shifted point, or, if
    that cannot be certified, bisected on labels of the next well's side), must land on the
    shifted point. Returns (largest distance [rad-ish] plus the copy's bracket half-width,
    number of pairs compared)."""
    pick = np.flatnonzero(ok)[::_SHIFT_STRIDE]
    shifted = base[pick] + np.array([2.0 * math.pi, 0.0])
    along = normal[pick]
    # the 2π shift predicts the copy's point (the RK4 map is 2π-periodic in θ, to
    # rounding): its segment is centred on the located one's offset
    offset = np.einsum("ij,ij->i", point[pick] - base[pick], along)
    # shot in the next saddle's frame: θ kept within π of it, so the copy's orbits round
    # differently from the located ones (in one frame the copy would be the same orbit)
    s_lo, s_hi, s_ok, s_at = shooter.refine(shifted, along, offset,
                                            saddle[pick] + 2.0 * math.pi, frame=1)
    s_at = np.where(s_ok, s_at, np.nan)
    again = np.flatnonzero(~s_ok)
    if again.size:

        def next_well(side):
            return np.where(side == RUNNING_SIDE, side, side + 1)

        g_lo, g_hi, s_ok[again] = bisect_between(
            labels, shifted[again] + offset[again, None] * along[again], along[again],
            next_well(below[pick[again]]), next_well(above[pick[again]]), tol=tol,
            half_width=HALF_WIDTH * tol)
        s_lo[again], s_hi[again] = offset[again] + g_lo, offset[again] + g_hi
    moved = shifted + np.where(np.isnan(s_at), 0.5 * (s_lo + s_hi), s_at)[:, None] * along
    # the copy's midpoint may sit exactly on the prediction: its bracket's half-width is
    # the resolution of the comparison
    gap = np.hypot(*(moved - point[pick] - np.array([2.0 * math.pi, 0.0])).T) \
        + 0.5 * (s_hi - s_lo)
    return float(gap[s_ok].max(initial=0.0)), int(s_ok.sum())
