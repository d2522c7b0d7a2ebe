"""Figures against a swept parameter, read from the file and drawn (no computing).

* :func:`fraction_curves`: the exact basin fraction of each k (lines), the grid counts
  (markers, a shape per curve) and, in a panel below, their *measured* error (grid count −
  exact fraction);
* :func:`basin_stability`: the share of the window that settles at a rest state and the
  running basin's share against the torque, drawn the same way.

What the curves mean, drawn so that they say it:

* the grid count's error is drawn as measured: grid count − exact fraction, in the panel
  below. The grid error bound (``basin_fraction_grid_error_bound``, a proven worst case,
  first order in the cell size, some 20 times the measured error) is drawn as error bars
  only at points without an exact value, where it is all that is known, and there only
  where informative (below INFORMATIVE_BOUND), clipped to [0, 1] (a fraction never leaves
  it); the legend says what the bars are, or that the bound is not drawn, and its size;
* where the window is symmetric about (0, 0) and there is no torque, the point reflection
  (θ, θ̇) → (−θ, −θ̇) maps the basin of k onto that of −k, so their fractions are equal:
  k and −k are merged into one curve "k = ±j" (their sum), as the legend says;
* the ``max_curves`` largest basins get a curve each; the others are thin grey lines, one
  each (never one sum that outgrows the curves it stands for);
* the bifurcations are marked and named on the axis: α = ω0 (critical damping), τ = ω0²
  (the saddle-node beyond which no rest state exists) and, where known, the homoclinic
  torque τ_c above which the running cycle exists (a study file's ``homoclinic_torque``,
  or the value the command layer passes in: views compute no dynamics).

Reader (``_*_scene``) and drawer (``_draw_*``) apart, as in :mod:`atlas.views.maps`.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import parameter_names, point_label, point_nodes
from atlas.views.style import CURVE_SIZE, axes, basin_colours

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["fraction_curves", "basin_stability", "PARAMETER_AXES", "CURVE_FIGURES",
           "INFORMATIVE_BOUND", "bifurcation_marks"]

#: Axis labels of the parameters.
PARAMETER_AXES = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
                  "torque": "torque τ [rad/s²]"}
#: At a point without an exact value the grid error bound is drawn (as an error bar) only
#: where it is below this: a bar longer than a tenth of the [0, 1] axis says nothing a
#: reader can use.
INFORMATIVE_BOUND = 0.1
#: The colour of the basins beyond the ``max_curves`` largest (thin lines, one each).
_OTHERS_COLOR = "0.65"
#: The grid counts' marker of each curve, in turn: the shape tells two curves apart where
#: their colours are near (wells of one parity; a projector; a colour-blind reader).
_SHAPES = ("o", "s", "^", "D", "v", "P", "X", "<", ">", "h")


def _held(full: xr.Dataset, ds: xr.Dataset, dim: str) -> str:
    """The title's second line: the swept parameters other than ``dim`` at the values held."""
    held = {n: float(ds[n]) for n in parameter_names(full) if n != dim and n in full.dims}
    return f"\nat {point_label(held)}" if held else ""


def _symmetric(ds: xr.Dataset) -> bool:
    """Whether the basin of −k is the point reflection of that of k in ``ds``'s window: no
    torque at any point drawn, and a window symmetric about (0, 0) (to 1e-12 relative)."""
    def centred(c: np.ndarray) -> bool:
        return bool(np.isclose(c[0], -c[-1], rtol=1e-12, atol=1e-12 * np.abs(c).max()))

    return (not np.any(ds["torque"].values) and centred(ds["theta0"].values)
            and centred(ds["theta_dot0"].values))


