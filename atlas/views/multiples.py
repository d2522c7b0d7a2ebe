"""A parameter atlas shown whole: small multiples of its basin maps, one panel per parameter
point, one colour key for all.

``atlas plot`` of a parameter atlas draws this as its basin figure (``NAME.png``): at most
MAX_PANELS panels, the points chosen evenly across the atlas (its first and last always
among them) and listed in the title, each panel titled with its swept parameters' values and
units and its point number (``#i``, the index ``atlas plot --point I`` takes). Every panel
is coloured with the one basin palette, :func:`atlas.views.style.well_colour` (a colour
means one k across the figure, and in every other figure), the running basin and "no
certified label" included, in one key (:func:`atlas.views.maps.basin_key`); the
separatrices, the running limit cycle and the critical points are drawn as on the single
map (:mod:`atlas.views.maps`), whose pieces these panels reuse.

As every figure of ``atlas plot``, it is read (:func:`multiples_scene`: each panel's map
band by band, coarsened, through the basin map's own reader) and then drawn
(:func:`draw_multiples`, which reads nothing), so that it can be drawn in a forked process.
"""

from __future__ import annotations

import math
import textwrap
from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import points
from atlas.views.maps import (
    MAP_FIGURES,
    basin_key,
    draw_limit_cycle,
    draw_separatrices,
    grid_image,
    label_bands,
)
from atlas.views.selectors import point_index, swept, value_text
from atlas.views.style import LABELLED_WELLS, critical_point_markers

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["MAX_PANELS", "chosen_panels", "multiples_scene", "draw_multiples",
           "multiples_size"]

#: The most panels a small-multiples figure draws: past it, the points drawn are chosen
#: evenly across the atlas (``atlas plot --point I`` draws any other as a full map).
MAX_PANELS = 12
#: The bands of a panel are named on its map sampled to at most this many pixels per axis:
#: a band is named where it is a few of these deep, room for its label in a panel.
_LABEL_ROWS = 64
#: A panel's size [in] and the room the colour key, the title and the axis labels take.
_PANEL, _KEY_WIDTH, _MARGIN = (2.9, 2.1), 1.7, 1.0


def chosen_panels(n: int, most: int | None = None) -> list[int]:
    """The indices of the points drawn of ``n``: all if ``n`` ≤ ``most`` (default
    MAX_PANELS); else ``most`` of them evenly spread (rounded from equal steps), the first
    and the last among them."""
    most = MAX_PANELS if most is None else most
    if n <= most:
        return list(range(n))
    return sorted({int(round(i * (n - 1) / (most - 1))) for i in range(most)})


def _grid_shape(n: int) -> tuple[int, int]:
    """Rows and columns of ``n`` panels: at most 4 columns, rows as full as they can be."""
    rows = math.ceil(n / 4)
    return rows, math.ceil(n / rows)


def multiples_size(n: int) -> tuple[float, float]:
    """The figure size [in] of ``n`` panels, the colour key at the right."""
    rows, cols = _grid_shape(n)
    return cols * _PANEL[0] + _KEY_WIDTH, rows * _PANEL[1] + _MARGIN


def _panel_title(point: dict[str, float], names: list[str], number: int) -> str:
    """"α = 0.02 s⁻¹ (#0)": the swept parameters' values with units, and the point's
    number."""
    return ", ".join(value_text(name, point[name]) for name in names) + f"  (#{number})"


