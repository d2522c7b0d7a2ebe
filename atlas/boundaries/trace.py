"""The traced separatrices: the basin boundaries of the RK4 map, located by shooting or bisection.

:func:`trace` is the one entry point, for every torque: it locates, to ``tol`` [rad-ish],
every basin boundary of the RK4 map at step dt (the curves that colour the basin map) that
enters the window — by shooting each point's segment to its saddle
(:mod:`atlas.boundaries.shooting`: a certificate that the saddle's stable manifold crosses
it), or, where that cannot certify it or for method "rk4-trigfree", by bisection on
certified labels (:mod:`atlas.boundaries.bisection`) — predicted by the exact boundaries
(:func:`atlas.boundaries.exact.exact_boundaries`), and checks them against those. Without
torque only the left branch of (π, 0) and the right branch of (−π, 0) are located and every
other boundary is a 2π copy (here); with torque every branch in the window is located on
its own labels (:mod:`atlas.boundaries.trace_tilted`); without rest states there is none.
Accuracy: the located curve differs from the exact one by RK4's O(dt⁴) (the ``discrepancy``,
≈ 6e-10 at α = 0.1 s⁻¹, ω0 = 1 rad s⁻¹, dt = 0.01 s), not by bisection error. The result is
the ``/separatrices`` node (:mod:`atlas.store.separatrices`). References: Nusse & Yorke,
Physica D 36 (1989) 137; Krauskopf et al., Int. J. Bifurcation Chaos 15 (2005) 763; Hairer,
Nørsett & Wanner, *Solving ODEs I*, §II.5–6. Derivation: docs/design/separatrices.md.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from atlas import defaults, lazy_dask  # noqa: F401 (lazy_dask installs itself)
from atlas.boundaries.bisection import (
    Labeller,
    bisect_across,
    field_normal,
    linger,
    locate,
)
from atlas.boundaries.certificate import cert_distance
from atlas.boundaries.check import DISCREPANCY_BOUND, SYMMETRY_BOUND, check, symmetry_error
from atlas.boundaries.crossings import axis_crossings
from atlas.boundaries.exact import ExactBoundaries, exact_boundaries
from atlas.boundaries.predictor import (
    edge_speeds,
    fine_spacing,
    needed,
    place,
    predict,
    reference,
    sources,
    window_boxes,
)
from atlas.boundaries.shooting import Shooter, left_to_labels
from atlas.boundaries.trace_tilted import trace_tilted_boundaries
from atlas.boundaries.window import Window, checked_window
from atlas.physics.pendulum import Pendulum
from atlas.store import separatrices as schema

__all__ = ["trace", "TRACES"]

#: Every 8th vertex of the right branch of −π that is a reflection of a located one is
#: located again on its own: the symmetry check.
_SYMMETRY_STRIDE = 8


def trace(
    pendulum: Pendulum,
    theta_window,
    theta_dot_window,
    *,
    tol: float = defaults.SEPARATRIX_TOL,
    max_spacing: float = defaults.MAX_SPACING,
    dt: float = defaults.DT,
    t_max: float = defaults.T_MAX,
    backend: str = "cpu",
    method: str = defaults.METHOD,
    exact: ExactBoundaries | None = None,
    barrier=None,
) -> xr.Dataset | None:
    """Trace every basin boundary in the window: the branches of the stable manifolds of the
    saddles, inside the window or not, that enter it. None for a pendulum without rest states
    (|τ| > ω0²: no saddle, no boundary).

    ``theta_window`` = (θmin, θmax) [rad], ``theta_dot_window`` = (θ̇min, θ̇max) [rad s⁻¹];
    ``tol``: bisection tolerance, the width [rad-ish] across the curve below which a point is
    accepted; ``max_spacing``: largest distance between vertices (the chord error stays below
    max_spacing²/8); ``dt`` [s]: RK4 step of the labels, the same as the basin map's;
    ``method``: their discretisation (:data:`atlas.kernels.METHODS`), the basin map's;
    ``t_max`` [s]: the atlas's, to which the lingering time at a saddle is added (with torque;
    without, the labels' t_max is the predictor's travel time plus that lingering time).
    ``exact``: the window's exact boundaries (:func:`atlas.boundaries.exact.exact_boundaries`)
    if the caller built them, with ``barrier`` the running barrier to label with (None: none);
    built here otherwise.

    Returns the ``/separatrices`` node (:func:`atlas.store.separatrices.node`): per ``point``
    the coordinates ``saddle_theta``, ``saddle_n``, ``branch`` (0 left, 1 right), ``vertex``
    and the variables ``theta``, ``theta_dot``, ``bracket_width``; per ``crossing`` of the
    axis θ0 = 0 the variables ``crossing_theta_dot``, ``k_below``, ``k_above``,
    ``crossing_bracket_width``, ``crossing_in_window``; attributes: ``alpha``, ``omega0``, the
    windows, ``tol``, ``max_spacing``, ``dt``, ``t_max``, ``n_boundaries``,
    ``symmetry_error``, ``symmetry_bound``, ``discrepancy``, ``discrepancy_bound``,
    ``polyline_error``, ``n_orbits`` (every orbit integrated), ``n_shots`` (those shot to a
    saddle), ``rounding`` (the largest rounding estimate [rad-ish] of a shot that located a
    point, :mod:`atlas.boundaries.shooting`; half the bracket plus it is within tol),
    ``n_unresolved``, ``warnings`` (lines joined by "\\n",
    read with :func:`atlas.store.separatrices.warnings`) and ``method`` (with torque also
    ``torque``, ``shift_error``, ``shift_pairs``, ``n_skipped``, ``reference_error``).
    Raises ValueError for α = 0, a bad window, dt or settings
    (:func:`atlas.limits.check_separatrix_settings`);
    :class:`~atlas.errors.SeparatrixError` (an :class:`~atlas.errors.AtlasError`) if a point
    or branch cannot be certified during the run.
    """
    p = pendulum
    window = checked_window(p, theta_window, theta_dot_window, tol, max_spacing, dt)
    settings = {"tol": tol, "max_spacing": max_spacing, "dt": dt, "backend": backend,
                "method": method}
    built = exact is None
    exact = exact_boundaries(p, window.box) if built else exact
    if not exact.has_boundary:
        return None
    if built and exact.cycle is not None:
        from atlas.physics.running import running_barrier

        barrier = running_barrier(p.alpha, p.omega0, p.torque, exact.cycle, dt=dt)
    traced = TRACES[exact.traced_as](p, window, exact, barrier, t_max=t_max, **settings)
    return unmeasured_shift(traced, window, exact)


def unmeasured_shift(ds: xr.Dataset, window: Window, exact: ExactBoundaries) -> xr.Dataset:
    """``ds`` with its ``discrepancy`` (the measured shift d_cert is built on) NaN, and a
    warning saying why, when no traced point lies in the window although an exact boundary
    comes within reach of it: the largest d_cert any accepted trace could give,
    SAFETY·(DISCREPANCY_BOUND + tol + reference error). Beyond that reach every label of the
    window is certified alike whatever the shift, so an empty trace keeps its 0 there."""
    inside = window.margin(ds["theta"].values, ds["theta_dot"].values) >= 0
    if inside.any():
        return ds
    (t0, t1), (v0, v1) = window.box
    centre_dist, _ = exact.distance(np.array([0.5 * (t0 + t1)]), np.array([0.5 * (v0 + v1)]))
    clearance = float(centre_dist[0]) - 0.5 * math.hypot(t1 - t0, v1 - v0)
    reach = cert_distance(DISCREPANCY_BOUND, float(ds.attrs["tol"]), exact.reference_error)
    if clearance > reach:
        return ds
    line = ("no point of a basin boundary could be located in the window although one "
            f"passes within {max(clearance, 0.0):.1e} of it (d_cert would need its shift): "
            "the RK4 map's boundary shift is not measured (NaN), so no label is certified "
            "for the exact equation")
    warnings = "\n".join(filter(None, [str(ds.attrs.get("warnings", "")), line]))
    return ds.assign_attrs(discrepancy=math.nan, warnings=warnings)


def _locate(shooter, labels, base, normal, saddle_n, run, tau, tol: float):
    """Locate every vertex (on the stable manifold of the saddle (nπ, 0), n = ``saddle_n``)
    by shooting (:meth:`atlas.boundaries.shooting.Shooter.locate`), and bisect those it
    cannot certify on certified labels, from ±HALF_WIDTH·tol around a shot's Newton
    estimate, else from ±FIRST_BRACKET·tol around the exact curve; for a
    method the shots do not integrate, bisect every vertex
    (:func:`atlas.boundaries.bisection.locate`). Returns (s_lo, s_hi, s) along ``normal``:
    the bracket, and the point in it (a certified shot's Newton estimate — within its
    bracket, more accurate than its midpoint —, else the midpoint)."""
    k = (saddle_n + 1) // 2
    if shooter.box is None:
        lo, hi = locate(labels, base, normal, k, run, tau, tol)
        return lo, hi, 0.5 * (lo + hi)
    lo, hi, ok, estimate = shooter.locate(base, normal, saddle_n * math.pi, run, tau)
    for bad, centre, half_width in left_to_labels(ok, estimate, tol):
        b_lo, b_hi = bisect_across(labels, base[bad] + centre[:, None] * normal[bad],
                                   normal[bad], k[bad], tol=tol, strict=False,
                                   half_width=half_width)
        lo[bad], hi[bad] = centre + b_lo, centre + b_hi
    return lo, hi, np.where(ok, estimate, 0.5 * (lo + hi))


def _twins(branch: np.ndarray, vertex: np.ndarray) -> np.ndarray:
    """For each vertex of the right branch of −π (branch 1), the row of the left branch of
    π's vertex with the same number (its reflection: the predicted right branch is the
    reflected left one, vertex by vertex); −1 elsewhere."""
    twin = np.full(branch.size, -1, np.int64)
    left, right = np.flatnonzero(branch == 0), np.flatnonzero(branch == 1)
    _, i, j = np.intersect1d(vertex[left], vertex[right], return_indices=True)
    twin[right[j]] = left[i]
    return twin


def _relocate(shooter, labels, base, normal, saddle_n, rows, tol: float, lo, hi, at):
    """Locate the vertices ``rows`` on their own (in place of their twins' reflections, so
    that the symmetry error measures the map's oddness there): shot around the twin's point
    (in the frame of π, so that their orbits round otherwise than the twins'), or, where
    that cannot certify them, bisected on labels from ±HALF_WIDTH·tol around it."""
    if not rows.size:
        return
    s_lo, s_hi, s_ok, s_at = shooter.refine(base[rows], normal[rows], at[rows],
                                            saddle_n[rows] * math.pi)
    guess = np.where(np.isfinite(s_at), s_at, at[rows])  # a shot's estimate, else the twin's
    for bad, centre, half_width in left_to_labels(s_ok, guess, tol):
        b_lo, b_hi = bisect_across(labels, base[rows[bad]] + centre[:, None]
                                   * normal[rows[bad]], normal[rows[bad]],
                                   (saddle_n[rows[bad]] + 1) // 2, tol=tol, strict=False,
                                   half_width=half_width)
        s_lo[bad], s_hi[bad] = centre + b_lo, centre + b_hi
    lo[rows], hi[rows] = s_lo, s_hi
    at[rows] = np.where(s_ok, s_at, 0.5 * (s_lo + s_hi))


def _trace_untilted(p: Pendulum, window: Window, exact, barrier, *, tol: float,
                    max_spacing: float, dt: float, t_max: float, backend: str,
                    method: str) -> xr.Dataset:
    """:func:`trace` without torque: the left branch L of π and the right branch R = −L of
    −π, predicted on the exact manifold (:mod:`atlas.boundaries.predictor`), located on
    certified labels (:func:`atlas.boundaries.bisection.locate`), placed in the window by
    their 2π copies and checked (:mod:`atlas.boundaries.check`). ``exact``, ``barrier`` and
    ``t_max`` are not needed: the manifold is its own predictor, there is no running cycle,
    and each label's t_max is the predictor's travel time plus the lingering time."""
    # the two source branches, over the stretch their copies in the window use: vertices on
    # the exact left branch of π, and their reflections for the right branch of −π
    ref = reference(p, window)
    left = predict(ref, edge_speeds(window), max_spacing, window_boxes(ref, window),
                   fine_spacing(window))
    grown = [g for b in sources(window)
             if (g := needed(left if b == "left" else left.reflected(), window)).theta.size]

    def cat(f):
        return np.concatenate([f(r, g) for r, g in enumerate(grown)]) if grown else np.zeros(0)

    run = cat(lambda r, g: np.full(g.theta.size, r)).astype(np.int32)
    saddle_n = cat(lambda r, g: np.full(g.theta.size, g.n)).astype(np.int32)
    branch = cat(lambda r, g: np.full(g.theta.size, schema.BRANCHES.index(g.branch))
                 ).astype(np.int8)
    vertex = cat(lambda r, g: g.vertex).astype(np.int32)
    base = np.column_stack([cat(lambda r, g: g.theta), cat(lambda r, g: g.theta_dot)])
    tau = cat(lambda r, g: g.tau)

    # vertices: t_max covers their travel τ and lingering down to δ ≈ tol²; unresolved ones
    # are stuck in floating point (see Labeller), so a longer t_max would not help them
    labels = Labeller(p, dt, tau.max(initial=0.0) + linger(p, tol), backend, method)
    shooter = Shooter(p, tol, dt=dt, t_max=labels.t_max, method=method)
    normal = np.column_stack(field_normal(p, base[:, 0], base[:, 1]))
    # the right branch's vertices whose left twin is located too are its reflections (the
    # RK4 map is odd; a pair shares its normal, so the offsets change sign): located once,
    # every _SYMMETRY_STRIDE-th checked on its own
    twin = _twins(branch, vertex) if shooter.box is not None else np.full(branch.size, -1)
    own = twin < 0
    lo, hi, at = np.empty(run.size), np.empty(run.size), np.empty(run.size)
    lo[own], hi[own], at[own] = _locate(shooter, labels, base[own], normal[own],
                                        saddle_n[own], run[own], tau[own], tol)
    mirrored = np.flatnonzero(~own)
    lo[mirrored], hi[mirrored], at[mirrored] = (-a[twin[mirrored]] for a in (hi, lo, at))
    relocated = mirrored[::_SYMMETRY_STRIDE]
    _relocate(shooter, labels, base, normal, saddle_n, relocated, tol, lo, hi, at)
    point = base + at[:, None] * normal
    symmetry = symmetry_error(branch, vertex, point)
    # pairs located independently: the mirrored ones checked, or all where none is mirrored
    pairs = relocated.size if mirrored.size else int(np.isin(
        vertex[branch == 1], vertex[branch == 0]).sum())
    source, copy = place(run, point, window)
    stored_n = (saddle_n[source] + 2 * copy).astype(np.int32)
    order = np.lexsort((vertex[source], branch[source], stored_n))
    source, copy, stored_n = source[order], copy[order], stored_n[order]
    stored_theta = point[source, 0] + 2.0 * math.pi * copy
    checked = check(ref, stored_n, branch[source], vertex[source], stored_theta,
                    point[source, 1])
    saddles = np.unique(stored_n).astype(np.int64)
    crossing, crossing_width, k_above, axis_labels, axis_shots = axis_crossings(
        ref, saddles, tol, dt, backend, method)
    crossing_in_window = (window.margin(0.0, crossing) >= 0).astype(np.int8)

    problems = []
    nonfinite = labels.nonfinite + axis_labels.nonfinite
    if nonfinite:
        problems.append(f"{nonfinite} orbits met NaN/inf (dt = {dt:g} s unstable?); they "
                        "were left out of the bisection")
    widths = np.concatenate([hi - lo, crossing_width])
    if np.any(widths >= tol):
        problems.append(
            f"{int(np.sum(widths >= tol))} points could not be bracketed below tol = {tol:g} "
            f"(widest {widths.max():.1e}): certified labels stop short of the curve where "
            "orbits stall at a saddle in floating point (large alpha/omega0 or |theta|); "
            "their bracket_width is stored; raise tol")
    if symmetry > SYMMETRY_BOUND * tol:
        problems.append(f"the right branch of -pi is up to {symmetry:.1e} from the point "
                        f"reflection of the left branch of pi (bound {SYMMETRY_BOUND:g} tol): "
                        "the labels are not symmetric under (theta, theta_dot) -> (-theta, "
                        "-theta_dot)")
    if checked.discrepancy > DISCREPANCY_BOUND:
        problems.append(f"separatrix points are up to {checked.discrepancy:.2e} from the "
                        f"DOP853 stable manifold (bound {DISCREPANCY_BOUND:.0e}): lower "
                        + ("tol" if tol > DISCREPANCY_BOUND else "dt"))

    return schema.node(
        theta=stored_theta, theta_dot=point[source, 1], width=(hi - lo)[source],
        crossing=crossing, crossing_width=crossing_width, k_below=k_above - 1,
        k_above=k_above, in_window=crossing_in_window, saddle_theta=stored_n * np.pi,
        saddle_n=stored_n, branch=branch[source], vertex=vertex[source],
        saddle_name="theta of the saddle (n*pi, 0)",
        branch_comment="left: arrives with theta_dot > 0 from theta < n*pi; right: arrives "
                       "with theta_dot < 0 from theta > n*pi",
        attrs={
            "alpha": p.alpha,
            "omega0": p.omega0,
            "theta_window": np.array(window.theta),
            "theta_dot_window": np.array(window.theta_dot),
            "tol": float(tol),
            "max_spacing": float(max_spacing),
            "dt": float(dt),
            "t_max": max(labels.t_max, axis_labels.t_max),
            "n_boundaries": int(saddles.size),
            "symmetry_error": symmetry, "symmetry_pairs": np.int64(pairs),
            "symmetry_bound": SYMMETRY_BOUND * tol,
            "discrepancy": checked.discrepancy,
            "discrepancy_bound": DISCREPANCY_BOUND,
            "polyline_error": checked.polyline_error,
            "n_orbits": labels.orbits + shooter.shots + axis_labels.orbits + axis_shots,
            "n_shots": shooter.shots + axis_shots,
            "rounding": shooter.rounding,
            "n_unresolved": labels.unresolved + axis_labels.unresolved,
            "warnings": "\n".join(problems),
            "method": (
                f"basin boundaries of the RK4 map (step dt, method {method}): the left "
                "branch of pi and the right branch of -pi, vertices predicted on the exact "
                "stable manifold (DOP853 in reversed time, rtol = atol = 1e-13, from 1e-7 "
                "along the stable "
                "eigenvector, essay eqs. 22, 24; the right branch its point reflection), "
                "spacing <= max_spacing and <= max_spacing/sqrt(curvature); each vertex "
                "located across the curve to a bracket narrower than tol: by shooting its "
                "segment to the saddle (the stable manifold of the RK4 map crosses it: cone "
                "conditions in the saddle's box; Newton steps from the exact curve and "
                "splines; method rk4), else by bisection/multisection on certified RK4 "
                "labels; every other branch is a copy shifted "
                "by a multiple of 2 pi (symmetry_error: the right branch of -pi vs the point "
                "reflection of the left branch of pi); checked against the same DOP853 "
                "manifold: discrepancy = max distance of the points to it, polyline_error = "
                "max distance of it to the polyline"),
        },
    )


#: How the RK4 map's separatrices are traced for each kind of exact boundaries (their
#: :attr:`~atlas.boundaries.exact.ExactBoundaries.traced_as`): one function of (pendulum,
#: window, exact boundaries, running barrier, settings) each.
TRACES = {"untilted": _trace_untilted, "tilted": trace_tilted_boundaries}