def _cycle_onset(tree: xr.DataTree, ds: xr.Dataset, dim: str) -> tuple[float, float] | None:
    """Where an atlas file's torque sweep first stores a running limit cycle (its
    ``/limit_cycle`` group has a node per point that has one): (the last torque without,
    the first with), which bracket the homoclinic torque; None if the sweep does not cross
    it or is not over τ."""
    if dim != "torque" or "limit_cycle" not in tree.children:
        return None
    held = {n: float(ds[n]) for n in parameter_names(ds) if n != dim and ds[n].ndim == 0}
    with_cycle = {float(node.attrs["torque"]) for node in point_nodes(tree, "limit_cycle")
                  if "torque" in node.attrs and all(
                      float(node.attrs.get(n, np.nan)) == v for n, v in held.items())}
    x = np.sort(np.abs(ds[dim].values))
    has = np.array([v in with_cycle or -v in with_cycle for v in x])
    if not has.any() or has.all() or not np.all(has[np.argmax(has):]):
        return None
    first = int(np.argmax(has))
    return float(x[first - 1]), float(x[first])


def bifurcation_marks(ds: xr.Dataset, dim: str, homoclinic_torque: float | None = None
                      ) -> list[tuple[float, str]]:
    """The bifurcations along ``dim`` that need no dynamics to place: α = ω0 (critical
    damping: the rest states turn from foci into nodes) when α is swept, τ = ω0² (the
    saddle-node: no rest state beyond) when τ is swept, and the homoclinic torque τ_c (the
    running cycle is born; read from the file as ``homoclinic_torque``, else
    ``homoclinic_torque`` as given) — those inside the swept range, as (value, label).
    (An atlas file without τ_c brackets it instead: :func:`_cycle_onset`.)"""
    x = ds[dim].values
    marks = []
    if dim == "alpha" and ds["omega0"].ndim == 0:
        marks.append((float(ds["omega0"]), "α = ω0: critical damping"))
    if dim == "torque" and ds["omega0"].ndim == 0:
        marks.append((float(ds["omega0"]) ** 2, "τ = ω0²: saddle-node, no rest state beyond"))
        if "homoclinic_torque" in ds and ds["homoclinic_torque"].ndim == 0:
            homoclinic_torque = float(ds["homoclinic_torque"])
        if homoclinic_torque is not None:
            marks.append((homoclinic_torque, f"τ_c = {homoclinic_torque:.4g}: homoclinic, "
                          "running cycle born"))
    return [(v, text) for v, text in marks if x.min() <= v <= x.max()]


