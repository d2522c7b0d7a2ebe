"""The basin-map figures of one parameter point, read from the file and drawn (no computing).

* :func:`basin_map`: colour by attractor k (:func:`atlas.views.style.well_colour`, one
  colour per k in every figure; the running basin grey, no certified label white; past
  LABELLED_WELLS wells each band also named "k = …"), separatrices as thin dark outlines,
  saddles and attractors as :data:`atlas.views.style.SADDLE_MARKER` and ``ATTRACTOR_MARKER``,
  the running limit cycle dashed;
* :func:`trap_time_map`: the time at which each label was certified, on a log colour scale
  (``T_TRAP_CMAP``; t = 0 at its dark end, no label white), the separatrices faint;
* :func:`boundary_distance_map`: each state's distance to the nearest basin boundary (how far
  it is from tipping into another well) on a log scale spanning its 1st to 99th percentile
  (``DISTANCE_CMAP``), black within d_cert (labels for the RK4 map only), white where none
  is stored, the separatrices faint.

Every title names the parameter point (:func:`atlas.views.style.point_title`), so that a map
of a parameter atlas says which α (ω0, τ) it shows.

Each figure is read, then drawn: a reader (``_*_scene``) takes what it shows out of the tree
as plain arrays and strings (the map through :func:`atlas.views.coarsen.read_maps`), a drawer
(``_draw_*``) draws them and reads nothing, so that ``atlas plot`` can draw in forked
processes (:mod:`atlas.views.plotting`). matplotlib is imported only where a figure is drawn.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import first_point, point_group, point_of
from atlas.models.base import Axis
from atlas.models.registry import DEFAULT, lookup, of_attrs
from atlas.views.coarsen import read_maps
from atlas.views.style import (
    ATTRACTOR_MARKER,
    CYCLE_COLOR,
    DISTANCE_CMAP,
    LABELLED_WELLS,
    MAP_SIZE,
    NEAR_BOUNDARY_COLOR,
    NO_LABEL_COLOR,
    SEPARATRIX_ALPHA,
    SEPARATRIX_COLOR,
    SEPARATRIX_FAINT,
    SEPARATRIX_WIDTH,
    T_TRAP_CMAP,
    axes,
    basin_colours,
    critical_point_markers,
    point_title,
    window_ticks,
)

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["basin_map", "trap_time_map", "boundary_distance_map", "MAP_FIGURES",
           "draw_limit_cycle", "basin_key", "draw_separatrices", "grid_image", "label_bands"]

TWO_PI = 2.0 * np.pi
#: The axes of a scene made by hand (a scene read from a file names its model's axes).
PENDULUM_AXES = lookup(DEFAULT).axes


def _map_scene(tree: xr.DataTree, name: str, maps: dict | None, index: dict
               ) -> tuple[xr.Dataset, dict]:
    """The point drawn (its dataset) and what every map figure shows of it: the grid (its
    model's axes: for the pendulum θ0 [rad], θ̇0 [rad/s]) and the axes themselves, the map
    ``name`` as :func:`read_maps` reads it, the separatrix branches (θ [rad], θ̇ [rad/s];
    none where not stored) and the point's parameters as a title line
    (:func:`point_title`)."""
    from atlas.store.separatrices import branches

    ds = first_point(tree.to_dataset(inherit=False), **index)
    sep = point_group(tree, "separatrices", point_of(ds))
    columns, rows = of_attrs(ds.attrs).axes
    return ds, {"grid": (ds[columns.name].values, ds[rows.name].values),
                "grid_axes": (columns, rows),
                "image": (maps or read_maps(tree, name, **index))[name],
                "separatrices": [] if sep is None else
                [(theta, theta_dot) for _, _, theta, theta_dot in branches(sep)],
                "point": point_title(point_of(ds))}


def grid_image(ax, grid: tuple[np.ndarray, np.ndarray], image: np.ndarray,
               grid_axes: tuple[Axis, Axis] = PENDULUM_AXES, **kwargs):
    """Draw a map over the grid (columns, rows: the model's ``grid_axes``; the pendulum's θ0 and
    θ̇0) as an image whose pixels are the grid's cells (centred on the grid
    points); ``image``: the map already coarsened to the figure's resolution (its blocks then
    span the same extent). An axis in radians gets ticks at multiples of π."""
    th, v = grid
    half_t = 0.5 * (th[-1] - th[0]) / max(th.size - 1, 1)
    half_v = 0.5 * (v[-1] - v[0]) / max(v.size - 1, 1)
    image = ax.imshow(np.ma.masked_invalid(image), origin="lower",
                      extent=(th[0] - half_t, th[-1] + half_t, v[0] - half_v, v[-1] + half_v),
                      aspect="auto", interpolation="nearest", **kwargs)
    ax.set_xlim(th[0], th[-1])
    ax.set_ylim(v[0], v[-1])
    columns, rows = grid_axes
    window_ticks(ax, th[0], th[-1], "x", columns.symbol, columns.unit_text,
                 pi=columns.units == "rad")
    window_ticks(ax, v[0], v[-1], "y", rows.symbol, rows.unit_text)
    return image


def draw_separatrices(ax, separatrices: list, faint: bool = False) -> None:
    """The separatrix branches (θ [rad], θ̇ [rad/s]): thin, near-black, translucent lines
    (about one pixel of the saved map), so that a tongue of a basin a few pixels wide keeps
    its colour between its two outlines; ``faint``: thinner, white and fainter still, over
    the t_trap and distance maps, whose ridges and valleys lie along them."""
    style = SEPARATRIX_FAINT if faint else {"color": SEPARATRIX_COLOR, "lw": SEPARATRIX_WIDTH,
                                            "alpha": SEPARATRIX_ALPHA}
    for i, (theta, theta_dot) in enumerate(separatrices):
        ax.plot(theta, theta_dot, **style, solid_capstyle="butt",
                label=("separatrices (basin boundaries)" if not faint else
                       "separatrices (faint)") if i == 0 else None)


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
    [s]) where stored, the attractors of a driven pendulum (:func:`_attractors_scene`) and
    the title."""
    ds, scene = _map_scene(tree, "basin", maps, index)
    point = point_of(ds)
    cp = point_group(tree, "critical_points", point)
    cycle = point_group(tree, "limit_cycle", point)
    return {name: value for name, value in scene.items() if name != "point"} | {
        "attractors": _attractors_scene(point_group(tree, "attractors", point)),
        "critical": None if cp is None else  # odd n: saddles
        (cp["theta"].values, cp["n"].values % 2 != 0, bool(float(ds["torque"]))),
        "cycle": None if cycle is None else
        (cycle["theta"].values, cycle["theta_dot"].values, float(cycle.attrs["period"])),
        "title": f"Basins of attraction, {scene['point']}"}