def multiples_scene(tree: xr.DataTree) -> dict:
    """What :func:`draw_multiples` draws of the atlas ``tree``, read: per chosen point
    (:func:`chosen_panels`) its basin map (as :func:`atlas.views.maps.basin_map` reads it,
    the running basin's value moved to the figure's largest well + 1), separatrices,
    critical points, limit cycle and title; the figure's wells, whether any panel has a
    running basin, and the title."""
    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    names = swept(ds)
    chosen = chosen_panels(len(every))
    read = MAP_FIGURES["basin"][0]
    panels = []
    for i in chosen:
        scene = read(tree, None, **point_index(ds, every[i]))
        image, kmin, kmax, running = scene["image"]
        wells = np.unique(image[np.isfinite(image) & (image <= kmax)]).astype(int).tolist()
        panels.append(scene | {"title": _panel_title(every[i], names, i),
                               "image": image, "wells": wells,
                               "running_value": kmax + 1 if running else None})
    found = sorted({k for panel in panels for k in panel["wells"]})
    wells = found  # the wells drawn in some panel (a model may skip a k)
    top = wells[-1] if wells else -1  # no well anywhere: the running basin is 0
    running = any(panel["running_value"] is not None for panel in panels)
    for panel in panels:  # one value for the running basin in every panel: top + 1
        value = panel.pop("running_value")
        if value is not None:
            panel["image"] = np.where(panel["image"] == value, top + 1, panel["image"])
    fixed = [value_text(name, value) for name, value in every[0].items()
             if name not in names and (value or name != "torque")]  # no torque: not said
    which = (f"all {len(every)} parameter points" if len(chosen) == len(every) else
             f"{len(chosen)} of {len(every)} parameter points, chosen evenly (#"
             + ", ".join(map(str, chosen)) + "; any other: atlas plot --point I)")
    return {"panels": panels, "wells": wells, "running": running,
            "title": f"Basins of attraction at {which}"
                     + (", " + ", ".join(fixed) if fixed else "")}


def draw_multiples(ax, panels: list[dict], wells: list[int], running: bool, title: str):
    """Draw :func:`multiples_scene` into the figure of ``ax`` (which it replaces by a grid of
    panels and a colour key spanning their rows); returns the panels' Axes."""
    fig = ax.figure
    ax.remove()
    rows, cols = _grid_shape(len(panels))
    grid = fig.add_gridspec(rows, cols + 1, width_ratios=[1] * cols + [0.06])
    unlabelled = any(bool(np.isnan(panel["image"]).any()) for panel in panels)
    cmap, norm, ticks, names, meaning = basin_key(wells, running, unlabelled)
    drawn, first = [], None
    for i, panel in enumerate(panels):
        ax = fig.add_subplot(grid[i // cols, i % cols], sharex=first, sharey=first)
        first = first or ax
        mesh = grid_image(ax, panel["grid"], panel["image"], panel["grid_axes"], cmap=cmap,
                          norm=norm)
        if len(panel["wells"]) > LABELLED_WELLS:  # named where a label fits in the panel
            step = max(1, -(-max(panel["image"].shape) // _LABEL_ROWS))
            label_bands(ax, panel["grid"], panel["image"][::step, ::step], panel["wells"])
        draw_separatrices(ax, panel["separatrices"])
        if panel["cycle"] is not None:
            draw_limit_cycle(ax, panel["grid"][0][0], panel["grid"][0][-1], *panel["cycle"])
        if panel["critical"] is not None:
            critical_point_markers(ax, *panel["critical"])
        ax.set_title(panel["title"], fontsize=9)
        ax.tick_params(labelsize=8)
        if i + cols < len(panels):  # the panel below shows the θ axis
            ax.tick_params(labelbottom=False)
            ax.set_xlabel("")
        if i % cols:
            ax.tick_params(labelleft=False)
            ax.set_ylabel("")
        drawn.append(ax)
    cbar = fig.colorbar(mesh, cax=fig.add_subplot(grid[:, cols]), ticks=ticks)
    cbar.ax.set_yticklabels(names, fontsize=8 if len(names) <= 24 else 6)
    cbar.set_label("attractor k", fontsize=9)
    marks = [text for drawn_here, text in (
        (any(panel["separatrices"] for panel in panels), "thin lines: the separatrices"),
        (any(panel["critical"] is not None for panel in panels),
         "dots: rest states, open circles: saddles"),
        (any(panel["cycle"] is not None for panel in panels),
         "dashed: the running limit cycle")) if drawn_here]
    # wrapped to the figure's width: about 0.55 em per character of a 10 pt sans font
    width = int(fig.get_figwidth() * 72 / (0.55 * 10))
    fig.suptitle("\n".join(textwrap.wrap(title, width)
                           + textwrap.wrap("; ".join([meaning, *marks]), width)), fontsize=10)
    return drawn