def _fraction_scene(tree: xr.DataTree, dim: str = "alpha", max_curves: int = 7,
                    homoclinic_torque: float | None = None) -> dict:
    """What :func:`fraction_curves` draws: the swept values; per curve (a well k, or ±k
    merged) the exact fractions, the grid counts, the grid error bound, its label and
    colour; the thin curves of the smaller basins; the bifurcation marks; the labels."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in full["basin_fraction_exact"].dims if d not in (dim, "k")})
    ks = ds["k"].values.astype(int)
    exact = ds["basin_fraction_exact"].transpose(dim, "k").values
    grid = ds["basin_fraction"].transpose(dim, "k").values
    bound = ds["basin_fraction_grid_error_bound"].transpose(dim, "k").values
    merged = _symmetric(ds) and set(ks) == set(-ks)
    groups = sorted({abs(k) for k in ks}) if merged else list(ks)

    def sum_of(values, g):
        return values[:, np.abs(ks) == g].sum(axis=1) if merged else values[:, ks == g][:, 0]

    curves = [(g, sum_of(exact, g), sum_of(grid, g), sum_of(bound, g)) for g in groups]
    size = [np.nanmax(np.where(np.isfinite(e), e, gr)) for _, e, gr, _ in curves]
    shown = set(np.argsort(size)[::-1][:max_curves])
    colours = basin_colours([g for i, (g, *_) in enumerate(curves) if i in shown], lines=True)

    def label(g):
        return f"k = ±{g}" if merged and g else f"k = {g:+d}".replace("+0", "0").replace(
            "-", "−")

    return {"x": ds[dim].values,
            "curves": [(e, gr, b, label(g), colours[g])
                       for i, (g, e, gr, b) in enumerate(curves) if i in shown],
            "others": [np.where(np.isfinite(e), e, gr)
                       for i, (g, e, gr, b) in enumerate(curves) if i not in shown],
            "marks": bifurcation_marks(ds, dim, homoclinic_torque),
            "onset": None if homoclinic_torque is not None or "homoclinic_torque" in ds
            else _cycle_onset(tree, ds, dim),
            "xlabel": PARAMETER_AXES[dim],
            "title": "Basin fractions of the window"
                     + (" (±k merged: the window is symmetric about (0, 0),\nso k and −k "
                        "have equal basins; each curve is their sum)" if merged else "")
                     + _held(full, ds, dim)}


def _broken(x, y, marks, onset=None):
    """(x, y) with a NaN between consecutive points that a bifurcation where the basins jump
    separates (the torque marks: the homoclinic torque, the saddle-node; or the ``onset``
    bracket of the homoclinic torque), so that a line never joins the two sides of a jump
    with a slope the exact values do not have. (Critical damping α = ω0 changes the rest
    state's kind, not the basins: no break there.)"""
    x, y = np.asarray(x, float), np.asarray(y, float)
    cuts = [value for value, text in marks if text.startswith("τ")]
    if onset is not None:
        cuts.append(0.5 * (onset[0] + onset[1]))
    gaps = [i for i in range(x.size - 1)
            if any(min(x[i], x[i + 1]) < c < max(x[i], x[i + 1]) for c in cuts)]
    if not gaps:
        return x, y
    at = np.array(gaps) + 1
    return np.insert(x, at, np.nan), np.insert(y, at, np.nan)


def _error_bars(ax, x, exact, grid, bound, color):
    """The grid error bound as error bars about the grid counts at the points without an
    exact value (NaN ``exact``: there the bound is all that is known of the count's error;
    where the exact area is drawn, the measured error is in the panel below and a worst-case
    bar, some 20 times longer, would say nothing), where it is below INFORMATIVE_BOUND,
    clipped to [0, 1]; returns whether any bar was drawn."""
    shown = (~np.isfinite(exact) & np.isfinite(bound) & (bound < INFORMATIVE_BOUND)
             & np.isfinite(grid))
    if not shown.any():
        return False
    g, b = grid[shown], bound[shown]
    lower, upper = np.clip(g - b, 0.0, 1.0), np.clip(g + b, 0.0, 1.0)
    ax.errorbar(x[shown], g, yerr=[g - lower, upper - g], fmt="none", capsize=2, lw=0.8,
                color=color)
    return True


def _bound_note(triples) -> str | None:
    """The legend's line on the grid error bound where it is not drawn, at the points with
    an exact value (``triples``: (exact, grid count, bound) per curve): its largest value
    beside the largest measured error |grid − exact| (the panel below); None where every
    point lacks an exact value or a bound."""
    bound = [b[np.isfinite(e) & np.isfinite(b)] for e, _, b in triples]
    measured = [np.abs(g - e)[np.isfinite(e) & np.isfinite(g)] for e, g, _ in triples]
    bound, measured = np.concatenate(bound), np.concatenate(measured)
    if not bound.size or not measured.size:
        return None
    return (f"no bar on an exact point: its measured\nerror |grid − exact| ≤ "
            f"{measured.max():.2g} is drawn\nbelow; the proven grid error bound\n"
            f"(≤ {bound.max():.2g}, worst case) is not")


def _residual_axes(ax, errors: list[np.ndarray]):
    """A panel under ``ax`` sharing its x axis, for the measured errors (grid count − exact
    fraction, one array per curve), and the power of ten p its axis counts in (its label
    says "[10^p]")."""
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    below = make_axes_locatable(ax).append_axes("bottom", size="32%", pad=0.12, sharex=ax)
    ax.tick_params(labelbottom=False)
    below.axhline(0.0, color="0.5", lw=0.6)
    finite = np.abs(np.concatenate([e[np.isfinite(e)] for e in errors] + [np.zeros(1)]))
    power = int(np.floor(np.log10(finite.max()))) if finite.max() > 0 else 0
    power = power if power < -1 else 0
    below.set_ylabel("measured error\ngrid − exact" + (
        f" [10{str(power).translate(_SUPERSCRIPT)}]" if power else ""))
    return below, 10.0 ** power


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _draw_marks(axs, marks, onset=None) -> None:
    """Vertical dotted lines at the bifurcations, each named by text along it (top panel);
    ``onset``: the torques that bracket the homoclinic torque, shaded and named."""
    if onset is not None:
        for a in axs:
            a.axvspan(*onset, color="0.88", lw=0, zorder=0)
        axs[0].annotate(f"τ_c in ({onset[0]:g}, {onset[1]:g}):\nrunning cycle born",
                        xy=(onset[1], 0.98), xycoords=("data", "axes fraction"),
                        xytext=(3, 0), textcoords="offset points", rotation=90, va="top",
                        ha="left", fontsize=7, color="0.25")
    for value, text in marks:
        for a in axs:
            a.axvline(value, color="0.25", ls=":", lw=1.0, zorder=1)
        axs[0].annotate(text, xy=(value, 0.98), xycoords=("data", "axes fraction"),
                        xytext=(-2, 0), textcoords="offset points", rotation=90, va="top",
                        ha="right", fontsize=7, color="0.25")


def _finish(ax, below, x, xlabel, title, bars: bool, generic: bool = True,
            note: str | None = None, shapes: dict[str, str] | None = None) -> None:
    """Scales, labels, title and legend of a curve figure (``bars``: whether error bars
    were drawn, which the legend then explains; ``generic``: add what a line and a marker
    mean; ``note``: a last legend line without a symbol, :func:`_bound_note`; ``shapes``:
    label → the marker its legend entry shows with its line)."""
    from matplotlib.lines import Line2D

    ax.set_xscale("log" if x.min() > 0 and x.max() / x.min() > 20 else "linear")
    ax.set_ylim(-0.02, 1.02)
    below.set_xlabel(xlabel)
    ax.set_title(title, fontsize=10)
    handles, labels = ax.get_legend_handles_labels()
    shapes = shapes or {}
    handles = [Line2D([], [], color=h.get_color(), marker=shapes[name], ms=4, label=name)
               if name in shapes else h for h, name in zip(handles, labels)]
    if generic:
        handles += [Line2D([], [], color="0.3", label="exact area (line)"),
                    Line2D([], [], color="0.3", marker="o", ls="none", ms=4,
                           label="grid count (marker)")]
    if bars:
        handles.append(Line2D([], [], color="0.3", marker="|", ls="none", ms=8,
                              label="grid error bound where no exact value\n"
                                    f"(proven worst case; where < {INFORMATIVE_BOUND:g}; "
                                    "clipped to [0, 1])"))
    if note:
        handles.append(Line2D([], [], ls="none", label=note))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0)


