"""``atlas view``: one self-contained HTML page to look at an atlas and click orbits.

The page (no server, no network: every script, style and image is inline) shows the basin map
of each parameter point as a PNG at the grid's native resolution, in the basin palette of
:func:`atlas.views.style.well_colour` (each well k the colour it has in every PNG, named in a
colour key; past LABELLED_WELLS wells each band is also named on the map), with its
separatrices and critical points (the figures' markers, :data:`atlas.views.style.SADDLE_MARKER`
and ``ATTRACTOR_MARKER``; and, with a torque τ, the running basin and the running limit
cycle). The palette, the colour maps and the markers come from :mod:`atlas.views.style` in
the page's data: the script keeps no colours of its own. The map fills the window's width (a
1920 px screen and a 400 px phone alike); it is drawn before the page's load event ends. A
layer switch shows t_trap or the boundary distance instead, in the PNGs' colour maps
(``T_TRAP_CMAP``, ``DISTANCE_CMAP``; log scales: t_trap from its least to its greatest
positive value, the distance between its 1st and 99th percentiles); a hover
line reads
the stored label, status, t_trap and distance of the grid point under the pointer. A click, or
a point typed in exact coordinates, integrates that orbit in the browser
(``view_assets/view.js``): the RK4 step of θ̈ = −ω0² sin θ − 2αθ̇ + τ of the file's method,
with the certificate the file's run used, read from the file (format 4: the trap's
``trap_energy_cap`` and ``trap_margin``, the running barrier of each ``/limit_cycle`` node;
nothing is rebuilt here), tested every ``check_every`` steps in the kernels' order, then
followed until it has settled (in its well, or on the running cycle). Orbits are kept until
cleared, drawn modulo the window's whole turns (a piece that leaves the window is drawn a whole
number of turns away, inside it); the pendulum is animated, and the readout shows the orbit's
label and certificate (the energy against the trap's level to one precision) next to the
stored label of the nearest grid point. A parameter atlas gets a slider. A file of format 3
stores no certificate and is refused with one line. How the arrays are packed (about 1 MB for
512²; the barrier never rounded) and why file strings cannot run as markup:
``docs/design/views.md``.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import os
import zlib
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import AtlasError, InputFileError
from atlas.layout import at_point, point_group
from atlas.layout import points as parameter_points
from atlas.models.registry import DEFAULT, of_attrs
from atlas.physics.pendulum import Pendulum, tilt, tilt_versine
from atlas.status import (
    RUNNING,
    RUNNING_NEAR_BOUNDARY,
    STATUS_MEANINGS,
)
from atlas.store.reader import open_atlas, require_certificate, stored_certificate
from atlas.store.separatrices import branches
from atlas.store.validate import file_method
from atlas.views.map_png import labelled_wells, map_png
from atlas.views.style import (
    ATTRACTOR_MARKER,
    DISTANCE_CMAP,
    LABELLED_WELLS,
    NEAR_BOUNDARY_COLOR,
    NO_LABEL_COLOR,
    ORBIT_START_MARKER,
    RUNNING_COLOR_HEX,
    SADDLE_MARKER,
    SEPARATRIX_ALPHA,
    SEPARATRIX_COLOR,
    SEPARATRIX_FAINT,
    T_TRAP_CMAP,
    colormap_table,
    well_palette,
)

__all__ = ["write_view", "build_page", "pack_distance", "unpack_distance", "safe_json",
           "page_style", "DIST_STEPS"]

#: Steps per octave of the log2-quantised boundary distance.
DIST_STEPS = 256
_DIST_OFFSET = 128  # log2 d from -128 to +128 fits uint16 at 256 steps per octave
_T_NAN = np.iinfo(np.uint32).max


def pack_distance(d: np.ndarray) -> np.ndarray:
    """boundary_distance → uint16: 0 for 0, 0xFFFF for NaN, else log2-quantised."""
    d = np.asarray(d, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.round((np.log2(d) + _DIST_OFFSET) * DIST_STEPS)
    q = np.clip(np.nan_to_num(q, nan=1, neginf=1, posinf=65534), 1, 65534)
    q = np.where(d == 0, 0, q)
    return np.where(np.isnan(d), 65535, q).astype("<u2")


def unpack_distance(q: np.ndarray) -> np.ndarray:
    """Inverse of :func:`pack_distance` (what the page computes)."""
    q = np.asarray(q, np.float64)
    d = 2.0 ** (q / DIST_STEPS - _DIST_OFFSET)
    return np.where(q == 0, 0.0, np.where(q == 65535, np.nan, d))


def _blob(array: np.ndarray) -> str:
    return base64.b64encode(zlib.compress(np.ascontiguousarray(array).tobytes(), 9)).decode()


def _uniform(values: np.ndarray, name: str, path) -> list[float]:
    """[first, last, n] of a uniformly spaced axis (the page maps pixels linearly). The
    spacing is compared to 1e-9 of the step, and to the rounding of the stored values
    (16 ulp of the largest: a zoom's step can be 1e-9 of its position)."""
    values = np.asarray(values, float)
    if values.size < 2 or not np.allclose(
            np.diff(values), values[1] - values[0], rtol=1e-9,
            atol=16 * np.finfo(float).eps * float(np.abs(values).max())):
        raise InputFileError(f"{path}: {name} is not a uniformly spaced axis")
    return [float(values[0]), float(values[-1]), int(values.size)]


#: Band names keep this fraction of the window's height off θ̇ = 0 (where the rest states
#: and saddles are marked) and of its width and height off its edges (where a name centred on
#: its point would be cut in half), wherever the band has room elsewhere.
_LABEL_CLEARANCE = 0.06


def _band_labels(attractor, labelled, wells, distance, theta0, theta_dot0) -> list:
    """Where the page writes "k" on the map when it has more than LABELLED_WELLS wells (past
    that, the palette repeats and a band is best named): for each well k, [k, θ0 [rad],
    θ̇0 [rad s⁻¹]] of its grid point farthest from every basin boundary (the stored
    ``boundary_distance``; with none stored, its middle point), of the points _LABEL_CLEARANCE
    away from θ̇ = 0 and from the window's edges where the band has any (as the PNG's band
    names, :func:`atlas.views.maps.label_bands`)."""
    if len(wells) <= LABELLED_WELLS:
        return []
    depth = np.where(np.isfinite(distance), distance, -1.0)
    width, height = np.ptp(theta0), np.ptp(theta_dot0)
    inside_t = np.minimum(theta0 - theta0[0], theta0[-1] - theta0) >= _LABEL_CLEARANCE * width
    inside_v = ((np.minimum(theta_dot0 - theta_dot0[0], theta_dot0[-1] - theta_dot0)
                 >= _LABEL_CLEARANCE * height)
                & (np.abs(theta_dot0) >= _LABEL_CLEARANCE * height))
    clear = inside_v[:, None] & inside_t[None, :]
    labels = []
    for k in wells:
        band = labelled & (attractor == k)
        j, i = np.nonzero(band & clear if (band & clear).any() else band)
        best = int(np.argmax(depth[j, i])) if (depth[j, i] > 0).any() else j.size // 2
        labels.append([int(k), float(theta0[i[best]]), float(theta_dot0[j[best]])])
    return labels


#: The finest the page draws: 1/CURVE_RESOLUTION of the window's width and height (a few
#: times finer than the pixels of the widest screen).
CURVE_RESOLUTION = 8192


def _decimals(span: float) -> int:
    """Decimal places that resolve 1/CURVE_RESOLUTION of ``span`` (at most 15)."""
    step = abs(span) / CURVE_RESOLUTION
    return int(min(15, max(0, math.ceil(-math.log10(step))))) if step > 0 else 15


def _curves(tree: xr.DataTree, point: dict[str, float], theta0: np.ndarray,
            theta_dot0: np.ndarray) -> list[list[list[float]]]:
    """Separatrix polylines of one parameter point as [[θ…], [θ̇…]] [rad, rad s⁻¹], rounded
    to the decimals that resolve 1/CURVE_RESOLUTION of the window's width and height (so a
    zoom keeps its digits and a wide window drops the ones no screen shows), vertices that
    round onto their predecessor dropped."""
    sep = point_group(tree, "separatrices", point)
    if sep is None or sep.sizes.get("point", 0) == 0:
        return []
    dt_, dv_ = _decimals(np.ptp(theta0)), _decimals(np.ptp(theta_dot0))
    curves = []
    for _, _, theta, theta_dot in branches(sep):
        theta, theta_dot = np.round(theta, dt_), np.round(theta_dot, dv_)
        kept = np.r_[True, (np.diff(theta) != 0) | (np.diff(theta_dot) != 0)]
        if kept.sum() > 1:
            curves.append([theta[kept].tolist(), theta_dot[kept].tolist()])
    return curves


def _critical(tree: xr.DataTree, point: dict[str, float]) -> dict[str, list[float]]:
    cp = point_group(tree, "critical_points", point)
    if cp is None:
        return {"attractors": [], "saddles": []}
    theta, n = cp["theta"].values, cp["n"].values
    return {"attractors": theta[n % 2 == 0].tolist(), "saddles": theta[n % 2 != 0].tolist()}


#: About how many segments of the limit cycle the page draws (a picture only).
CYCLE_DRAWN = 256


def _running(tree: xr.DataTree, point: dict[str, float], barrier) -> dict:
    """The running barrier and the limit cycle of one parameter point for the page (None
    each where the point has no running cycle): the barrier its labels were certified with,
    as stored (``barrier``, :class:`atlas.store.reader.StoredBarrier`), g as a float64 blob;
    the stored cycle (about ``CYCLE_DRAWN`` segments, rounded to 1e-4) to draw."""
    cycle = point_group(tree, "limit_cycle", point)  # only points with a running cycle
    if cycle is None or barrier is None:
        return {"barrier": None, "cycle": None}
    theta, theta_dot = cycle["theta"].values, cycle["theta_dot"].values
    n = theta.size
    drawn = np.unique(np.r_[0:n:max(1, (n - 1) // CYCLE_DRAWN), n - 1])  # both ends: one turn
    return {
        "barrier": {"theta0": barrier.theta0, "top": barrier.top,
                    "direction": barrier.direction, "n": int(barrier.g.size),
                    "g": _blob(np.asarray(barrier.g).astype("<f8"))},
        "cycle": {"theta": np.round(theta[drawn], 4).tolist(),
                  "theta_dot": np.round(theta_dot[drawn], 4).tolist(),
                  "period": float(cycle.attrs["period"])},
    }


def _tilt(point: dict[str, float], cap: float) -> dict:
    """What the page's trap needs for the point's torque: the stored cap (None where no well
    can trap, |τ| ≥ ω0²), θ* (:func:`atlas.physics.pendulum.tilt`, as the kernels' torque
    model) and 1 − cos θ* as the kernels compute it, and the lower saddle's energy above the
    rest state (the pictures follow a trapped orbit until it has nearly settled, E_k below
    1e-3 of it)."""
    alpha, omega0, torque = point["alpha"], point["omega0"], point.get("torque", 0.0)
    shift = tilt(omega0, torque)
    pendulum = Pendulum(alpha, omega0, torque)
    return {"torque": torque, "cap": cap if math.isfinite(cap) else None, "shift": shift,
            "vers": tilt_versine(shift),
            "saddle_energy": pendulum.saddle_energy if pendulum.has_rest_states else None}


def _text(value) -> str:
    return value if isinstance(value, str) else str(value)


def _name(ds: xr.Dataset) -> str:
    try:
        return _text(json.loads(ds.attrs["config"])["name"])
    except (KeyError, TypeError, ValueError):
        return _text(ds.attrs.get("title", "atlas"))


def payload(tree: xr.DataTree, path: Path) -> dict:
    """Everything the page shows, as JSON-ready data. A file of format 3, which does not store
    the certificate, is refused (InputFileError, one line)."""
    require_certificate(tree, path)
    ds = tree.to_dataset(inherit=False)
    dt, t_max = float(ds.attrs["dt"]), float(ds.attrs["t_max"])
    check_every = int(ds.attrs["check_every"])
    kinds = of_attrs(ds.attrs).status_kinds()
    points = []
    for params in parameter_points(ds):
        point = at_point(ds, params)
        alpha, omega0 = params["alpha"], params["omega0"]
        attractor = point["attractor"].values.astype("<i2")
        status = point["status"].values.astype("<i1")
        t_trap = point["t_trap"].values.astype(np.float64)
        n_check = np.round(t_trap / (dt * check_every))
        n_check = np.where(np.isfinite(n_check), n_check, _T_NAN).astype("<u4")
        d_cert = float(point["d_cert"]) if "d_cert" in point else math.nan
        certificate = stored_certificate(tree, params)
        distance = (point["boundary_distance"].values if "boundary_distance" in point
                    else np.full(attractor.shape, np.nan))
        labelled, wells = labelled_wells(attractor, status, kinds)
        running = np.isin(status, (RUNNING, RUNNING_NEAR_BOUNDARY))
        points.append({
            "alpha": alpha, "omega0": omega0, "margin": float(point["trap_margin"]),
            "d_cert": d_cert if math.isfinite(d_cert) else None,
            "png": map_png(attractor, status, wells, kinds),
            "band_labels": _band_labels(attractor, labelled, wells, distance,
                                        point["theta0"].values, point["theta_dot0"].values),
            "key": {"wells": wells.tolist(), "running": bool(running.any()),
                    "unlabelled": bool((~labelled & ~running).any())},
            "attractor": _blob(attractor), "status": _blob(status),
            "t_trap": _blob(n_check), "distance": _blob(pack_distance(distance)),
            "curves": _curves(tree, params, ds["theta0"].values, ds["theta_dot0"].values),
            **_critical(tree, params),
            **_tilt(params, certificate.trap_energy_cap),
            **_running(tree, params, certificate.barrier),
        })
    return {
        "name": _name(ds), "file": Path(path).name, "title": _text(ds.attrs.get("title", "")),
        "created": _text(ds.attrs.get("created", "")),
        "atlas_version": _text(ds.attrs.get("atlas_version", "")),
        "dt": dt, "t_max": t_max, "check_every": check_every,
        "method": file_method(ds.attrs, path),
        "theta0": _uniform(ds["theta0"].values, "theta0", path),
        "theta_dot0": _uniform(ds["theta_dot0"].values, "theta_dot0", path),
        "dist_steps": DIST_STEPS, "dist_offset": _DIST_OFFSET,
        "status_names": {str(k): v for k, v in STATUS_MEANINGS.items()},
        **page_style(),
        "points": points,
    }


def _marker(style: dict) -> dict:
    """A matplotlib marker of :mod:`atlas.views.style` as the page draws it: fill and edge
    colours, the diameter and the edge width in points (the page draws 1 pt as 1 CSS px)."""
    return {"fill": style["mfc"], "edge": style["mec"], "size": style["ms"],
            "width": style["mew"]}


def page_style() -> dict:
    """The page's whole look, from :mod:`atlas.views.style` (the script keeps no colour of its
    own): the well palette's tables (:func:`atlas.views.style.well_palette`), the running and
    "no label" colours, the t_trap and distance colour maps as 256-entry tables
    (:func:`atlas.views.style.colormap_table`, packed as one string of "rrggbb" each: 1.5 kB,
    not 2.5) with the distance map's d_cert colour, the separatrices, the critical-point
    markers and the orbit's start."""
    return {
        "palette": well_palette(), "running_color": RUNNING_COLOR_HEX,
        "no_label_color": NO_LABEL_COLOR, "near_boundary_color": NEAR_BOUNDARY_COLOR,
        "colormaps": {layer: "".join(c[1:] for c in colormap_table(name))
                      for layer, name in (("t_trap", T_TRAP_CMAP), ("distance", DISTANCE_CMAP))},
        "separatrix": {"color": SEPARATRIX_COLOR, "alpha": SEPARATRIX_ALPHA},
        "separatrix_faint": {"color": SEPARATRIX_FAINT["color"],
                             "alpha": SEPARATRIX_FAINT["alpha"]},
        "markers": {"saddle": _marker(SADDLE_MARKER), "attractor": _marker(ATTRACTOR_MARKER),
                    "start": _marker(ORBIT_START_MARKER)},
    }


def safe_json(data) -> str:
    """JSON that cannot end its ``<script>`` element or start markup: ``<``, ``>``, ``&``
    and U+2028/U+2029 as \\uXXXX escapes (valid JSON and JavaScript either way)."""
    text = json.dumps(data, ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    for char, escape in (("<", "\\u003c"), (">", "\\u003e"), ("&", "\\u0026")):
        text = text.replace(char, escape)
    return text


def build_page(tree: xr.DataTree, path: Path) -> str:
    """The whole HTML page for the atlas ``tree`` read from ``path``."""
    assets = Path(__file__).with_name("view_assets")
    script = (assets / "view.js").read_text(encoding="utf-8")
    # The page may run this one script and nothing else (no other inline script, no network).
    digest = base64.b64encode(hashlib.sha256(script.encode("utf-8")).digest()).decode()
    return (_TEMPLATE.replace("/*STYLE*/", (assets / "view.css").read_text(encoding="utf-8"))
            .replace("/*HASH*/", digest)
            .replace("/*SCRIPT*/", script)
            .replace("/*DATA*/", safe_json(payload(tree, path))))  # last: never rescanned


def write_view(path: str | Path, output: str | Path | None = None) -> Path:
    """Write the page of the atlas file ``path`` to ``output`` (default: next to it, .html);
    returns the page's path. An atlas of another model than the pendulum gets the static
    page of :mod:`atlas.views.page_described`. Bad files, and files of format 3 (which do not
    store the certificate the page integrates with), raise :class:`InputFileError`."""
    path = Path(path)
    output = Path(output) if output is not None else path.with_suffix(".html")
    if output.is_dir():
        raise AtlasError(f"{output}: the output path is a directory")
    if not output.parent.is_dir():
        raise AtlasError(f"{output}: the output folder {output.parent} is not a directory")
    tree = open_atlas(path)
    try:
        model = of_attrs(tree.attrs)
        for name in model.label_variables:
            if name not in tree.to_dataset(inherit=False):
                raise InputFileError(f"{path}: no {name} variable in this atlas")
        if model.name == DEFAULT:
            page = build_page(tree, path)
        else:  # the page's orbits are the pendulum's: another model's page shows the map
            from atlas.views.page_described import described_page

            page = described_page(tree, path, model)
    finally:
        tree.close()
    tmp = output.with_name(f".{output.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(page, encoding="utf-8")
        os.replace(tmp, output)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise AtlasError(f"{output}: cannot write the page ({exc.strerror or exc})") from None
    return output


_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; img-src data:; \
style-src 'unsafe-inline'; script-src 'sha256-/*HASH*/'">
<title>atlas view</title>
<style>/*STYLE*/</style>
</head>
<body>
<header>
  <h1>Basins of the damped pendulum: <span id="name"></span></h1>
  <p id="subtitle"></p>
</header>
<div id="controls" hidden>
  <label for="point">parameter point</label>
  <input id="point" type="range" min="0" max="0" step="1" value="0">
  <span id="point-label"></span>
</div>
<div id="toolbar">
  <fieldset id="layers"><legend>show</legend>
    <label><input type="radio" name="layer" value="basins" checked> basins</label>
    <label><input type="radio" name="layer" value="t_trap"> time to trap</label>
    <label><input type="radio" name="layer" value="distance"> distance to a boundary</label>
  </fieldset>
  <form id="goto" autocomplete="off">
    <label>θ0 [rad] <input id="in-theta0" size="9" placeholder="e.g. 0 or -pi/2"></label>
    <label>θ̇0 [rad/s] <input id="in-theta-dot0" size="9" placeholder="e.g. -3.1"></label>
    <button type="submit">run orbit</button>
    <span id="goto-error" role="alert"></span>
  </form>
  <button id="clear" type="button" disabled>clear orbits</button>
</div>
<main>
  <div id="figure">
    <div id="stage">
      <canvas id="map"></canvas>
      <canvas id="overlay" title="click to integrate the orbit from here"></canvas>
    </div>
    <p id="hover" aria-live="polite">Move the pointer over the map to read the stored label;
    click to follow an orbit.</p>
    <div id="key"></div>
  </div>
  <aside>
    <div id="readout" data-ready="0">
      <p class="hint">Click anywhere on the map, or type a point above: the orbit from that
      initial condition is integrated here in the browser (RK4 with the file's α, ω0, τ, dt
      and method, the energy trap and the running certificate of atlas) and drawn in black;
      earlier orbits are kept until you clear them.</p>
    </div>
    <canvas id="pendulum" width="220" height="220"></canvas>
    <p id="clock"></p>
  </aside>
</main>
<footer>
  <p><span id="legend"></span> <span id="provenance"></span></p>
</footer>
<script type="application/json" id="atlas-data">/*DATA*/</script>
<script>/*SCRIPT*/</script>
</body>
</html>
"""
