"""``atlas info`` and ``atlas run``'s summary: what an atlas holds, in a few lines."""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from . import store


def summary_lines(tree: xr.DataTree) -> list[str]:
    """Grid, parameters, basin fractions ± standard error, unresolved count, run time, and
    the separatrices' summary."""
    ds = tree.to_dataset(inherit=False)
    n_orbits = ds.sizes["theta0"] * ds.sizes["theta_dot0"]
    lines = [f"grid      {ds.sizes['theta0']} x {ds.sizes['theta_dot0']} (theta0 x theta_dot0)"
             f" = {n_orbits:,} orbits"]
    if "alpha" in ds.dims:
        lines.append(f"sweep     alpha: {ds.sizes['alpha']} values, omega0: "
                     f"{ds.sizes['omega0']} values; basin fractions per point:")
        for a in ds["alpha"].values:
            for w in ds["omega0"].values:
                point = ds.sel(alpha=a, omega0=w)
                lines.append(f"  alpha = {a:g}, omega0 = {w:g}: {_fractions(point)}")
        unresolved = int(round(float(ds["unresolved_fraction"].sum()) * n_orbits))
    else:
        lines.append(f"pendulum  alpha = {ds.attrs['alpha']:g} 1/s, omega0 = "
                     f"{ds.attrs['omega0']:g} rad/s, dt = {ds.attrs['dt']:g} s")
        lines.append(f"basins    {_fractions(ds)}")
        unresolved = int(round(float(ds["unresolved_fraction"]) * n_orbits))
    lines.append(f"unresolved {unresolved} orbits")
    if "run_time_s" in ds.attrs:
        lines.append(f"time      {float(ds.attrs['run_time_s']):.2f} s")
    if "separatrices" in tree.children:
        lines += _separatrix_lines(tree["separatrices"].to_dataset(inherit=False))
    return lines


def _fractions(ds: xr.Dataset) -> str:
    """``k=+0: 0.26621±8.6e-04, …`` for the basins of one parameter point."""
    return ", ".join(f"k={int(k):+d}: {float(p):.5f}±{float(e):.1e}"
                     for k, p, e in zip(ds["k"].values, ds["basin_fraction"].values,
                                        ds["basin_fraction_stderr"].values) if p > 0)


def _separatrix_lines(sep: xr.Dataset) -> list[str]:
    from .separatrices import summary

    if "point_alpha" not in sep.coords:
        return summary(sep)
    n = len({(a, w) for a, w in zip(sep["point_alpha"].values, sep["point_omega0"].values)})
    bound = float(sep.attrs["discrepancy_bound"])
    disc = float(sep.attrs["discrepancy"])
    return [f"separatrices: {n} parameter points, {sep.sizes['point']} points in all; max "
            f"distance to the DOP853 stable manifold {disc:.1e} "
            f"({'within' if disc <= bound else 'EXCEEDS'} bound {bound:.0e})"]


def info_lines(path: str | Path) -> list[str]:
    """Completeness, then :func:`summary_lines` for a complete file, then provenance."""
    path = Path(path)
    d = store.describe(path)
    attrs = d["attrs"]
    state = ("complete" if d["complete"] else
             f"partial: {d['tiles_done']} of {d['tiles']} tiles done (run the same config "
             "again to continue)")
    lines = [f"{path}: atlas file, {state}"]
    if d["complete"]:
        lines += ["  " + line for line in summary_lines(store.open_atlas(path))]
    lines.append(f"  created   {attrs.get('created', '?')} by atlas "
                 f"{attrs.get('atlas_version', '?')} (numba {attrs.get('numba_version', '?')}, "
                 f"numpy {attrs.get('numpy_version', '?')})")
    lines.append(f"  method    {attrs.get('method', '?')}, dt = {attrs.get('dt', '?')} s, "
                 f"t_max = {attrs.get('t_max', '?')} s, config hash {attrs.get('config_hash')}")
    return lines