def _attractors_scene(group: xr.Dataset | None) -> dict | None:
    """A driven pendulum's attractors as the basin map draws them (from ``/attractors``):
    each attractor's name and colour (:func:`atlas.views.style.attractor_colours`: by
    kind) by its index k (:func:`atlas.views.info_driven.attractor_key`) and its points
    on the stroboscopic map (θ [rad] wrapped, θ̇ [rad/s]; a chaotic one's cloud); None where the
    point has no such group."""
    from atlas.views.info_driven import attractor_key

    if group is None:
        return None
    names, colours = attractor_key(group)
    marks = []
    for i in range(group.sizes.get("attractor", 0)):
        theta, theta_dot = group["theta"].values[i], group["theta_dot"].values[i]
        keep = np.isfinite(theta)
        marks.append((theta[keep], theta_dot[keep], str(group["kind"].values[i])))
    return {"names": names, "marks": marks, "colours": colours}


def draw_attractors(ax, marks: list) -> None:
    """The attractors' points on the stroboscopic map: a periodic orbit's points as the
    attractor marker (:data:`atlas.views.style.ATTRACTOR_MARKER`), a chaotic attractor's
    cloud as small black dots."""
    for i, (theta, theta_dot, kind) in enumerate(marks):
        first = i == 0 or all(m[2] != kind for m in marks[:i])
        if kind == "chaotic":
            ax.plot(theta, theta_dot, ls="none", marker=".", ms=1.0, color="black", zorder=5,
                    label="chaotic attractor (its points on the map)" if first else None)
        else:
            ax.plot(theta, theta_dot, **ATTRACTOR_MARKER, zorder=5, clip_on=True,
                    label="periodic attractors (their points on the map)" if first else None)


