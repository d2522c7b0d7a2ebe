"""``atlas info`` and ``atlas run``'s summary: what an atlas holds, in a few lines."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (lazy_dask installs itself)
from atlas.errors import AtlasError
from atlas.layout import at_point, point_group, point_label, points
from atlas.models.registry import DEFAULT, DRIVEN, of_attrs
from atlas.store import reader as store
from atlas.views.described import described_lines, grid_line
from atlas.views.info_driven import driven_lines
from atlas.views.info_table import table_lines
from atlas.views.selectors import choose_points

#: Basins, saddles and crossings listed by a brief summary (``atlas run``'s): a window of
#: many turns has dozens of each, which ``atlas info`` lists in full.
BRIEF_ROWS = 9


def summary_lines(tree: xr.DataTree, chosen: list[dict] | None = None,
                  brief: bool = False) -> list[str]:
    """Grid, then for every parameter point its parameters, exact basin fractions, grid
    fractions with their error, d_cert and the certified share, and its separatrices'
    summary; then the unresolved count and the run time. A parameter atlas: one table of
    all its points instead (:func:`atlas.views.info_table.table_lines`), or the detail of
    the points ``chosen`` (:func:`atlas.views.selectors.choose_points`). ``brief`` (``atlas
    run``'s summary): at most :data:`BRIEF_ROWS` basins, saddles and crossings, with how many
    more ``atlas info`` lists. An atlas of another model than the pendulum: what its
    description declares (:func:`atlas.views.described.described_lines`)."""
    most = BRIEF_ROWS if brief else None
    ds = tree.to_dataset(inherit=False)
    model = of_attrs(ds.attrs)
    columns, rows = model.axes
    n_orbits = ds.sizes[columns.name] * ds.sizes[rows.name]
    every = points(ds)
    if model.name == DRIVEN:
        return driven_lines(tree, model, chosen) + _closing_lines(ds, n_orbits)
    if model.name != DEFAULT:
        return described_lines(tree, model, chosen) + _closing_lines(ds, n_orbits)
    lines = [grid_line(ds, model, len(every))]
    detail = chosen if chosen is not None else every if len(every) == 1 else []
    if not detail:
        lines += table_lines(tree)
    for point in detail:
        lines.append(f"pendulum  {point_label(point)}")
        sep = point_group(tree, "separatrices", point)
        lines += ["  " + line for line in _basin_lines(at_point(ds, point),
                                                       traced=sep is not None, most=most)]
        lines += ["  " + line for line in _torque_lines(tree, point)]
        if sep is not None:
            lines += ["  " + line for line in separatrix_lines(sep, most=most)]
    return lines + _closing_lines(ds, n_orbits)


def _closing_lines(ds: xr.Dataset, n_orbits: int) -> list[str]:
    """The unresolved count (where the model stores ``unresolved_fraction``) and the run
    time."""
    lines = []
    if "unresolved_fraction" in ds:
        unresolved = int(round(float(ds["unresolved_fraction"].sum()) * n_orbits))
        lines.append(f"unresolved {unresolved} orbits")
    if "run_time_s" in ds.attrs:
        lines.append(f"time      {float(ds.attrs['run_time_s']):.2f} s")
    return lines


def _largest(values: np.ndarray, ks: np.ndarray, most: int | None) -> np.ndarray:
    """Where ``values`` holds its ``most`` largest (to 6 digits; ties to the smaller |k|),
    in their order; all where ``most`` is None or not exceeded."""
    keep = np.ones(values.size, bool)
    if most is not None and values.size > most:
        keep[:] = False
        keep[np.lexsort((np.abs(ks), -np.round(values, 6)))[:most]] = True
    return keep


def _basin_lines(ds: xr.Dataset, traced: bool = False, most: int | None = None) -> list[str]:
    """The basins of one parameter point: exact area fractions first, then the grid counts
    with their error bound and measured error, then d_cert and the certified share (why
    d_cert is missing: separatrices disabled, or, ``traced``, traced without measuring a
    boundary shift). ``most``: only the basins of the ``most`` largest fractions, and one line
    saying how many more there are and their share."""
    present = (ds["basin_fraction_exact"].values > 0) | (ds["basin_fraction"].values > 0)
    share = np.where(np.isnan(ds["basin_fraction_exact"].values),
                     ds["basin_fraction"].values, ds["basin_fraction_exact"].values)[present]
    shown = _largest(share, ds["k"].values[present], most)
    left_out, left_share = int((~shown).sum()), float(share[~shown].sum())
    present[present] = shown
    ks = ds["k"].values[present]
    exact = ds["basin_fraction_exact"].values[present]
    exact_err = ds["basin_fraction_exact_error"].values[present]
    grid = ds["basin_fraction"].values[present]
    bound = ds["basin_fraction_grid_error_bound"].values[present]
    measured = ds["basin_fraction_grid_error"].values[present]
    lines = ["basins    k   area fraction (exact)        grid count   grid error: bound, "
             "measured"]
    lines += [f"          {int(k):+d}  "
              + (f"{e:.14f} ± {ee:.0e}" if e == e else f"{'not computed':<22}")
              + f"   {g:.6f}     "
              + (f"{b:.1e}, {m:.1e}" if b == b else "not computed")
              for k, e, ee, g, b, m in zip(ks, exact, exact_err, grid, bound, measured)]
    if left_out:
        lines.append(f"          … {left_out} more basins, {left_share:.2e} of the window in "
                     "all (`atlas info` of the file lists every one)")
    running, running_exact = float(ds["running_fraction"]), float(ds["running_fraction_exact"])
    if running or running_exact:
        lines.append(f"          run {running_exact:.14f} ± "
                     f"{float(ds['running_fraction_exact_error']):.0e}   {running:.6f}     "
                     f"{float(ds['running_fraction_grid_error_bound']):.1e}, "
                     f"{abs(running - running_exact):.1e}   (the running limit cycle)")
    d_cert = float(ds["d_cert"])
    n = ds.sizes["theta0"] * ds.sizes["theta_dot0"]
    certified = int(round(float(ds["certified_fraction"]) * n))
    if d_cert == 0.0:  # no rest state, no boundary (|torque| > omega0^2)
        lines.append(f"certified {certified:,} of {n:,} labels ({certified / n:.2%}) hold for "
                     "the exact equation: without rest states there is no basin boundary and "
                     "the running cycle attracts every orbit (status running); the others "
                     "are unresolved")
    elif d_cert == d_cert:  # not NaN
        lines.append(f"certified {certified:,} of {n:,} labels ({certified / n:.2%}) hold for "
                     f"the exact equation: farther than d_cert = {d_cert:.1e} from every "
                     "basin boundary (status trapped or running); the others for the RK4 "
                     "map only")
    elif traced:
        lines.append("certified d_cert not measured (the separatrices measured no boundary "
                     "shift in this window; see their warning): labels are certified for the "
                     "RK4 map only (status near_boundary or running_near_boundary)")
    else:
        lines.append("certified d_cert not measured (separatrices disabled): labels are "
                     "certified for the RK4 map only (status near_boundary)")
    if int(ds["side_mismatches"]):
        lines.append(f"warning   {int(ds['side_mismatches'])} labels beyond d_cert disagree "
                     "with the exact boundaries")
    return lines


def _torque_lines(tree: xr.DataTree, point: dict) -> list[str]:
    """For a pendulum with torque: its rest states or their absence, and its running limit
    cycle."""
    if not point.get("torque"):
        return []
    lines = []
    cp = point_group(tree, "critical_points", point)
    if cp is not None and cp.sizes.get("point", 0) == 0:
        lines.append("critical  none: |torque| > omega0^2, every orbit runs")
    elif cp is not None:
        kinds = sorted(set(cp["kind"].values.tolist()))
        lines.append(f"critical  {cp.sizes['point']} in the window (" + ", ".join(kinds)
                     + "), tilted: rest states at theta = asin(torque/omega0^2) + 2 pi k")
    cycle = point_group(tree, "limit_cycle", point)
    if cycle is None:
        lines.append("cycle     no running limit cycle (below the homoclinic torque)")
    else:
        lines.append(f"cycle     running limit cycle: period {float(cycle.attrs['period']):.10g} "
                     f"s, mean angular velocity {float(cycle.attrs['mean_theta_dot']):.10g} "
                     f"rad/s (relative error {float(cycle.attrs['relative_error']):.0e})")
    return lines


def _listed(items: list[str], most: int | None) -> str:
    """``items`` joined by commas; beyond ``most`` the first ones, "…", the last and the count."""
    if most is None or len(items) <= most:
        return ", ".join(items)
    return f"{', '.join(items[:most - 1])}, …, {items[-1]} ({len(items)} in all)"


def separatrix_lines(ds: xr.Dataset, most: int | None = None) -> list[str]:
    """One parameter point's ``/separatrices`` node (:mod:`atlas.store.separatrices`) in a
    few lines: its boundaries and branches, its symmetry check (the point reflection without
    torque, the 2π shift with), its check against the exact boundaries, its orbits, its
    crossings of the axis θ0 = 0, its warnings. ``most``: at most that many saddles and
    crossings named."""
    from atlas.store.separatrices import branches, max_discrepancy, warnings

    found = {(n, b) for n, b, *_ in branches(ds)}
    saddles = sorted({n for n, _ in found})
    bound = float(ds.attrs["discrepancy_bound"])
    disc = max_discrepancy(ds)
    symmetry = float(ds.attrs.get("symmetry_error", math.nan))
    symmetry_bound = float(ds.attrs.get("symmetry_bound", math.nan))
    lines = [
        f"separatrices: {len(saddles)} basin boundaries (saddles n = "
        f"{_listed(list(map(str, saddles)), most) or '-'}), {len(found)} branches, "
        f"{ds.sizes.get('point', 0)} points, located to tol {float(ds.attrs['tol']):.0e}"
        + (f" (rounding estimate of the shots ≤ {float(ds.attrs['rounding']):.1e})"
           if "rounding" in ds.attrs else "")
        + f", max spacing {float(ds.attrs['max_spacing']):g}",
        (f"symmetry: torque breaks the point reflection; the 2 pi shift between copies, "
         f"located independently: max distance {float(ds.attrs['shift_error']):.1e} over "
         f"{int(ds.attrs.get('shift_pairs', 0))} pairs"
         if "shift_error" in ds.attrs else
         "symmetry: right branch of -pi vs reflected left branch of pi: "
         + (f"max distance {symmetry:.1e} over "
            f"{int(ds.attrs.get('symmetry_pairs', 0))} pairs located independently "
            f"({'within' if symmetry <= symmetry_bound else 'EXCEEDS'} bound "
            f"{symmetry_bound:.0e})" if symmetry == symmetry else
            "not checked (the window needs one of them only)")),
        (f"check vs DOP853 stable manifold: max distance {disc:.1e} "
         f"({'within' if disc <= bound else 'EXCEEDS'} bound {bound:.0e}); "
         if disc == disc else
         "check vs DOP853 stable manifold: boundary shift not measured (see the warning); ")
        +
        f"polyline error {float(ds.attrs['polyline_error']):.1e}; "
        f"{int(ds.attrs['n_orbits'])} orbits"
        + (f" ({int(ds.attrs['n_shots'])} shot to a saddle, the rest labelled)"
           if "n_shots" in ds.attrs else " labelled")
        + f", {int(ds.attrs['n_unresolved'])} labels "
        "uncertified (left out, never counted as either side)",
    ]
    inside = ds["crossing_in_window"].values if "crossing_in_window" in ds else None
    cross = [f"{v:+.10f} ({_basin_name(lo)}|{_basin_name(hi)})"
             f"{'' if inside is None or inside[i] else '*'}"
             for i, (v, lo, hi) in enumerate(zip(ds["crossing_theta_dot"].values,
                                                 ds["k_below"].values, ds["k_above"].values,
                                                 strict=True))]
    lines.append("basin boundaries on theta0 = 0: theta_dot0 = "
                 + (_listed(cross, most) if cross else "none") + " rad/s (k below|above; "
                 "* outside the window)")
    lines += [f"warning: {w}" for w in warnings(ds)]
    return lines


def _basin_name(k) -> str:
    """A crossing's basin: its well k, or "run" for the running basin (the fill value)."""
    from atlas.status import ATTRACTOR_FILL

    return "run" if int(k) == ATTRACTOR_FILL else str(int(k))


def info_lines(path: str | Path, selectors: dict | None = None) -> list[str]:
    """Completeness, then :func:`summary_lines` for a complete file (opened and checked by
    :func:`atlas.store.reader.open_atlas`; ``selectors``, as
    :func:`atlas.views.selectors.choose_points` takes them: the detail of those points),
    then provenance. A file that fails the check raises
    :class:`~atlas.errors.InputFileError`. For the output of an interrupted run, not written
    yet, its partial run (``<path>.partial``) is described: how far it got, how to finish.
    A stability study is described by :func:`atlas.views.study_info.study_info_lines`."""
    path = Path(path)
    from atlas.store.study import is_study_file

    if is_study_file(path):
        from atlas.views.study_info import study_info_lines

        if selectors and any(selectors.values()):
            raise AtlasError(f"{path}: a stability study; --point, --alpha, --omega0 and "
                             "--torque choose points of an atlas file")

        return study_info_lines(path)
    partial = None if path.exists() else store.interrupted_run(path)
    d = store.describe(partial or path)
    attrs = d["attrs"]
    state = ("complete" if d["complete"] else
             f"partial: {d['tiles_done']} of {d['tiles']} tiles done (run the same config "
             "again to continue)")
    lines = [f"{path}: atlas file, {state}" if partial is None else
             f"{path}: not written yet: its run was interrupted; {partial} holds "
             f"{d['tiles_done']} of {d['tiles']} tiles (run the same config again, "
             "`atlas run CONFIG`, to finish it)"]
    if d["complete"]:
        tree = store.open_atlas(path)
        try:
            chosen = choose_points(tree.to_dataset(inherit=False), **(selectors or {}))
            lines += ["  " + line for line in summary_lines(tree, chosen)]
            attrs = tree.attrs
        finally:
            tree.close()
    lines.append(f"  created   {_text(attrs, 'created')} by atlas "
                 f"{_text(attrs, 'atlas_version')} (numba {_text(attrs, 'numba_version')}, "
                 f"numpy {_text(attrs, 'numpy_version')})")
    lines.append(f"  method    {_text(attrs, 'method')}, dt = {_text(attrs, 'dt')} s, "
                 f"t_max = {_text(attrs, 't_max')} s, config hash "
                 f"{_text(attrs, 'config_hash')}")
    return lines


def _text(attrs: dict, name: str) -> str:
    """An attribute for display, on one line and not too long (a file's text is untrusted)."""
    value = attrs.get(name, "?")
    text = " ".join(str(value).split())
    return text if len(text) <= 80 else text[:77] + "..."
