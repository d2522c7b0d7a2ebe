"""``atlas plot`` of a stability study: its figures, read from the file and drawn (no
computing).

1-D study: the basin stability of the rest states (all wells together, and well 0 alone) and
of the running cycle against the swept parameter, with the Gaussian stability if stored, and
every bifurcation inside the range drawn as a labelled vertical line (NAME_stability.png);
the minimal fatal shock against the parameter, with the same lines (NAME_fatal_shock.png).
2-D study: the rest states' basin stability over the two parameters, with the bifurcation
curves drawn on it (NAME_stability_map.png). Points whose numbers are NaN (the saddle-node,
failures) are marked where they lie, never at a value: a grey band over the whole height on
the curves, a white cell on the map, each named in the legend.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.store.study import BIFURCATIONS
from atlas.views.style import CURVE_SIZE, MAP_SIZE, PNG_OPTIONS, STYLE, basin_colours

__all__ = ["plot_study"]

_LABELS = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
           "torque": "torque τ [rad/s²]"}
#: The bifurcation variables' labels (which parameter each is a value of:
#: :data:`atlas.store.study.BIFURCATIONS`), and each bifurcation's colour and dashes.
_LABELS_OF = {"homoclinic_torque": "homoclinic τ_c", "homoclinic_damping": "homoclinic α_c",
              "homoclinic_omega0": "homoclinic ω0_c",
              "saddle_node_torque": "saddle-node τ = ω0²",
              "saddle_node_omega0": "saddle-node ω0 = √|τ|",
              "focus_node_damping": "focus → node α", "focus_node_torque": "focus → node τ",
              "focus_node_omega0": "focus → node ω0"}
_DRAWN = {"homoclinic": ("#b2182b", "--"), "saddle-node": ("#2166ac", ":"),
          "focus-node": ("#5e3c99", "-.")}
#: The bifurcations where the basin stability jumps (a curve is broken there).
_JUMPS = ("homoclinic", "saddle-node")


def _figure(out: Path, size, draw, dpi) -> Path:
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from atlas.store.outputs import figure_metadata

    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=size, dpi=dpi or STYLE["savefig.dpi"])
        FigureCanvasAgg(fig)
        draw(fig.add_subplot())
        fig.tight_layout()
        options = {"pil_kwargs": PNG_OPTIONS} if out.suffix == ".png" else {}
        fig.savefig(out, metadata=figure_metadata(out.suffix, "atlas plot"), **options)
    return out


def _bifurcations_at(ds: xr.Dataset, axis: str) -> list[tuple[str, float]]:
    """(variable, value) of every bifurcation of ``axis`` inside its plotted range, by
    value."""
    lo, hi = float(ds[axis][0]), float(ds[axis][-1])
    found = [(name, float(value)) for name, (along, _) in BIFURCATIONS.items()
             if along == axis and name in ds
             for value in np.unique(np.atleast_1d(ds[name].values))
             if np.isfinite(value) and lo <= value <= hi]
    return sorted(found, key=lambda item: item[1])


#: Bifurcation lines closer than this on the page [pt] are one line to the eye (the
#: focus–node torque √(ω0⁴ − α⁴) lies 3·10⁻⁶ below the saddle-node ω0² at α = 0.05): they
#: are drawn as one line, whose one label names each.
_COINCIDE_PT = 3.0


def _per_point(ax, lo: float, hi: float) -> float:
    """Data units of the x range from lo to hi (either way round) per typographic point
    across ``ax``."""
    return abs(hi - lo) / (ax.bbox.width * 72.0 / ax.figure.dpi)


def _coinciding(found: list[tuple[str, float]], apart: float) -> list[list[tuple[str, float]]]:
    """``found`` (by value) in groups whose neighbours lie less than ``apart`` from each other,
    in data units: the lines that one line stands for."""
    groups: list[list[tuple[str, float]]] = []
    for name, value in found:
        if groups and value - groups[-1][-1][1] < apart:
            groups[-1].append((name, value))
        else:
            groups.append([(name, value)])
    return groups


def _bifurcation_lines(ax, ds: xr.Dataset, axis: str) -> int:
    """Every bifurcation of ``axis`` inside the plotted range: a labelled vertical line,
    lines that coincide on the page (_COINCIDE_PT) drawn as one, in the look of one where the
    basin stability jumps, its label naming each; the labels above the axes, each on the
    lowest row where it overlaps no other. Returns the rows of labels."""
    lo, hi = float(ds[axis][0]), float(ds[axis][-1])
    per_pt = _per_point(ax, lo, hi)
    per_char = 0.6 * 8.0 * per_pt  # a label's character at 8 pt: about 0.6 em wide
    taken: list[list[tuple[float, float]]] = []  # per row, the extents of its labels
    for group in _coinciding(_bifurcations_at(ds, axis), _COINCIDE_PT * per_pt):
        lead, value = next((m for m in group if BIFURCATIONS[m[0]][1] in _JUMPS), group[0])
        colour, style = _DRAWN[BIFURCATIONS[lead][1]]
        ax.axvline(value, color=colour, ls=style, lw=1.0)
        text = "; ".join(f"{_LABELS_OF[name]} = {v:.10g}" for name, v in group)
        right = value > lo + 0.7 * (hi - lo)  # above the axes, over nothing drawn
        width = (len(text) + 1) * per_char
        extent = (value - width, value) if right else (value, value + width)
        row = next((i for i, row in enumerate(taken)
                    if all(extent[1] < a or b < extent[0] for a, b in row)), len(taken))
        if row == len(taken):
            taken.append([])
        taken[row].append(extent)
        ax.annotate(text, (value, 1.0), xycoords=("data", "axes fraction"),
                    xytext=(0, 2 + 10 * row), textcoords="offset points", va="bottom",
                    fontsize=8, color=colour, ha="right" if right else "left",
                    annotation_clip=False)
    return len(taken)


def _x_range(ds: xr.Dataset, axis: str) -> tuple[float, float]:
    """The x limits of a 1-D figure: the parameter's range, 1 % wider on a side where a
    bifurcation lies at its end (its line would hide under the frame: the saddle-node τ = ω0²
    at the end of a torque range)."""
    lo, hi = float(ds[axis][0]), float(ds[axis][-1])
    pad = 0.01 * (hi - lo)
    at = [v for _, v in _bifurcations_at(ds, axis)]
    return (lo - pad if any(v - lo < pad for v in at) else lo,
            hi + pad if any(hi - v < pad for v in at) else hi)


#: A band marking a point without an exact value is at least this wide on the page [pt]
#: (at 1,001 torques half the spacing each side is a fraction of a point).
_NAN_BAND_PT = 4.0


def _nan_points(ax, ds: xr.Dataset, axis: str) -> None:
    """The points without an exact value (``point_status`` ≠ 0: the saddle-node, a failure)
    as grey bands over the whole height, halfway to each neighbour and at least _NAN_BAND_PT
    wide, named in the legend by what they are: a band marks where, never a value (a marker
    at y = 0 read as a basin stability of 0)."""
    from atlas.store.study import POINT_STATUS_MEANINGS

    status = np.atleast_1d(ds["point_status"].values)
    if not status.any():
        return
    x = np.atleast_1d(ds[axis].values).astype(float)
    mid = 0.5 * (x[1:] + x[:-1])
    left, right = np.r_[1.5 * x[0] - 0.5 * x[1], mid], np.r_[mid, 1.5 * x[-1] - 0.5 * x[-2]]
    half = 0.5 * _NAN_BAND_PT * _per_point(ax, x[0], x[-1])
    what = " / ".join(POINT_STATUS_MEANINGS[int(v)].replace("_", "-")
                      for v in np.unique(status[status != 0]))
    for i in np.flatnonzero(status):
        ax.axvspan(min(left[i], x[i] - half), max(right[i], x[i] + half), color="0.82", lw=0,
                   zorder=0, label=f"no exact value ({what})")


def _legend(ax, **options) -> None:
    """The legend of ``ax``, each label once (a band per failed point shares one)."""
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    ax.legend(unique.values(), unique.keys(), **options)


_SYMBOLS = {"alpha": "α", "omega0": "ω0", "torque": "τ"}


def _curve(ds: xr.Dataset, axis: str, values, jumps: bool = True
           ) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of a curve against ``axis``, broken (a NaN) between the two points on either
    side of each bifurcation where the basin stability jumps (``jumps``): a jump there is
    not drawn as a slope. (The fatal shocks do not jump: ``jumps`` false.)"""
    x, y = np.asarray(ds[axis].values, float), np.asarray(values, float)
    cuts = [v for name, v in _bifurcations_at(ds, axis)
            if jumps and BIFURCATIONS[name][1] in _JUMPS]
    at = sorted({int(i) for v in cuts if x[0] < v < x[-1]
                 for i in [np.searchsorted(x, v)] if x[i] != v})
    return np.insert(x, at, np.nan), np.insert(y, at, np.nan)