def _draw_fractions(ax, x, curves, others, marks, xlabel: str, title: str, onset=None):
    """Draw :func:`_fraction_scene` (as :func:`fraction_curves`)."""
    below, unit = _residual_axes(ax, [g - e for e, g, *_ in curves])
    bars = False
    for values in others:
        ax.plot(*_broken(x, values, marks, onset), "-", color=_OTHERS_COLOR, lw=0.6, zorder=1)
    if others:
        ax.plot([], [], "-", color=_OTHERS_COLOR, lw=0.6,
                label=f"{len(others)} smaller basins\n(one thin line each)")
    shapes = {}
    for (e, g, b, label, color), shape in zip(curves, itertools.cycle(_SHAPES)):
        ax.plot(*_broken(x, e, marks, onset), "-", color=color, label=label, zorder=3)
        ax.plot(x, g, shape, ms=3.5, color=color, zorder=4)
        bars |= _error_bars(ax, x, e, g, b, color)
        below.plot(x, (g - e) / unit, "-", marker=shape, ms=3, lw=0.6, color=color)
        shapes[label] = shape
    _draw_marks((ax, below), marks, onset)
    ax.set_ylabel("basin fraction of the window")
    _finish(ax, below, x, xlabel, title, bars, note=_bound_note([c[:3] for c in curves]),
            shapes=shapes)
    top = max([np.nanmax(np.r_[e, g, 0.0]) for e, g, *_ in curves] + [0.0])
    ax.set_ylim(-0.02 * max(top, 0.1), min(1.02, 1.1 * max(top, 0.1)))
    return ax


