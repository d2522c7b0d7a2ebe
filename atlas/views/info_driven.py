"""``atlas info`` of a driven pendulum's atlas: per parameter point the attractors of the
stroboscopic map (``/attractors``: kind, period, winding, Floquet multipliers), each with its
share of the grid and that share's standard error, and how its labels were decided."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import at_point, point_group, point_label, points
from atlas.models.base import Model
from atlas.views.described import grid_line
from atlas.views.style import attractor_colours

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["driven_lines", "attractor_name", "attractor_names", "attractor_key",
           "measure_lines"]


def attractor_name(kind: str, period: int, winding: int) -> str:
    """"oscillation, period 1", "rotation, period 2, winding -2" or "chaotic": an
    attractor as keys and texts name it (its kind in words first: what its colour family
    says, :func:`atlas.views.style.attractor_colours`)."""
    if kind == "chaotic":
        return "chaotic"
    if winding == 0:
        return f"oscillation, period {period}"
    return f"rotation, period {period}, winding {winding:+d}"


def attractor_names(group: xr.Dataset | None) -> dict[int, str]:
    """Each attractor of one point's ``/attractors`` group by its index, named as every key
    and text names it ("#1 rotation, period 2, winding -2"); {} where there is none."""
    if group is None:
        return {}
    return {i: f"#{i} " + attractor_name(str(group["kind"].values[i]),
                                          int(group["period"].values[i]),
                                          int(group["winding"].values[i]))
            for i in range(group.sizes.get("attractor", 0))}


def attractor_key(group: xr.Dataset | None) -> tuple[dict[int, str], dict[int, str]]:
    """(names, colours) of one point's attractors by index: :func:`attractor_names` and
    their colours by kind (:func:`atlas.views.style.attractor_colours`), for the maps, their
    keys and the page alike."""
    if group is None:
        return {}, {}
    colours = attractor_colours(group["kind"].values, group["winding"].values)
    return attractor_names(group), dict(enumerate(colours))


def _attractor_lines(ds: xr.Dataset, group: xr.Dataset | None, model: Model) -> list[str]:
    if group is None or group.sizes.get("attractor", 0) == 0:
        return ["attractors none found in the window"]
    share = dict(zip(ds["k"].values.tolist(), ds["basin_fraction"].values.tolist()))
    error = dict(zip(ds["k"].values.tolist(), ds["basin_fraction_error"].values.tolist()))
    lines = [f"attractors of the stroboscopic map: {group.sizes['attractor']} (drive period "
             f"{float(group.attrs['drive_period']):.6g} s, "
             f"{int(group.attrs['steps_per_period'])} RK4 steps per period)"]
    for i in range(group.sizes["attractor"]):
        kind = str(group["kind"].values[i])
        name = attractor_name(kind, int(group["period"].values[i]),
                              int(group["winding"].values[i]))
        moduli = group["floquet_modulus"].values[i]
        floquet = ("" if kind == "chaotic" else
                   f", |Floquet multipliers| {moduli[0]:.3g}, {moduli[1]:.3g}")
        status = model.statuses.get(int(group["status"].values[i]), "?")
        lines.append(f"  #{i} {name}{floquet}; basin {share.get(i, 0.0):.4f} ± "
                     f"{error.get(i, 0.0):.4f} of the grid (labels {status}, capture radius "
                     f"{float(group['capture_radius'].values[i]):.3g})")
    changed = float(ds["changed_at_half_dt_fraction"])
    how = ("the larger of the grid count's binomial standard error and its spread over the "
           "grid's four interleaved half-resolution grids"
           if "basin_fraction_shifted_spread" in ds else
           "the grid count's binomial standard error")
    lines.append(f"  ± : {how}, plus its change at dt/2 ({changed:.2%} of the labels change "
                 "when dt is halved)")
    return lines


def measure_lines(ds: xr.Dataset) -> list[str]:
    """The fractal measures of one point's map (:mod:`atlas.models.driven.measures`), each
    with what it is and how far it goes; none for a file without them."""
    if "boundary_basin_entropy" not in ds:
        return []
    sbb, fractal = float(ds["boundary_basin_entropy"]), float(ds["fractal_boundary"])
    lines = [f"fractal measures of the map (labels of the RK4 stroboscopic map, "
             f"boxes of {ds['basin_entropy'].attrs.get('box', '5 x 5 grid points')})"]
    if not np.isfinite(float(ds["basin_entropy"])):
        lines.append("  basin entropy not measured (no box of labelled orbits)")
    elif not np.isfinite(sbb):
        lines.append(f"  basin entropy S_b {float(ds['basin_entropy']):.4f} nats; no box "
                     "holds two basins: no boundary box")
    else:
        lines.append(f"  basin entropy S_b {float(ds['basin_entropy']):.4f}, boundary basin "
                     f"entropy S_bb {sbb:.4f} nats: " + (
                         "> ln 2 = 0.6931, the boundary is fractal" if fractal == 1 else
                         "not above ln 2: no evidence of a fractal boundary from this test "
                         "(which two basins can never pass)"))
    alpha = float(ds["uncertainty_exponent"])
    if np.isfinite(alpha):
        eps = ds["epsilon"].values
        lines.append(f"  uncertainty exponent alpha {alpha:.3f} ± "
                     f"{float(ds['uncertainty_exponent_error']):.3f} (the fit's standard error "
                     f"only), from {int(ds['uncertain_fraction'].attrs['n_points']):,} random "
                     f"points at epsilon {eps[0]:.0e} to {eps[-1]:.0e} of the window: boundary "
                     f"dimension D = 2 - alpha = {float(ds['boundary_dimension']):.3f}"
                     + (" (a smooth boundary has alpha = 1)" if alpha < 0.9 else ""))
    wada = ds["wada"].values[np.isfinite(ds["wada"].values)]
    if wada.size:
        shares = ", ".join(f"W_{m} {w:.3f}" for m, w in enumerate(wada, 1))
        merged = float(ds["wada_merge_distance_max"])
        meaning = (f"W_{wada.size}: the share of boundary cells that meet all {wada.size} "
                   "basins; 1 for Wada basins" if wada.size >= 3 else
                   "with two basins every boundary cell meets both: no Wada test")
        lines.append(f"  Wada grid method: {shares} ({meaning}, on the map thinned to at "
                     f"most {int(ds['wada'].attrs.get('thinned_to_at_most', 150))} points per "
                     "axis)" + (
                         f"; merging method: Hausdorff distances "
                         f"{float(ds['wada_merge_distance_min']):.2f} to {merged:.2f} cells "
                         "of that map" if np.isfinite(merged) else ""))
    return lines


def driven_lines(tree: xr.DataTree, model: Model, chosen: list[dict] | None = None
                 ) -> list[str]:
    """The summary of a driven pendulum's atlas: the grid, then every parameter point
    (those ``chosen``, where given) with its attractors and their shares."""
    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    lines = [grid_line(ds, model, len(every)), f"model     {model.name}: {model.title}"]
    for point in chosen if chosen is not None else every:
        lines.append(f"pendulum  {point_label(point)}")
        group = point_group(tree, "attractors", point)
        lines += ["  " + line for line in _attractor_lines(at_point(ds, point), group, model)]
        lines += ["  " + line for line in measure_lines(at_point(ds, point))]
        if "status" in ds:  # the file (atlas run's summary holds no map)
            status = at_point(ds, point)["status"].values
            counts = {name: int(np.sum(status == code)) for code, name in model.statuses.items()}
            lines.append("  labels    " + ", ".join(f"{name} {n:,}" for name, n in counts.items()
                                                     if n))
    return lines
