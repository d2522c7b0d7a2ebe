"""Figures against a swept parameter, read from the file and drawn (no computing).

* :func:`fraction_curves`: exact basin fractions of each k (lines), with the grid counts and
  their error bounds (markers with error bars);
* :func:`basin_stability`: the share of the window that settles at a rest state and the
  running basin's share, against the torque.

Reader (``_*_scene``) and drawer (``_draw_*``) apart, as in :mod:`atlas.views.maps`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import PARAMETERS, point_label
from atlas.views.style import CURVE_SIZE, axes

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["fraction_curves", "basin_stability", "PARAMETER_AXES", "CURVE_FIGURES"]

#: Axis labels of the parameters.
PARAMETER_AXES = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
                  "torque": "torque τ [rad/s²]"}


def _held(full: xr.Dataset, ds: xr.Dataset, dim: str) -> str:
    """The title's second line: the swept parameters other than ``dim`` at the values held."""
    held = {n: float(ds[n]) for n in PARAMETERS if n != dim and n in full.dims}
    return f"\nat {point_label(held)}" if held else ""


def _fraction_scene(tree: xr.DataTree, dim: str = "alpha", max_curves: int = 7) -> dict:
    """What :func:`fraction_curves` draws: the swept values, the curves (exact fractions,
    grid counts, their bounds, label, colour), α = ω0 where α is swept, and the labels."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in full["basin_fraction_exact"].dims if d not in (dim, "k")})
    exact = ds["basin_fraction_exact"].transpose(dim, "k").values
    grid = ds["basin_fraction"].transpose(dim, "k").values
    bound = ds["basin_fraction_grid_error_bound"].transpose(dim, "k").values
    shown = np.sort(np.argsort(exact.max(axis=0))[::-1][:max_curves])
    rest = np.setdiff1d(np.arange(exact.shape[1]), shown)
    curves = [(exact[:, j], grid[:, j], bound[:, j], f"k = {int(ds['k'].values[j]):+d}", None)
              for j in shown]
    if rest.size:
        curves.append((exact[:, rest].sum(axis=1), grid[:, rest].sum(axis=1),
                       bound[:, rest].sum(axis=1), f"other k ({rest.size})", "0.5"))
    return {"x": ds[dim].values, "curves": curves,
            "critical": float(ds["omega0"]) if dim == "alpha" and ds["omega0"].ndim == 0
            else None, "xlabel": PARAMETER_AXES[dim],
            "title": "Basin fractions: exact areas (lines), grid counts with error bounds "
                     "(dots)" + _held(full, ds, dim)}


def _draw_fractions(ax, x, curves, critical, xlabel: str, title: str):
    """Draw :func:`_fraction_scene` (as :func:`fraction_curves`)."""
    for e, g, b, label, color in curves:
        line, = ax.plot(x, e, "-", color=color, label=label)
        ax.errorbar(x, g, yerr=b, fmt="o", ms=3, capsize=2, color=line.get_color())
    if critical is not None:
        ax.axvline(critical, color="0.3", ls=":", lw=1, label="α = ω0 (critical)")
    ax.set_xscale("log" if x.min() > 0 and x.max() / x.min() > 20 else "linear")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("basin fraction of the window")
    ax.set_title(title)
    ax.legend(ncol=2)
    return ax


def fraction_curves(tree: xr.DataTree, ax=None, dim: str = "alpha", max_curves: int = 7):
    """Exact basin fraction of each k against the swept parameter ``dim`` (lines), with the
    grid counts and their error bounds (markers with error bars); any other swept parameter
    is held at its first value (named in the title).

    The ``max_curves`` largest basins get a curve each; the rest are summed into one
    "other k" curve. A dashed line marks critical damping α = ω0 when α is swept.
    """
    return _draw_fractions(axes(ax, CURVE_SIZE), **_fraction_scene(tree, dim, max_curves))


def _stability_scene(tree: xr.DataTree, dim: str = "torque") -> dict:
    """What :func:`basin_stability` draws: the swept values, the rest states' and the running
    basin's shares (exact and grid counts), the grid error bound, and the labels."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in PARAMETERS if d in full.dims and d != dim})
    return {"x": ds[dim].values,
            "exact": ds["basin_fraction_exact"].sum("k", skipna=False).values,
            "grid": ds["basin_fraction"].sum("k").values,
            "bound": ds["basin_fraction_grid_error_bound"].sum("k", skipna=False).values,
            "running": ds["running_fraction"].values,
            "running_exact": ds["running_fraction_exact"].values,
            "xlabel": PARAMETER_AXES[dim],
            "title": "Basin stability of the rest states and of the running cycle"
                     + _held(full, ds, dim)}


def _draw_stability(ax, x, exact, grid, bound, running, running_exact, xlabel: str,
                    title: str):
    """Draw :func:`_stability_scene` (as :func:`basin_stability`)."""
    shown = np.isfinite(exact)
    if shown.any():
        ax.plot(x[shown], exact[shown], "-", color="C0", label="rest states, exact area")
        ax.plot(x[shown], running_exact[shown], "-", color="0.4", label="running, exact area")
    ax.errorbar(x, grid, yerr=np.where(np.isfinite(bound), bound, 0.0), fmt="o", ms=3,
                capsize=2, color="C0", label="rest states, grid count")
    ax.plot(x, running, "s", ms=3, color="0.4", label="running, grid count")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("basin stability (fraction of the window)")
    ax.set_ylim(-0.02, 1.02)
    ax.set_title(title)
    ax.legend()
    return ax


def basin_stability(tree: xr.DataTree, ax=None, dim: str = "torque"):
    """Basin stability against the swept parameter ``dim``: the share of the window that
    settles at a rest state (all wells together) and the running basin's share, as exact
    areas (lines, where computed) and grid counts (markers; error bars: the grid error bound,
    where computed). Any other swept parameter is held at its first value."""
    return _draw_stability(axes(ax, CURVE_SIZE), **_stability_scene(tree, dim))


#: The curve figures: name → (reader, drawer), as :data:`atlas.views.maps.MAP_FIGURES`; the
#: reader takes the swept dim.
CURVE_FIGURES = {"fractions": (_fraction_scene, _draw_fractions),
                 "basin_stability": (_stability_scene, _draw_stability)}