def _run_depth(mask: np.ndarray) -> np.ndarray:
    """Per pixel of ``mask`` (rows × columns), the number of pixels to the nearest pixel
    outside it (or the image's edge) along the row and the column, the least of the four
    directions; 0 outside. Its largest value sits in the widest part of a region."""
    def from_start(m):  # pixels since the last one outside, along each row
        idx = np.arange(m.shape[1])
        last = np.maximum.accumulate(np.where(m, -1, idx), axis=1)
        return np.where(m, idx - last, 0)

    return np.minimum.reduce([from_start(mask), from_start(mask[:, ::-1])[:, ::-1],
                              from_start(mask.T).T, from_start(mask.T[:, ::-1])[:, ::-1].T])


#: A band is named only where it is at least this many pixels deep (a sliver has no room).
_LABEL_DEPTH = 4


def _well_name(k: int) -> str:
    """"+3", "0", "−3": a well's name in keys and labels."""
    return f"{k:+d}".replace("+0", "0").replace("-", "−")


def label_bands(ax, grid, image: np.ndarray, ks: list[int]) -> None:
    """Name each well's band "k = …" at the pixel deepest inside it (:func:`_run_depth`;
    of equally deep pixels, the one nearest the middle column): the basin map's key once its
    colours alone are too many to tell apart. Bands nowhere _LABEL_DEPTH pixels deep stay
    unnamed (the colour bar names them). The rows near θ̇ = 0, where the rest states and
    saddles are marked, are avoided wherever the band is deep enough elsewhere."""
    import matplotlib.patheffects as pe

    th, v = grid
    middle = 1.0 - np.abs(np.linspace(-1.0, 1.0, image.shape[1]))  # 1 in the middle, 0 at edges
    rows = np.linspace(v[0], v[-1], image.shape[0])
    markers = np.abs(rows) <= max(0.06 * abs(v[-1] - v[0]),
                                  3.0 * abs(v[-1] - v[0]) / max(image.shape[0] - 1, 1))
    for k in ks:
        depth = _run_depth(image == k)
        if depth.max() < _LABEL_DEPTH:
            continue
        score = depth + 0.5 * middle
        away = np.where(markers[:, None], -np.inf, score)
        if depth[~markers].max(initial=0) >= _LABEL_DEPTH:
            score = away
        r, c = np.unravel_index(score.argmax(), depth.shape)
        ax.text(th[0] + (th[-1] - th[0]) * c / max(image.shape[1] - 1, 1),
                v[0] + (v[-1] - v[0]) * r / max(image.shape[0] - 1, 1), f"k = {_well_name(k)}",
                fontsize=6, ha="center", va="center", zorder=6,
                path_effects=[pe.withStroke(linewidth=1.8, foreground="white")])