def _parameter_title(ds: xr.Dataset, swept) -> str:
    fixed = [f"{_SYMBOLS[n]} = {float(ds[n]):g}" for n in ("alpha", "omega0", "torque")
             if n not in swept]
    (a, b), (lo, hi) = ds.attrs["window_theta"], ds.attrs["window_theta_dot"]
    return (f"{', '.join(fixed)}; window θ ∈ [{a:.3g}, {b:.3g}], θ̇ ∈ [{lo:g}, {hi:g}]")


def _stability_curves(ds: xr.Dataset, axis: str):
    colours = basin_colours([0], running=True)

    marker = "." if ds.sizes[axis] <= 60 else None

    def draw(ax):
        ax.plot(*_curve(ds, axis, ds["basin_stability"].sum("k", skipna=False).values),
                color="#1b7837", lw=1.6, marker=marker, label="rest states (all wells)")
        if 0 in ds["k"].values:
            ax.plot(*_curve(ds, axis, ds["basin_stability"].sel(k=0).values),
                    color=colours[0], lw=1.0, ls="--", marker=marker,
                    label="rest state k = 0")
        ax.plot(*_curve(ds, axis, ds["running_stability"].values), color="#4d4d4d", lw=1.6,
                marker=marker, label="running cycle")
        if "gaussian_stability" in ds:
            ax.plot(*_curve(ds, axis, ds["gaussian_stability"].values), color="#e08214",
                    lw=1.2, marker=marker,
                    label=f"rest state under a Gaussian kick σθ = "
                    f"{ds.attrs['sigma_theta']:g}, σθ̇ = {ds.attrs['sigma_theta_dot']:g}")
        rows = _bifurcation_lines(ax, ds, axis)
        _nan_points(ax, ds, axis)
        ax.set_xlim(*_x_range(ds, axis))
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel(_LABELS[axis])
        ax.set_ylabel("basin stability (exact area fraction"
                      + ("; Gaussian: probability)" if "gaussian_stability" in ds else ")"))
        ax.set_title(f"basin stability: {_parameter_title(ds, (axis,))}", fontsize=9,
                     pad=4 + 10 * max(rows, 1))
        _legend(ax, loc="best")

    return draw


