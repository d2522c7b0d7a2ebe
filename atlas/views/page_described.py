"""``atlas view`` of an atlas of any model but the pendulum: one self-contained HTML page of
what the file stores, from its model's description (:class:`atlas.models.base.Model`).

Per parameter point: the basin map as a PNG at the grid's native resolution (each label k in
its colour of every figure, :func:`atlas.views.style.well_colour`; no label white), its axes
by the model's axes and the window's ends, and a key with each basin's stored share of the
grid; then what each status code means in the file. A model whose equation the page can
integrate gets a script that follows a clicked orbit with that model's own step: the driven
pendulum (:mod:`atlas.views.page_driven`, its returns to the stroboscopic map labelled by the
run's rule). Any other model's page has no script (the pendulum's own page,
:mod:`atlas.views.page`, integrates the pendulum's RK4 step and certificate), and says so
rather than follow an orbit of the wrong equation.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import at_point, point_group, point_label, points
from atlas.models.base import Model
from atlas.models.driven.description import DRIVEN_PENDULUM
from atlas.views.info_driven import attractor_key
from atlas.views.map_png import labelled_wells, map_png
from atlas.views.style import NO_LABEL_COLOR, RUNNING_COLOR_HEX, well_colour

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["described_page"]

_STYLE = """
body { font: 14px/1.4 "DejaVu Sans", system-ui, sans-serif; margin: 10px 16px; color: #222; }
h1 { font-size: 18px; margin: 0 0 2px; } h2 { font-size: 15px; margin: 14px 0 4px; }
p { margin: 2px 0; color: #444; }
section { max-width: 960px; }
img { width: 100%; image-rendering: pixelated; border: 1px solid #888; }
table { border-collapse: collapse; margin: 6px 0; } td, th { padding: 1px 8px; text-align: left; }
.swatch { display: inline-block; width: 14px; height: 14px; border: 1px solid #555;
          vertical-align: middle; }
"""


def _esc(value) -> str:
    return html.escape(str(value), quote=True)


def _ends(values: np.ndarray) -> str:
    return f"{float(values[0]):g} to {float(values[-1]):g}"


def _point_section(ds: xr.Dataset, model: Model, title: str,
                   key: tuple[dict[int, str], dict[int, str]], index: int | None = None) -> str:
    """One parameter point: its map, the window, the key with the stored shares (each
    attractor named and coloured by ``key``, (names, colours), where given); with
    ``index`` (the driven pendulum's page), a layer over the map that a click follows an
    orbit on, and its readout."""
    columns, rows = model.axes
    kinds = model.status_kinds()
    attractor = ds["attractor"].values.astype(np.int16)
    status = ds["status"].values.astype(np.int8)
    labelled, wells = labelled_wells(attractor, status, kinds)
    share = dict(zip(ds["k"].values.tolist(), ds["basin_fraction"].values.tolist())
                 ) if "basin_fraction" in ds else {}
    names, colours = key
    key = [(colours.get(int(k)) or well_colour(int(k)), names.get(int(k), f"k = {int(k):+d}"),
            f"{share[int(k)]:.4f} of the grid" if int(k) in share else "") for k in wells]
    running = kinds[status.astype(np.int64) + 128] == 2
    if running.any():
        key.append((RUNNING_COLOR_HEX, "running", f"{running.mean():.4f} of the grid"))
    if (~labelled & ~running).any():
        key.append((NO_LABEL_COLOR, "no label", f"{(~labelled & ~running).mean():.4f} of "
                    "the grid"))
    cells = "".join(f'<tr><td><span class="swatch" style="background:{colour}"></span></td>'
                    f"<td>{_esc(name)}</td><td>{_esc(text)}</td></tr>"
                    for colour, name, text in key)
    image = f'<img src="{map_png(attractor, status, wells, kinds, colours)}" alt="basin map">'
    opening, readout = "<section>", ""
    if index is not None:
        opening = f'<section data-point="{index}">'
        image = (f'<div class="stage">{image}<canvas title="click to follow the orbit from '
                 'here"></canvas></div>')
        readout = ('<div class="orbit-readout" aria-live="polite" data-ready="0"><p>Click the '
                   "map to follow the orbit from that point: its returns to P are drawn as "
                   "black dots, the attractors' points on P as white diamonds.</p></div>")
    return (f"{opening}<h2>{_esc(title)}</h2>{image}{readout}"
            f"<p>{_esc(columns.label)} from {_esc(_ends(ds[columns.name].values))} (left to "
            f"right), {_esc(rows.label)} from {_esc(_ends(ds[rows.name].values))} (bottom "
            f"to top); one pixel per grid point.</p><table>{cells}</table></section>")


def _orbits(tree: xr.DataTree, ds: xr.Dataset, model: Model) -> list[dict | None] | None:
    """Per parameter point what the page needs to follow an orbit in the browser, for a
    model whose equation the page integrates (the driven pendulum:
    :mod:`atlas.views.page_driven`); None for any other."""
    if model.name != DRIVEN_PENDULUM.name:
        return None
    from atlas.views.page_driven import orbit_data

    t_max = float(ds.attrs["t_max"])
    return [orbit_data(tree, at_point(ds, point), point, t_max, model.statuses)
            for point in points(ds)]


_FOLLOWS = """<p>Click a map to follow the orbit from that initial state: it is integrated
here in the browser with atlas's own stroboscopic map P (RK4, dt = T/N from t = 0, the
drive read at each step's ends and middle), its returns to P are drawn over the map, and it
is labelled by the run's rule, next to the label the file stores at the nearest grid
point.</p>"""
_STATIC = """<p>This page shows the stored labels only. Clicking to follow an orbit works on the
pendulum's page only, because that page integrates the pendulum's own equation in the
browser.</p>"""
_STAGE_STYLE = """
.stage { position: relative; line-height: 0; }
.stage canvas { position: absolute; left: 0; top: 0; width: 100%; height: 100%;
                cursor: crosshair; }
.orbit-readout { margin: 6px 0; padding: 4px 8px; border-left: 4px solid #222;
                 background: #f4f4f4; font-size: 15px; }
.orbit-readout p { color: #111; }
.orbit-label { font-weight: bold; }
"""


def described_page(tree: xr.DataTree, path: Path, model: Model) -> str:
    """The whole HTML page of the atlas ``tree`` of ``model``, read from ``path``."""
    ds = tree.to_dataset(inherit=False)
    columns, rows = model.axes
    orbits = _orbits(tree, ds, model)
    sections = "".join(
        _point_section(at_point(ds, point), model, point_label(point),
                       attractor_key(point_group(tree, "attractors", point)),
                       p if orbits is not None and orbits[p] is not None else None)
        for p, point in enumerate(points(ds)))
    style, script, csp, note = _STYLE, "", "", _STATIC
    if orbits is not None and any(o is not None for o in orbits):
        from atlas.views.page_driven import script as driven_script
        from atlas.views.page_driven import script_hash

        code = driven_script()
        style, note = _STYLE + _STAGE_STYLE, _FOLLOWS
        csp = f"; script-src '{script_hash(code)}'"
        data = _esc(json.dumps(orbits, allow_nan=False, separators=(",", ":")))
        script = (f'<div id="atlas-data" hidden data-json="{data}"></div>\n'
                  f"<script>{code}</script>\n")
    meanings = "".join(f"<tr><td>{code}</td><td>{_esc(word)}</td><td>"
                       f"{_esc(model.in_file.get(code, ''))}</td></tr>"
                       for code, word in model.statuses.items())
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; img-src data:; \
style-src 'unsafe-inline'{csp}">
<title>{_esc(Path(path).name)} · atlas view</title>
<style>{style}</style>
</head>
<body>
<header>
<h1>Basins of the {_esc(model.title)} (model {_esc(model.name)}): {_esc(Path(path).name)}</h1>
<p>Grid {ds.sizes[columns.name]} × {ds.sizes[rows.name]} ({_esc(columns.long_name)} ×
{_esc(rows.long_name)}); dt = {_esc(f"{float(ds.attrs.get('dt', math.nan)):g}")} s,
t_max = {_esc(f"{float(ds.attrs.get('t_max', math.nan)):g}")} s. Each pixel is an initial
state, coloured by the label the file stores for it.</p>
{note}
</header>
{sections}
<footer>
<h2>What each status means in this file</h2>
<table>{meanings}</table>
<p>{_esc(ds.attrs.get("title", ""))}; created {_esc(ds.attrs.get("created", ""))} by atlas
{_esc(ds.attrs.get("atlas_version", ""))}.</p>
</footer>
{script}</body>
</html>
"""