def basin_key(wells: list[int], running: bool, unlabelled: bool,
              colours: dict[int, str] | None = None):
    """The colour key of basin maps showing ``wells`` (ascending k), with the running basin
    and "no label" where present: (colormap, norm, tick values, tick names, what the colours
    mean, in a line). Each well has its own fixed colour (:func:`basin_colours`). An image
    holds k for a well, ``wells[-1] + 1`` for the running basin, NaN for no label; a k
    between two wells that is none (a model whose labels skip it) has no colour of its own,
    the norm's bins lying halfway between the values drawn. ``colours``: each label's own
    colour where the model gives one (a driven pendulum's attractors, by kind), instead of
    the wells'."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    palette = basin_colours(wells, running=running) | (colours or {})
    colors, names = [palette[k] for k in wells], [_well_name(k) for k in wells]
    if running:  # the running basin: one more colour after the wells
        colors.append(palette["running"])
        names.append("running")
    if unlabelled:  # no certified label (NaN, drawn as "bad"): one more entry of the key
        colors.append(palette["none"])
        names.append("no label")
    top = wells[-1] if wells else -1
    values = np.array([*wells, *range(top + 1, top + 1 + len(colors) - len(wells))], float)
    cmap = ListedColormap(colors).with_extremes(bad=palette["none"])
    edges = np.r_[values[0] - 0.5, 0.5 * (values[1:] + values[:-1]), values[-1] + 0.5]
    norm = BoundaryNorm(edges, cmap.N)
    meaning = ("colour: the well k at whose rest state the orbit settles"
               + ("; running: it rotates (the running limit cycle)" if running else "")
               + ("; no label: unresolved by t_max, or not finite" if unlabelled else ""))
    return cmap, norm, values.astype(int).tolist(), names, meaning


def drawn_wells(image: np.ndarray, kmin: int, kmax: int) -> list[int]:
    """The wells a basin map's key names: every k from ``kmin`` to ``kmax`` (the whole
    map's, read at full resolution) that the drawn ``image`` holds, and both ends (a well
    of a model whose labels skip a k, as the Duffing oscillator's −1 and +1, gets no key
    entry for the k between)."""
    held = {int(k) for k in np.unique(image[np.isfinite(image) & (image <= kmax)])}
    return [k for k in range(kmin, kmax + 1) if k in held or k in (kmin, kmax)]


def _draw_basin(ax, grid, image, separatrices, critical, cycle, title: str,
                grid_axes: tuple[Axis, Axis] = PENDULUM_AXES, attractors: dict | None = None):
    """Draw :func:`_basin_scene` (as :func:`basin_map`)."""
    k, kmin, kmax, running = image
    wells = drawn_wells(k, kmin, kmax)
    unlabelled = bool(np.isnan(k).any())
    cmap, norm, ticks, names, _ = basin_key(
        wells, running, unlabelled, None if attractors is None else attractors["colours"])
    if attractors is not None:  # a driven pendulum's: each named by period and winding
        names = [attractors["names"].get(w, str(w)) for w in wells] + names[len(wells):]
    mesh = grid_image(ax, grid, k, grid_axes, cmap=cmap, norm=norm)
    cbar = ax.figure.colorbar(mesh, ax=ax, ticks=ticks)
    cbar.ax.set_yticklabels(names, fontsize=8 if len(names) <= 24 else 6)
    meaning = ("attractor k: orbit settles at the rest state of well k" if attractors is None
               else "attractor of the stroboscopic map reached")
    cbar.set_label(meaning
                   + (";\nrunning: orbit rotates (the running limit cycle)" if running else "")
                   + (";\nno label: unresolved by t_max, or not finite" if unlabelled else ""))
    if attractors is not None:
        draw_attractors(ax, attractors["marks"])
    if len(wells) > LABELLED_WELLS:
        label_bands(ax, grid, k, wells)
    draw_separatrices(ax, separatrices)
    if cycle is not None:
        draw_limit_cycle(ax, grid[0][0], grid[0][-1], *cycle)
    if critical is not None:
        critical_point_markers(ax, *critical)
    ax.set_title(title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=3, borderaxespad=0)
    return ax


def basin_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the basin map of ``tree`` (colour by k) with critical points and separatrices;
    ``maps``: :func:`read_maps` of the same point, if already read."""
    return _draw_basin(axes(ax, MAP_SIZE), **_basin_scene(tree, maps, **index))