def _shock_curve(ds: xr.Dataset, axis: str):
    def draw(ax):
        x = ds[axis].values
        ax.plot(*_curve(ds, axis, ds["minimal_fatal_shock"].isel(k=0).values, jumps=False),
                color="#1b7837", lw=1.6, marker="." if x.size <= 60 else None,
                label="of the rest states")
        if "running_fatal_shock" in ds and np.isfinite(ds["running_fatal_shock"].values).any():
            ax.plot(*_curve(ds, axis, ds["running_fatal_shock"].values, jumps=False),
                    color="#525252",
                    lw=1.6, ls="--", marker="." if x.size <= 60 else None,
                    label="of the running cycle")
        rows = _bifurcation_lines(ax, ds, axis)
        _nan_points(ax, ds, axis)
        ax.set_xlim(*_x_range(ds, axis))
        ax.set_ylim(bottom=0.0)
        ax.set_xlabel(_LABELS[axis])
        ax.set_ylabel("minimal fatal shock √(Δθ² + Δθ̇²)  (θ in rad, θ̇ in rad/s)")
        ax.set_title(f"minimal fatal shock: {_parameter_title(ds, (axis,))}", fontsize=9,
                     pad=4 + 10 * max(rows, 1))
        _legend(ax, loc="best", title="minimal fatal shock", fontsize=8, title_fontsize=8)

    return draw


