"""The ``/separatrices`` node of an atlas file: its schema, written once, and its readers.

One node per parameter point (:mod:`atlas.layout`) holds the traced basin boundaries of the
RK4 map (:func:`atlas.boundaries.trace.trace`): per ``point`` the located boundary points
(``theta`` [rad], ``theta_dot`` [rad s⁻¹], ``bracket_width``) with their saddle, branch and
vertex; per ``crossing`` of the axis θ0 = 0 the speed, its bracket and the basins on either
side; the trace's settings and checks as attributes. :func:`node` builds it (the tracers
call it), :func:`branches`, :func:`warnings` and :func:`max_discrepancy` read it (the views
and ``atlas info``). Conventions: CF-1.10, as the rest of the file (:mod:`atlas.store.schema`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)

__all__ = ["BRANCHES", "node", "branches", "warnings", "max_discrepancy"]

#: Branch names, in the order of the ``branch`` flag values 0, 1.
BRANCHES = ("left", "right")


def node(*, theta, theta_dot, width, crossing, crossing_width, k_below, k_above, in_window,
         saddle_theta, saddle_n, branch, vertex, saddle_name: str, branch_comment: str,
         attrs: dict, k_comment: str | None = None) -> xr.Dataset:
    """The ``/separatrices`` node of one parameter point: per ``point`` the located boundary
    points with their saddle, branch and vertex; per ``crossing`` of the axis θ0 = 0 the
    speed, its bracket and the basins on either side (module docstring); ``saddle_name``,
    ``branch_comment``, ``k_comment``: the tracer's words for its saddles, branches and
    basins; ``attrs``: its settings and checks."""
    flags = np.array([0, 1], np.int8)
    k_attrs = {"units": "1", **({"comment": k_comment} if k_comment else {})}
    return xr.Dataset(
        data_vars={
            "theta": ("point", theta, {"units": "rad", "long_name": "angle theta"}),
            "theta_dot": ("point", theta_dot,
                          {"units": "rad s-1", "long_name": "angular velocity theta_dot"}),
            "bracket_width": ("point", width, {
                "units": "1", "long_name": "final bisection bracket width across the curve "
                "(phase-plane distance, rad and rad s-1 mixed)"}),
            "crossing_theta_dot": ("crossing", crossing, {
                "units": "rad s-1", "long_name": "theta_dot0 where the label changes on the "
                "axis theta0 = 0"}),
            "k_below": ("crossing", np.asarray(k_below).astype(np.int16),
                        {**k_attrs, "long_name": "attractor k just below the crossing"}),
            "k_above": ("crossing", np.asarray(k_above).astype(np.int16),
                        {**k_attrs, "long_name": "attractor k just above the crossing"}),
            "crossing_bracket_width": ("crossing", crossing_width, {
                "units": "rad s-1", "long_name": "final bisection bracket width"}),
            "crossing_in_window": ("crossing", in_window, {
                "long_name": "whether the crossing (0, theta_dot0) lies in the window",
                "flag_values": flags, "flag_meanings": "outside inside"}),
        },
        coords={
            "saddle_theta": ("point", saddle_theta, {"units": "rad", "long_name": saddle_name}),
            "saddle_n": ("point", saddle_n, {"units": "1", "long_name": "saddle at n*pi"}),
            "branch": ("point", branch, {
                "long_name": "branch of the stable manifold", "flag_values": flags,
                "flag_meanings": " ".join(BRANCHES), "comment": branch_comment}),
            "vertex": ("point", vertex, {
                "units": "1", "long_name": "index along the branch, 0 nearest the saddle",
                "comment": "gaps where the branch leaves the window and comes back"}),
        },
        attrs=attrs,
    )


def branches(ds: xr.Dataset) -> Iterator[tuple[int, str, np.ndarray, np.ndarray]]:
    """Yield (saddle_n, "left"|"right", theta [rad], theta_dot [rad s⁻¹]) per polyline, the
    arrays ordered from the saddle outward; for plotting. A branch that leaves the window and
    comes back (its ``vertex`` skips the points outside) yields one polyline per visit."""
    n, b, vtx = (ds[name].values for name in ("saddle_n", "branch", "vertex"))
    theta, theta_dot = ds["theta"].values, ds["theta_dot"].values
    for key in sorted(set(zip(n.tolist(), b.tolist(), strict=True))):
        sel = np.flatnonzero((n == key[0]) & (b == key[1]))
        sel = sel[np.argsort(vtx[sel], kind="stable")]
        for piece in np.split(sel, np.flatnonzero(np.diff(vtx[sel]) != 1) + 1):
            yield key[0], BRANCHES[key[1]], theta[piece], theta_dot[piece]


def warnings(ds: xr.Dataset) -> list[str]:
    """The problems the trace recorded (e.g. a discrepancy above its bound), one per line."""
    text = str(ds.attrs.get("warnings", ""))
    return [line for line in text.split("\n") if line]


def max_discrepancy(ds: xr.Dataset) -> float:
    """The largest distance [rad-ish] of the traced points to the exact boundaries (DOP853)."""
    return float(ds.attrs["discrepancy"])
