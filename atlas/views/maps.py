"""The basin-map figures of one parameter point, read from the file and drawn (no computing).

* :func:`basin_map`: colour by attractor k (the running basin grey), separatrices in red,
  saddles as open circles, attractors as filled dots, the running limit cycle dashed;
* :func:`trap_time_map`: the certified trapping time on a log colour scale;
* :func:`boundary_distance_map`: each state's distance to the nearest basin boundary (how far
  it is from tipping into another well), white within d_cert (labels for the RK4 map only).

Each figure is read, then drawn: a reader (``_*_scene``) takes what it shows out of the tree
as plain arrays and strings (the map through :func:`atlas.views.coarsen.read_maps`), a drawer
(``_draw_*``) draws them and reads nothing, so that ``atlas plot`` can draw in forked
processes (:mod:`atlas.views.plotting`). matplotlib is imported only where a figure is drawn.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import first_point, point_group, point_of
from atlas.views.coarsen import read_maps
from atlas.views.style import (
    CYCLE_COLOR,
    MAP_SIZE,
    RUNNING_COLOR,
    SEPARATRIX_COLOR,
    WELL_COLORS,
    axes,
    critical_point_markers,
    point_title,
    window_ticks,
)

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["basin_map", "trap_time_map", "boundary_distance_map", "MAP_FIGURES",
           "draw_limit_cycle"]

TWO_PI = 2.0 * np.pi


def _map_scene(tree: xr.DataTree, name: str, maps: dict | None, index: dict
               ) -> tuple[xr.Dataset, dict]:
    """The point drawn (its dataset) and what every map figure shows of it: the grid (θ0
    [rad], θ̇0 [rad/s]), the map ``name`` as :func:`read_maps` reads it, and the separatrix
    branches (θ [rad], θ̇ [rad/s]; none where not stored)."""
    from atlas.store.separatrices import branches

    ds = first_point(tree.to_dataset(inherit=False), **index)
    sep = point_group(tree, "separatrices", point_of(ds))
    return ds, {"grid": (ds["theta0"].values, ds["theta_dot0"].values),
                "image": (maps or read_maps(tree, name, **index))[name],
                "separatrices": [] if sep is None else
                [(theta, theta_dot) for _, _, theta, theta_dot in branches(sep)]}


def _grid_image(ax, grid: tuple[np.ndarray, np.ndarray], image: np.ndarray, **kwargs):
    """Draw a map over the grid (θ0, θ̇0: columns, rows) as an image whose pixels are the
    grid's cells (centred on the grid points); ``image``: the map already coarsened to the
    figure's resolution (its blocks then span the same extent)."""
    th, v = grid
    half_t = 0.5 * (th[-1] - th[0]) / max(th.size - 1, 1)
    half_v = 0.5 * (v[-1] - v[0]) / max(v.size - 1, 1)
    image = ax.imshow(np.ma.masked_invalid(image), origin="lower",
                      extent=(th[0] - half_t, th[-1] + half_t, v[0] - half_v, v[-1] + half_v),
                      aspect="auto", interpolation="nearest", **kwargs)
    ax.set_xlim(th[0], th[-1])
    ax.set_ylim(v[0], v[-1])
    window_ticks(ax, th[0], th[-1], "x", "θ0", "rad", pi=True)
    window_ticks(ax, v[0], v[-1], "y", "θ̇0", "rad/s")
    return image


def _draw_separatrices(ax, separatrices: list) -> None:
    """The separatrix branches (θ [rad], θ̇ [rad/s]), in red."""
    for i, (theta, theta_dot) in enumerate(separatrices):
        ax.plot(theta, theta_dot, color=SEPARATRIX_COLOR, lw=1.2,
                label="separatrices" if i == 0 else None)


def draw_limit_cycle(ax, lo: float, hi: float, theta: np.ndarray, theta_dot: np.ndarray,
                     period: float) -> None:
    """The running limit cycle (θ [rad], θ̇ [rad/s]; period [s]), repeated 2π-periodically
    across the window θ ∈ [lo, hi]."""
    order = np.argsort(theta)
    theta, theta_dot = theta[order], theta_dot[order]
    shifts = np.arange(np.floor((lo - theta.max()) / TWO_PI), np.ceil((hi - theta.min()) / TWO_PI)
                       + 1)
    for i, shift in enumerate(shifts):
        ax.plot(theta + TWO_PI * shift, theta_dot, color=CYCLE_COLOR, lw=1.6, ls="--", zorder=4,
                label=f"limit cycle (period {period:.4g} s)" if i == 0 else None)