def fraction_curves(tree: xr.DataTree, ax=None, dim: str = "alpha", max_curves: int = 7,
                    homoclinic_torque: float | None = None):
    """Exact basin fraction of each k against the swept parameter ``dim`` (lines), the grid
    counts (dots) and, in a panel below, their measured error (grid count − exact fraction);
    error bars only at points without an exact value (the grid error bound, where below
    INFORMATIVE_BOUND, clipped to [0, 1]); any other swept parameter is held at its first
    value (named in the title).

    The ``max_curves`` largest basins get a curve each (k and −k merged where the window is
    symmetric, as the title says); the rest are thin grey lines. Bifurcations in the range
    are marked (:func:`bifurcation_marks`). Returns the upper panel's Axes.
    """
    return _draw_fractions(axes(ax, CURVE_SIZE),
                           **_fraction_scene(tree, dim, max_curves, homoclinic_torque))


def _stability_scene(tree: xr.DataTree, dim: str = "torque",
                     homoclinic_torque: float | None = None) -> dict:
    """What :func:`basin_stability` draws: the swept values, the rest states' and the running
    basin's shares (exact and grid counts, with the grid error bound), the colours, the
    bifurcation marks and the labels."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in parameter_names(full) if d in full.dims and d != dim})
    colours = basin_colours([0], running=True, lines=True)
    return {"x": ds[dim].values,
            "exact": ds["basin_fraction_exact"].sum("k", skipna=False).values,
            "grid": ds["basin_fraction"].sum("k").values,
            "bound": ds["basin_fraction_grid_error_bound"].sum("k", skipna=False).values,
            "running": ds["running_fraction"].values,
            "running_exact": ds["running_fraction_exact"].values,
            "running_bound": ds["running_fraction_grid_error_bound"].values
            if "running_fraction_grid_error_bound" in ds else None,
            "colours": (colours[0], colours["running"]),
            "marks": bifurcation_marks(ds, dim, homoclinic_torque),
            "onset": None if homoclinic_torque is not None or "homoclinic_torque" in ds
            else _cycle_onset(tree, ds, dim),
            "xlabel": PARAMETER_AXES[dim],
            "title": "Basin stability of the rest states and of the running cycle"
                     + _held(full, ds, dim)}


def _draw_stability(ax, x, exact, grid, bound, running, running_exact, running_bound,
                    colours, marks, xlabel: str, title: str, onset=None):
    """Draw :func:`_stability_scene` (as :func:`basin_stability`)."""
    below, unit = _residual_axes(ax, [grid - exact, running - running_exact])
    bars = False
    nothing = np.full_like(np.asarray(grid, float), np.nan)
    drawn = ((exact, grid, bound, colours[0], "rest states"),
             (running_exact, running, nothing if running_bound is None else running_bound,
              colours[1], "running"))
    for e, g, b, color, name in drawn:
        ax.plot(*_broken(x, e, marks, onset), "-", color=color, label=f"{name}, exact area")
        ax.plot(x, g, "o", ms=3.5, color=color, label=f"{name}, grid count")
        bars |= _error_bars(ax, x, e, g, b, color)
        below.plot(x, (g - e) / unit, "o-", ms=3, lw=0.6, color=color)
    _draw_marks((ax, below), marks, onset)
    ax.set_ylabel("basin stability\n(fraction of the window)")
    _finish(ax, below, x, xlabel, title, bars, generic=False,
            note=_bound_note([d[:3] for d in drawn]))
    return ax


def basin_stability(tree: xr.DataTree, ax=None, dim: str = "torque",
                    homoclinic_torque: float | None = None):
    """Basin stability against the swept parameter ``dim``: the share of the window that
    settles at a rest state (all wells together) and the running basin's share, as exact
    areas (lines, where computed), grid counts (dots; error bars as :func:`fraction_curves`)
    and, below, the measured error (grid count − exact area). Any other swept parameter is
    held at its first value; bifurcations in the range are marked. Returns the upper
    panel's Axes."""
    return _draw_stability(axes(ax, CURVE_SIZE),
                           **_stability_scene(tree, dim, homoclinic_torque))


#: The curve figures: name → (reader, drawer), as :data:`atlas.views.maps.MAP_FIGURES`; the
#: reader takes the swept dim.
CURVE_FIGURES = {"fractions": (_fraction_scene, _draw_fractions),
                 "basin_stability": (_stability_scene, _draw_stability)}