def _trap_time_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`trap_time_map` draws (:func:`_map_scene`'s), and for a model other than
    the pendulum what its ``t_trap`` is (its long name: a label "decided", not
    "certified")."""
    ds, scene = _map_scene(tree, "t_trap", maps, index)
    model = of_attrs(ds.attrs)
    return scene | ({} if model.name == DEFAULT else
                    {"meaning": str(ds["t_trap"].attrs.get("long_name", "time to a label"))})


def _draw_trap_time(ax, grid, image, separatrices, point: str,
                    grid_axes: tuple[Axis, Axis] = PENDULUM_AXES, meaning: str | None = None):
    """Draw :func:`_trap_time_scene` (as :func:`trap_time_map`); ``point``: the parameter
    point's title line."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm

    # blocks keep their largest t_trap (the transform below is monotone: the same as the
    # largest of the transformed cells)
    t, lo, hi = image
    lo = lo if lo == lo else 1e-2
    hi = max(hi if hi == hi else 1.0, lo * 10)
    cmap = colormaps[T_TRAP_CMAP]
    # t_trap = 0 (certified at once: the orbit starts inside the trap) is the shortest time
    # there is: drawn below the scale in the scale's own dark end, not in a colour of its own
    cmap = cmap.with_extremes(under=cmap(0.0), bad=NO_LABEL_COLOR)
    mesh = grid_image(ax, grid, np.where(t == 0, lo / 2, t), grid_axes, cmap=cmap,
                      norm=LogNorm(lo, hi))
    if meaning is None:  # the pendulum's
        ax.figure.colorbar(mesh, ax=ax, extend="min").set_label(
            "t_trap [s]: time at which the label was certified\n(trapped in a well, or "
            "running)")
        ax.set_title(f"Time to a certified label, {point}\n(darkest: certified at t = 0; "
                     "white: no label certified by t_max"
                     + (";\nfaint lines: the separatrices)" if separatrices else ")"))
    else:
        ax.figure.colorbar(mesh, ax=ax, extend="min").set_label(f"t_trap [s]: {meaning}")
        ax.set_title(f"Time to a label, {point}\n(white: no label by t_max)")
    draw_separatrices(ax, separatrices, faint=True)
    return ax


def trap_time_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw the certified trapping time t_trap [s] on a log colour scale, white where no label
    was certified (``maps`` as :func:`basin_map`)."""
    return _draw_trap_time(axes(ax, MAP_SIZE), **_trap_time_scene(tree, maps, **index))


def _boundary_distance_scene(tree: xr.DataTree, maps: dict | None = None, **index) -> dict:
    """What :func:`boundary_distance_map` draws: :func:`_map_scene`'s and d_cert (rad and
    rad/s as one Euclidean unit, as ``boundary_distance``)."""
    ds, scene = _map_scene(tree, "boundary_distance", maps, index)
    return scene | {"d_cert": float(ds["d_cert"]) if "d_cert" in ds else math.nan}


def _draw_boundary_distance(ax, grid, image, separatrices, d_cert: float, point: str,
                            grid_axes: tuple[Axis, Axis] = PENDULUM_AXES):
    """Draw :func:`_boundary_distance_scene` (as :func:`boundary_distance_map`); ``point``:
    the parameter point's title line."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap, LogNorm

    d = image[0]
    measured = d_cert == d_cert
    lo, hi = _spread(d[np.isfinite(d) & (d > (d_cert if measured else 0.0))])
    cmap = colormaps[DISTANCE_CMAP].with_extremes(bad=NO_LABEL_COLOR)
    mesh = grid_image(ax, grid, d, grid_axes, cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="both").set_label(
        "distance to the nearest basin boundary\n[rad (θ) and rad/s (θ̇) as one Euclidean "
        "unit];\ncolours span its 1st to 99th percentile")
    near = measured and bool(np.any(d <= d_cert))
    if near:  # closer than d_cert: black, over the map
        ax.imshow(np.ma.masked_where(~(d <= d_cert), np.ones_like(d)), origin="lower",
                  extent=ax.images[0].get_extent(), aspect="auto", interpolation="nearest",
                  cmap=ListedColormap([NEAR_BOUNDARY_COLOR]), zorder=1)
    draw_separatrices(ax, separatrices, faint=True)
    note = (f"black: closer than d_cert = {d_cert:.1e} (labels certified for the RK4 map "
            "only)" if near else f"none closer than d_cert = {d_cert:.1e}: every label "
            "certified for the exact equation" if measured else
            "d_cert not measured: labels certified for the RK4 map only")
    notes = ["white: no distance stored"] * bool(np.isnan(d).any()) + [note]
    ax.set_title(f"Distance to the nearest basin boundary, {point}\n({'; '.join(notes)};\n"
                 "faint lines: the separatrices)")
    return ax


def _spread(values: np.ndarray) -> tuple[float, float]:
    """Limits of a log colour scale that spreads ``values`` (positive): their 1st and 99th
    percentiles (apart by a factor 10 at least); 1e-3, 1 if there are none."""
    if not values.size:
        return 1e-3, 1.0
    lo, hi = np.percentile(values, [1.0, 99.0])
    return float(lo), float(max(hi, 10 * lo))


def boundary_distance_map(tree: xr.DataTree, ax=None, maps: dict | None = None, **index):
    """Draw ``boundary_distance`` on a log colour scale spanning its 1st to 99th percentile,
    the separatrices faint, and in black the states closer than d_cert (labels certified for
    the RK4 map only); ``maps`` as :func:`basin_map`."""
    return _draw_boundary_distance(axes(ax, MAP_SIZE),
                                   **_boundary_distance_scene(tree, maps, **index))


#: The map figures: name → (reader, drawer); ``drawer(ax, **reader(tree, maps))`` draws one.
MAP_FIGURES = {"basin": (_basin_scene, _draw_basin),
               "trap_time": (_trap_time_scene, _draw_trap_time),
               "boundary_distance": (_boundary_distance_scene, _draw_boundary_distance)}
