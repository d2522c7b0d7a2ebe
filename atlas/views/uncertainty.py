"""The uncertainty exponent's figure of a driven pendulum's atlas (``atlas plot``:
``NAME_uncertainty.png``): the fraction f(ε) of ε-uncertain initial conditions against ε on
log-log axes, one set of markers per parameter point, with the line of the stored fit
f ∝ ε^α through them (:mod:`atlas.models.driven.measures`), its α ± its standard error and
D = 2 − α in the legend. Read from the file, drawn; the line's intercept is that of the
same least-squares fit (the mean of ln f less α times the mean of ln ε, over the ε with
f > 0), the slope the stored α.

Reader (:func:`uncertainty_scene`) and drawer (:func:`draw_uncertainty`) apart, as in
:mod:`atlas.views.maps`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import at_point, point_label, points

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["uncertainty_scene", "draw_uncertainty", "has_uncertainty"]


def has_uncertainty(ds: xr.Dataset) -> bool:
    """Whether the atlas's root ``ds`` stores an uncertainty exponent for some point."""
    return "uncertain_fraction" in ds and bool(np.isfinite(ds["uncertainty_exponent"]).any())


def uncertainty_scene(tree: xr.DataTree) -> dict:
    """What :func:`draw_uncertainty` draws: per parameter point its name, ε, f(ε), α, its
    error and D; and the number of random points behind each f."""
    ds = tree.to_dataset(inherit=False)
    curves = []
    for point in points(ds):
        here = at_point(ds, point)
        alpha = float(here["uncertainty_exponent"])
        if np.isfinite(alpha):
            curves.append({"name": point_label(point), "eps": ds["epsilon"].values,
                           "f": here["uncertain_fraction"].values, "alpha": alpha,
                           "error": float(here["uncertainty_exponent_error"]),
                           "dimension": float(here["boundary_dimension"])})
    return {"curves": curves,
            "n_points": int(ds["uncertain_fraction"].attrs.get("n_points", 0))}


def draw_uncertainty(ax, curves: list[dict], n_points: int) -> None:
    """Draw :func:`uncertainty_scene`'s curves into ``ax``."""
    for i, c in enumerate(curves):
        eps, f = np.asarray(c["eps"]), np.asarray(c["f"])
        used = f > 0
        marks = ax.loglog(eps[used], f[used], "o", ms=5,
                          label=f"{c['name']}" if len(curves) > 1 else "f(ε), measured")[0]
        x, y = np.log(eps[used]), np.log(f[used])
        intercept = y.mean() - c["alpha"] * x.mean()
        ax.loglog(eps[used], np.exp(intercept + c["alpha"] * x), "-", lw=1.2,
                  color=marks.get_color(),
                  label=f"fit f ∝ ε^α: α = {c['alpha']:.3f} ± {c['error']:.3f}, "
                        f"D = 2 − α = {c['dimension']:.3f}")
        if i >= 7:
            break
    ax.set_xlabel("ε (perturbation, as a fraction of the window's sides)")
    ax.set_ylabel("f(ε): share of ε-uncertain initial conditions")
    ax.set_title(f"Uncertainty exponent of the basin boundary ({n_points:,} random "
                 "initial conditions, each moved by ±ε)")
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(loc="lower right")
