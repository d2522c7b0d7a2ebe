"""``atlas info`` of an atlas of any model, from what its description declares
(:class:`atlas.models.base.Model`): the grid by its axes, the parameters with their units,
and per parameter point every summary variable the model stores, by its long name: the
per-basin ones over ``k``, the per-point ones after them. The pendulum's atlas has a richer
summary of its own (:mod:`atlas.views.info`: exact areas, d_cert, separatrices); any other
model is described here, with no code of its own."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import at_point, point_label, points
from atlas.models.base import Model, units_text

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["grid_line", "described_lines"]


def grid_line(ds: xr.Dataset, model: Model, n_points: int) -> str:
    """"grid 24 x 16 (theta0 x theta_dot0) = 384 orbits per parameter point, 1 parameter
    point (alpha [1/s], …)": the grid by the model's axes, the parameters with their units."""
    columns, rows = model.axes
    n = ds.sizes[columns.name] * ds.sizes[rows.name]
    units = ", ".join(f"{name} [{units_text(units)}]"
                      for name, (units, _) in model.parameters.items() if name in ds.coords)
    return (f"grid      {ds.sizes[columns.name]} x {ds.sizes[rows.name]} ({columns.name} x "
            f"{rows.name}) = {n:,} orbits per parameter point, {n_points} parameter point"
            f"{'s' if n_points != 1 else ''} ({units})")


def _point_lines(ds: xr.Dataset, model: Model) -> list[str]:
    """One parameter point's summary: each basin variable over k, then each point
    variable, by its long name."""
    basins = [name for name in model.basin_variables if name in ds]
    present = np.zeros(ds.sizes["k"], bool)
    for name in basins:
        present |= np.nan_to_num(ds[name].values) != 0
    lines = ["basins    k  " + "  ".join(f"{name:>14}" for name in basins)]
    for i in np.flatnonzero(present):
        lines.append(f"          {int(ds['k'].values[i]):+d} "
                     + "  ".join(f"{float(ds[name].values[i]):>14.6f}" for name in basins))
    lines += [f"          {name}: {ds[name].attrs.get('long_name', name)}" for name in basins]
    lines += [f"{name} {float(ds[name]):.6g} ({ds[name].attrs.get('long_name', name)})"
              for name in model.point_variables if name in ds]
    return lines


def described_lines(tree: xr.DataTree, model: Model, chosen: list[dict] | None = None
                    ) -> list[str]:
    """The summary of an atlas of ``model``: the grid, then every parameter point (those
    ``chosen``, where given) with its summary variables."""
    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    lines = [grid_line(ds, model, len(every)),
             f"model     {model.name}: {model.title}"]
    for point in chosen if chosen is not None else every:
        lines.append(f"{model.name:<9} {point_label(point)}")
        lines += ["  " + line for line in _point_lines(at_point(ds, point), model)]
    return lines
