"""The ``/separatrices`` node of an atlas file: its schema, written once, and its readers.

One node per parameter point (:mod:`atlas.layout`) holds the traced basin boundaries of the
RK4 map (:func:`atlas.boundaries.trace.trace`): per ``point`` the located boundary points
(``theta`` [rad], ``theta_dot`` [rad s⁻¹], ``bracket_width``) with their saddle, branch and
vertex; per ``crossing`` of the axis θ0 = 0 the speed, its bracket and the basins on either
side; the trace's settings and checks as attributes. :func:`node` builds it (the tracers
call it), :func:`branches`, :func:`curves`, :func:`warnings` and :func:`max_discrepancy` read
it (the views, ``atlas info`` and users: :func:`curves` lays the polylines out for xarray).
Conventions: CF-1.10, as the rest of the file (:mod:`atlas.store.schema`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)

__all__ = ["BRANCHES", "node", "branches", "curves", "warnings", "max_discrepancy",
           "inexact_line", "inexact_points"]

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


def _pieces(ds: xr.Dataset) -> Iterator[tuple[int, int, np.ndarray]]:
    """(saddle_n, branch flag, indices along ``point``) per polyline of the node ``ds``, the
    indices ordered from the saddle outward (by ``vertex``) and split where ``vertex`` skips
    (the branch left the window and came back), whatever the order of the stored points."""
    n, b, vtx = (ds[name].values for name in ("saddle_n", "branch", "vertex"))
    for key in sorted(set(zip(n.tolist(), b.tolist(), strict=True))):
        sel = np.flatnonzero((n == key[0]) & (b == key[1]))
        sel = sel[np.argsort(vtx[sel], kind="stable")]
        for piece in np.split(sel, np.flatnonzero(np.diff(vtx[sel]) != 1) + 1):
            yield key[0], key[1], piece


def branches(ds: xr.Dataset) -> Iterator[tuple[int, str, np.ndarray, np.ndarray]]:
    """Yield (saddle_n, "left"|"right", theta [rad], theta_dot [rad s⁻¹]) per polyline, the
    arrays ordered from the saddle outward; for plotting. A branch that leaves the window and
    comes back (its ``vertex`` skips the points outside) yields one polyline per visit.

    ``ds`` is one ``/separatrices`` node: ``tree["separatrices"].to_dataset(inherit=False)``
    for an atlas of one parameter point, ``atlas.layout.point_group(tree, "separatrices",
    point)`` for a point of a parameter atlas."""
    theta, theta_dot = ds["theta"].values, ds["theta_dot"].values
    for n, b, piece in _pieces(ds):
        yield n, BRANCHES[b], theta[piece], theta_dot[piece]


def curves(ds: xr.Dataset) -> xr.Dataset:
    """The polylines of :func:`branches` as one Dataset over (``curve``, ``along``), so that
    xarray and matplotlib draw them in one line.

    ``theta`` [rad] and ``theta_dot`` [rad s⁻¹] run from the saddle outward along ``along``
    and are NaN after a curve's last point; ``vertex`` (curve, along) is each point's index
    in the file's ``vertex`` (−1 in the padding); ``saddle_n`` and ``branch`` (curve) name
    its saddle nπ and branch with the file's flags (0 left, 1 right). The curves come in the
    order of :func:`branches`. Matplotlib draws each column of a 2-D array as a line and
    leaves NaN out, so ``ax.plot(c.theta.T, c.theta_dot.T)`` draws every boundary of the
    node and ``ax.plot(c.theta[i], c.theta_dot[i])`` one. A reader only: the file keeps its
    flat ``point`` list. ``ds``: one node, as for :func:`branches`.
    """
    pieces = list(_pieces(ds))
    length = max((piece.size for *_, piece in pieces), default=0)
    shape = (len(pieces), length)
    theta, theta_dot = np.full(shape, np.nan), np.full(shape, np.nan)
    vertex = np.full(shape, -1, np.int32)
    for i, (*_, piece) in enumerate(pieces):
        theta[i, :piece.size] = ds["theta"].values[piece]
        theta_dot[i, :piece.size] = ds["theta_dot"].values[piece]
        vertex[i, :piece.size] = ds["vertex"].values[piece]
    dims = ("curve", "along")
    return xr.Dataset(
        data_vars={"theta": (dims, theta, ds["theta"].attrs),
                   "theta_dot": (dims, theta_dot, ds["theta_dot"].attrs)},
        coords={"saddle_n": ("curve", np.array([n for n, *_ in pieces], np.int32),
                             ds["saddle_n"].attrs),
                "branch": ("curve", np.array([b for _, b, _ in pieces], np.int8),
                           ds["branch"].attrs),
                "vertex": (dims, vertex, {**ds["vertex"].attrs, "comment": "-1 after the "
                                          "curve's last point"})})


def warnings(ds: xr.Dataset) -> list[str]:
    """The problems the trace recorded (e.g. a discrepancy above its bound), one per line."""
    text = str(ds.attrs.get("warnings", ""))
    return [line for line in text.split("\n") if line]


def max_discrepancy(ds: xr.Dataset) -> float:
    """The largest distance [rad-ish] of the traced points to the exact boundaries (DOP853)."""
    return float(ds.attrs["discrepancy"])


def _discrepancy(ds: xr.Dataset) -> tuple[float, float]:
    """(the traced points' largest distance to the DOP853 stable manifold, its bound) of one
    ``/separatrices`` node (NaN, NaN where it has none)."""
    return (float(ds.attrs.get("discrepancy", math.nan)),
            float(ds.attrs.get("discrepancy_bound", math.nan)))


def inexact_line(where: str, separatrices: xr.Dataset) -> str | None:
    """The warning for one ``/separatrices`` node whose check against the DOP853 stable
    manifold exceeds its bound, naming it ``where``; None where it is within its bound."""
    disc, bound = _discrepancy(separatrices)
    if not disc > bound:
        return None
    return (f"{where}: check vs DOP853 stable manifold: max distance {disc:.1e} EXCEEDS bound "
            f"{bound:.0e}: labels near the basin boundaries are less certain than the bound "
            "assumes; lower separatrices.tol or integrator.dt")


def inexact_points(tree: xr.DataTree) -> list[str]:
    """The nodes of ``tree``'s ``/separatrices`` (a written atlas, or :func:`run`'s result)
    whose check against the DOP853 stable manifold exceeds its bound: one line each, naming
    the node (empty where every check is within its bound, or there are none)."""
    if "separatrices" not in tree.children:
        return []
    return [line for node in tree["separatrices"].subtree
            for line in [inexact_line(node.path, node)] if line]