def _basin_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`basin_map` draws: :func:`_map_scene`'s, the critical points (θ [rad],
    saddle or not, tilted or not) and the running limit cycle (θ [rad], θ̇ [rad/s], period
    [s]) where stored, and the title."""
    ds, scene = _map_scene(tree, "basin", maps, index)
    point = point_of(ds)
    cp = point_group(tree, "critical_points", point)
    cycle = point_group(tree, "limit_cycle", point)
    return scene | {
        "critical": None if cp is None else  # odd n: saddles
        (cp["theta"].values, cp["n"].values % 2 != 0, bool(float(ds["torque"]))),
        "cycle": None if cycle is None else
        (cycle["theta"].values, cycle["theta_dot"].values, float(cycle.attrs["period"])),
        "title": f"Basins of attraction, {point_title(point)}"}


def _draw_basin(ax, grid, image, separatrices, critical, cycle, title: str):
    """Draw :func:`_basin_scene` (as :func:`basin_map`)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    k, kmin, kmax, running = image
    colors = [WELL_COLORS[k % 10] for k in range(kmin, kmax + 1)]
    ticks, names = list(range(kmin, kmax + 1)), [f"{k:+d}" for k in range(kmin, kmax + 1)]
    if running:  # the running basin: one more colour after the wells
        colors.append(RUNNING_COLOR)
        ticks.append(kmax + 1)
        names.append("running")
    cmap = ListedColormap(colors).with_extremes(bad="white")
    levels = np.arange(kmin, kmin + len(colors) + 1) - 0.5
    mesh = _grid_image(ax, grid, k, cmap=cmap, norm=BoundaryNorm(levels, cmap.N))
    cbar = ax.figure.colorbar(mesh, ax=ax, ticks=ticks)
    cbar.ax.set_yticklabels(names)
    cbar.set_label("attractor k: orbit settles at the rest state of well k" if not running
                   else "attractor k: orbit settles at the rest state of well k;\n"
                   "running: orbit rotates (the running limit cycle)")
    _draw_separatrices(ax, separatrices)
    if cycle is not None:
        draw_limit_cycle(ax, grid[0][0], grid[0][-1], *cycle)
    if critical is not None:
        critical_point_markers(ax, *critical)
    ax.set_title(title)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=3, borderaxespad=0)
    return ax


def basin_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the basin map of ``tree`` (colour by k) with critical points and separatrices;
    ``maps``: :func:`read_maps` of the same point, if already read."""
    return _draw_basin(axes(ax, MAP_SIZE), **_basin_scene(tree, maps, **index))


def _trap_time_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`trap_time_map` draws (:func:`_map_scene`'s)."""
    return _map_scene(tree, "t_trap", maps, index)[1]


def _draw_trap_time(ax, grid, image, separatrices):
    """Draw :func:`_trap_time_scene` (as :func:`trap_time_map`)."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm

    # blocks keep their largest t_trap (the transform below is monotone: the same as the
    # largest of the transformed cells)
    t, lo, hi = image
    lo = lo if lo == lo else 1e-2
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = colormaps["magma"].with_extremes(under="0.8", bad="white")
    # t_trap = 0 (already inside the trap) is drawn below the scale, in grey
    mesh = _grid_image(ax, grid, np.where(t > 0, t, lo / 2), cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label("trapping time t_trap [s]")
    _draw_separatrices(ax, separatrices)
    ax.set_title("Time to certified trapping (grey: trapped at t = 0; white: never)")
    return ax


def trap_time_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the certified trapping time t_trap [s] on a log colour scale (``maps`` as
    :func:`basin_map`)."""
    return _draw_trap_time(axes(ax, MAP_SIZE), **_trap_time_scene(tree, maps, **index))


def _boundary_distance_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`boundary_distance_map` draws: :func:`_map_scene`'s and d_cert [rad-ish]."""
    ds, scene = _map_scene(tree, "boundary_distance", maps, index)
    return scene | {"d_cert": float(ds["d_cert"])}


def _draw_boundary_distance(ax, grid, image, separatrices, d_cert: float):
    """Draw :func:`_boundary_distance_scene` (as :func:`boundary_distance_map`)."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm

    d, lo, hi = image
    lo = max(lo if lo == lo else 1e-12, d_cert if d_cert > 0 else 0, 1e-12)
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = colormaps["viridis"].with_extremes(under="white", bad="0.5")
    mesh = _grid_image(ax, grid, d, cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label(
        "distance to the nearest basin boundary (rad-ish)")
    _draw_separatrices(ax, separatrices)
    cert = f"d_cert = {d_cert:.1e}" if d_cert == d_cert else "d_cert not measured"
    ax.set_title(f"Distance to tipping into another well (white: closer than {cert})")
    return ax


def boundary_distance_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw ``boundary_distance`` on a log colour scale, the separatrices, and in white the
    states closer than d_cert (labels certified for the RK4 map only); ``maps`` as
    :func:`basin_map`."""
    return _draw_boundary_distance(axes(ax, MAP_SIZE),
                                   **_boundary_distance_scene(tree, maps, **index))


#: The map figures: name → (reader, drawer); ``drawer(ax, **reader(tree, maps))`` draws one.
MAP_FIGURES = {"basin": (_basin_scene, _draw_basin),
               "trap_time": (_trap_time_scene, _draw_trap_time),
               "boundary_distance": (_boundary_distance_scene, _draw_boundary_distance)}