def _map_curves(ds: xr.Dataset, x: str, y: str) -> dict[str, tuple]:
    """{variable: (x values, y values) of its curve} on an x × y map: each
    bifurcation once, as the variable that is a value of one axis over the other (or a
    constant) with the most values inside its axis's range (the focus–node read along τ over
    α is smooth where the one along α over τ has one sample in range), none for a bifurcation
    outside the map."""
    best = {}
    for name, (value_axis, kind) in BIFURCATIONS.items():
        if name not in ds or value_axis not in (x, y):
            continue
        other = y if value_axis == x else x
        values = ds[name]
        if values.dims == (other,):
            along, at = ds[other].values, values.values
        elif values.dims == ():
            along, at = ds[other].values[[0, -1]], np.full(2, float(values))
        else:
            continue
        lo, hi = float(ds[value_axis][0]), float(ds[value_axis][-1])
        inside = int(np.count_nonzero(np.isfinite(at) & (at >= lo) & (at <= hi)))
        if inside and inside > best.get(kind, (0, None, None))[0]:
            best[kind] = (inside, name, (at, along) if value_axis == x else (along, at))
    return {name: pair for _, name, pair in best.values()}


def _stability_map(ds: xr.Dataset, x: str, y: str):
    def draw(ax):
        total = ds["basin_stability"].sum("k", skipna=False).transpose(y, x)
        mesh = ax.pcolormesh(ds[x].values, ds[y].values, total.values, shading="nearest",
                             cmap="viridis", vmin=0.0, vmax=1.0)
        ax.figure.colorbar(mesh, ax=ax, label="basin stability of the rest states")
        for name, pair in _map_curves(ds, x, y).items():
            colour, style = _DRAWN[BIFURCATIONS[name][1]]
            ax.plot(*pair, color="white", lw=2.4)
            ax.plot(*pair, color=colour, ls=style, lw=1.3, label=_LABELS_OF[name])
        ax.set_xlim(ds[x].values[0], ds[x].values[-1])
        ax.set_ylim(ds[y].values[0], ds[y].values[-1])
        ax.set_xlabel(_LABELS[x])
        ax.set_ylabel(_LABELS[y])
        ax.set_title(f"basin stability of the rest states: {_parameter_title(ds, (x, y))}",
                     fontsize=9)
        if np.isnan(total.values).any():
            from matplotlib.patches import Patch

            ax.add_artist(ax.legend(handles=[Patch(fc="white", ec="0.3", label="no exact "
                                                   "value (saddle-node / failed)")],
                                    loc="lower right", frameon=True))
        ax.legend(loc="best", frameon=True)

    return draw


def plot_study(path: str | Path, outdir=None, fmt: str = "png", dpi=None) -> list[Path]:
    """The figures of the study file at ``path`` (module docstring), written into ``outdir``
    (default: next to the file) as NAME_<figure>.<fmt>; a parameter listed with one value is a
    fixed one. A study of one point, or over three parameters, has no figure:
    InputFileError (one line)."""
    from atlas.store.study import open_study, swept_dims

    path = Path(path)
    ds = open_study(path)
    from atlas.store.driven_study import is_driven_study

    if is_driven_study(ds):  # a driven pendulum's: its orbit diagram and fractions
        from atlas.views.driven_study import plot_driven_study

        return plot_driven_study(ds, path, outdir, fmt, dpi)
    # a parameter given as a list of one value is a fixed one
    ds = ds.isel({d: 0 for d in swept_dims(ds) if ds.sizes[d] == 1})
    swept = swept_dims(ds)
    if len(swept) not in (1, 2):
        from atlas.errors import InputFileError

        what = "one parameter point" if not swept else f"{len(swept)} swept parameters"
        raise InputFileError(f"{path}: a study of {what} has no figure (`atlas plot` draws "
                             "1-D curves and 2-D maps); `atlas info` prints its numbers")
    from atlas.store.outputs import check_output

    folder = Path(outdir) if outdir is not None else path.parent
    stem = path.name.removesuffix(path.suffix)
    if len(swept) == 1:
        figures = [(f"{stem}_stability", CURVE_SIZE, _stability_curves(ds, swept[0])),
                   (f"{stem}_fatal_shock", CURVE_SIZE, _shock_curve(ds, swept[0]))]
    else:
        y, x = swept  # alpha before torque: torque across, alpha up
        figures = [(f"{stem}_stability_map", MAP_SIZE, _stability_map(ds, x, y))]
    paths = [folder / f"{name}.{fmt}" for name, _, _ in figures]
    for out in paths:  # before any figure is written: never over the study or another file
        check_output(out, "figure", inputs=(path,), option="--outdir",
                     command="atlas plot")
    folder.mkdir(parents=True, exist_ok=True)
    return [_figure(out, size, draw, dpi) for out, (_, size, draw) in zip(paths, figures)]
