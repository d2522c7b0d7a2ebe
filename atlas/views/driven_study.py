"""``atlas info`` and ``atlas plot`` of a driven pendulum's study
(:mod:`atlas.store.driven_study`): read from the file, nothing computed.

The figures (NAME_orbits.png, NAME_fractions.png):

- the **orbit diagram**: θ and θ̇ of every attractor's points on the stroboscopic map P
  against the swept parameter, one colour per global id, coloured by kind as the basin maps
  colour a point's attractors (:func:`atlas.views.style.attractor_colours`: oscillations
  green, rotations warm or cool by their sense, chaotic attractors grey): periodic points as
  dots, chaotic clouds as fine points;
- the **basin fractions** against the parameter, one curve per global id (broken where the
  attractor is absent), with its ±1 standard error band, and the unresolved fraction; the
  located bifurcations as vertical dashed lines, named by their events at the top.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.store.driven_study import EVENT_MEANINGS, KIND_MEANINGS
from atlas.views.info_driven import attractor_name
from atlas.views.style import STYLE, attractor_colours

__all__ = ["driven_study_lines", "plot_driven_study", "id_colours", "id_markers", "id_names"]

_AXIS = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
         "torque": "torque τ [rad/s²]", "amplitude": "drive amplitude A [rad/s²]",
         "frequency": "drive frequency Ω [rad/s]", "phase": "drive phase φ [rad]"}
_EVENT_SHORT = {"birth": "+", "death": "−", "period_change": "~"}
_EVENT_COLOUR = {"birth": "#1b7837", "death": "#b2182b", "period_change": "#5e3c99"}


def _seen(ds: xr.Dataset, gid: int) -> list[tuple[str, int, int]]:
    """(kind, period, winding) of the attractor ``gid`` at each point where it is present,
    in the sweep's order."""
    return [(KIND_MEANINGS[int(k)], int(p), int(w)) for k, p, w in
            zip(ds["attractor_kind"].values[:, gid], ds["attractor_period"].values[:, gid],
                ds["attractor_winding"].values[:, gid]) if k > 0]


def _kind_winding(ds: xr.Dataset, gid: int) -> tuple[str, int, int]:
    """(kind, period, winding) of the attractor ``gid`` as it is at most of the points where
    it is present (the first of equals; periodic before chaotic): what names and colours
    it, as a basin map's key would name and colour it there."""
    seen = _seen(ds, gid)
    return max(seen, key=lambda s: (seen.count(s), s[0] == "periodic", -seen.index(s)))


def id_colours(ds: xr.Dataset, lines: bool = True) -> dict[int, str]:
    """The colour of each global id: by its kind and winding (:func:`_kind_winding`), in
    the order of the ids (:func:`atlas.views.style.attractor_colours`)."""
    ids = [int(g) for g in ds["attractor_id"].values]
    kinds, windings = zip(*[_kind_winding(ds, g)[::2] for g in ids]) if ids else ((), ())
    return dict(zip(ids, attractor_colours(kinds, windings, lines)))


#: The markers of the first, second, … attractor of one colour family (told apart where
#: their colours are near).
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "<", ">")


def id_markers(ds: xr.Dataset) -> dict[int, str]:
    """A marker per global id: the j-th of its colour family (oscillations, rotations each
    way, chaotic) gets the j-th of :data:`_MARKERS`."""
    seen: dict[str, int] = {}
    out = {}
    for g in (int(v) for v in ds["attractor_id"].values):
        kind, _, winding = _kind_winding(ds, g)
        family = kind if kind == "chaotic" else str(int(np.sign(winding)))
        out[g] = _MARKERS[seen.get(family, 0) % len(_MARKERS)]
        seen[family] = seen.get(family, 0) + 1
    return out


def _also(kind: str, period: int, winding: int) -> str:
    if kind == "chaotic":
        return "chaotic"
    return f"period {period}" + (f", winding {winding:+d}" if winding else "")


def id_names(ds: xr.Dataset) -> dict[int, str]:
    """"#12 rotation, period 2, winding -2" of each global id, as it is at most of its
    points (:func:`_kind_winding`), and what else it is somewhere along the sweep ("#11
    rotation, period 1, winding -1; also period 2, winding -2"): the period changes that
    the events mark."""
    out = {}
    for g in (int(v) for v in ds["attractor_id"].values):
        best = _kind_winding(ds, g)
        others = [_also(*f) for f in dict.fromkeys(_seen(ds, g)) if f != best]
        out[g] = f"#{g} {attractor_name(*best)}" + (
            "; also " + ", ".join(others) if others else "")
    return out


def _events(ds: xr.Dataset) -> list[tuple[float, float, str, int, int, int]]:
    return [(float(ds["bifurcation_value"].values[i]), float(ds["bifurcation_error"].values[i]),
             EVENT_MEANINGS[int(ds["bifurcation_kind"].values[i])],
             int(ds["bifurcation_attractor"].values[i]),
             int(ds["bifurcation_period_before"].values[i]),
             int(ds["bifurcation_period_after"].values[i]))
            for i in range(ds.sizes.get("bifurcation", 0))]


def _period(p: int) -> str:
    return "chaotic" if p == 0 else "absent" if p < 0 else f"period {p}"


def driven_study_lines(ds: xr.Dataset) -> list[str]:
    """The summary of a driven study: its sweep, sampling, attractors (where each lives and
    its largest basin fraction) and located bifurcations."""
    dim = str(ds.attrs["swept_parameter"])
    x = np.atleast_1d(ds[dim].values)
    (a, b), (lo, hi) = ds.attrs["window_theta"], ds.attrs["window_theta_dot"]
    fixed = ", ".join(f"{n} = {float(ds[n]):g}" for n in
                      ("alpha", "omega0", "torque", "amplitude", "frequency", "phase")
                      if n != dim)
    sweep = f"{dim} = {x[0]:g}" if x.size == 1 else \
        f"{dim} from {x[0]:g} to {x[-1]:g} ({x.size} points)"
    n = int(ds.attrs["samples"])
    lines = [f"driven pendulum study: {sweep}; {fixed}",
             f"window    theta in [{a:.6g}, {b:.6g}] rad, theta_dot in [{lo:g}, {hi:g}] rad/s;"
             f" {n:,} samples per point (seed {int(ds.attrs['seed'])}), the same at every "
             "point",
             f"attractors {ds.sizes['attractor_id']} followed (matched by set distance on P "
             f"below {float(ds.attrs['matching_threshold']):g}); at most "
             f"{int(ds['attractor_count'].max()) if x.size else 0} at one point"]
    names = id_names(ds)
    frac = ds["basin_fraction"].values
    err = ds["basin_fraction_error"].values
    for g in (int(v) for v in ds["attractor_id"].values):
        where = np.flatnonzero(ds["attractor_kind"].values[:, g] > 0)
        best = where[np.argmax(frac[where, g])]
        span = f"at {dim} = {x[where[0]]:g}" if where.size == 1 else \
            f"{dim} {x[where[0]]:g} … {x[where[-1]]:g} ({where.size} points)"
        lines.append(f"  {names[g]}: {span}; largest basin {frac[best, g]:.4f} ± "
                     f"{err[best, g]:.4f} at {x[best]:g}")
    u = ds["unresolved_fraction"].values
    if u.size:
        lines.append(f"unresolved fraction: at most {u.max():.4f} (at {dim} = "
                     f"{x[np.argmax(u)]:g})")
    events = _events(ds)
    lines.append(f"bifurcations: {len(events)} located (bisection to "
                 f"{float(ds.attrs['bisection_rtol']):g} relative, at most "
                 f"{int(ds.attrs['bisection_max_steps'])} steps)")
    for value, error, kind, g, before, after in events:
        change = f" ({_period(before)} → {_period(after)})" if kind == "period_change" else ""
        lines.append(f"  {dim} = {value:.6f} ± {error:.1g}: {kind.replace('_', ' ')} of "
                     f"#{g}{change}")
    return lines


def _orbit_diagram(ds: xr.Dataset, dim: str):
    colours = id_colours(ds)
    markers = id_markers(ds)
    names = id_names(ds)
    x = np.atleast_1d(ds[dim].values)

    def draw(fig):
        axes = fig.subplots(2, 1, sharex=True)
        step = ds["orbit_step"].values
        gid = ds["orbit_attractor"].values
        kinds = ds["attractor_kind"].values
        for ax, name, label in ((axes[0], "orbit_theta", "θ on P [rad]"),
                                (axes[1], "orbit_theta_dot", "θ̇ on P [rad/s]")):
            y = ds[name].values
            for g in np.unique(gid):
                mine = gid == g
                chaotic = kinds[step[mine], g] == 2
                px, py = x[step[mine]], y[mine]
                if (~chaotic).any():
                    ax.scatter(px[~chaotic], py[~chaotic], s=10, color=colours[int(g)],
                               marker=markers[int(g)], linewidths=0, label=names[int(g)],
                               zorder=3)
                if chaotic.any():
                    ax.scatter(px[chaotic], py[chaotic], s=0.6, color=colours[int(g)],
                               linewidths=0, zorder=2, rasterized=True,
                               label=None if (~chaotic).any() else names[int(g)])
            ax.set_ylabel(label)
        axes[0].set_ylim(-np.pi, np.pi)
        axes[0].set_yticks([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi],
                           ["−π", "−π/2", "0", "π/2", "π"])
        axes[1].set_xlabel(_AXIS.get(dim, dim))
        axes[0].set_title("attractors on the stroboscopic map P, followed along the sweep",
                          loc="left")
        from matplotlib.lines import Line2D

        ids = [int(g) for g in ds["attractor_id"].values]
        handles = [Line2D([], [], ls="", marker=markers[g], color=colours[g], ms=5)
                   for g in ids]  # proxies: the scatters keep their sizes
        fig.legend(handles, [names[g] for g in ids], loc="outside right upper",
                   fontsize=7, ncols=1 if len(ids) <= 24 else 2,
                   title="fine points: chaotic", title_fontsize=7)

    return draw


def _groups(events, width: float) -> list[list]:
    """Events within ``width`` of each other, one group each (drawn as one line)."""
    out: list[list] = []
    for e in sorted(events):
        if out and e[0] - out[-1][-1][0] <= width:
            out[-1].append(e)
        else:
            out.append([e])
    return out


def _fraction_curves(ds: xr.Dataset, dim: str):
    colours = id_colours(ds)
    markers = id_markers(ds)
    names = id_names(ds)
    x = np.atleast_1d(ds[dim].values)
    n = int(ds.attrs["samples"])

    def draw(fig):
        ax = fig.subplots()
        f = ds["basin_fraction"].values
        e = ds["basin_fraction_error"].values
        for g in (int(v) for v in ds["attractor_id"].values):
            present = np.isfinite(f[:, g])
            ax.plot(x, f[:, g], "-", color=colours[g], lw=1.4, label=names[g],
                    marker=markers[g], ms=3.5,
                    markevery=max(1, int(present.sum()) // 8) or None)
            ax.fill_between(x, f[:, g] - e[:, g], f[:, g] + e[:, g], color=colours[g],
                            alpha=0.25, lw=0)
        u = ds["unresolved_fraction"].values
        if (u > 0).any():
            ax.plot(x, u, ":", color="0.3", lw=1.2, label="unresolved")
        span = x[-1] - x[0] if x.size > 1 else 1.0
        top = ax.get_ylim()[1]
        for group in _groups(_events(ds), 0.012 * span):
            value = float(np.mean([g[0] for g in group]))
            kinds = {g[2] for g in group}
            colour = _EVENT_COLOUR[kinds.pop()] if len(kinds) == 1 else "0.35"
            ax.axvline(value, color=colour, ls="--", lw=0.8, zorder=1)
            tags = [f"{_EVENT_SHORT[k]}{g}" for _, _, k, g, _, _ in group]
            tag = "\n".join(" ".join(tags[i:i + 5]) for i in range(0, len(tags), 5))
            ax.text(value, 1.01, tag, linespacing=1.0, transform=ax.get_xaxis_transform(),
                    rotation=90,
                    ha="center", va="bottom", fontsize=7.5, color=colour)
        ax.set_ylim(0, max(top, 0.05))
        ax.set_xlim(x[0], x[-1]) if x.size > 1 else None
        ax.set_xlabel(_AXIS.get(dim, dim))
        ax.set_ylabel(f"basin fraction ({n:,} samples; band ±1 s.e.)")
        fig.suptitle("basin fractions of the attractors followed along the sweep; dashed: "
                     "located bifurcations\n(+ birth, − death, ~ period change of the "
                     "attractor #; events within 1.2 % of the range share a line)",
                     fontsize=10)
        # as many columns as the longest name leaves room for (7.5 pt: about 0.055 in a
        # character, and 0.5 in for the line and the gap), at most 4
        longest = max([len(v) for v in names.values()] + [len("unresolved")])
        fits = int(fig.get_figwidth() / (0.055 * longest + 0.5))
        fig.legend(loc="outside lower center", fontsize=7.5,
                   ncols=max(1, min(4, fits, (len(names) + 1 + 3) // 4)))

    return draw


def _figure(out: Path, size, draw, dpi) -> Path:
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from atlas.store.outputs import figure_metadata
    from atlas.views.style import PNG_OPTIONS

    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=size, dpi=dpi or STYLE["savefig.dpi"], layout="constrained")
        FigureCanvasAgg(fig)
        draw(fig)
        options = {"pil_kwargs": PNG_OPTIONS} if out.suffix == ".png" else {}
        fig.savefig(out, metadata=figure_metadata(out.suffix, "atlas plot"), **options)
    return out


def plot_driven_study(ds: xr.Dataset, path: Path, outdir=None, fmt: str = "png", dpi=None
                      ) -> list[Path]:
    """The figures (module docstring) of the driven study ``ds`` read from ``path``, written
    into ``outdir`` (default: next to it) as NAME_orbits.<fmt> and NAME_fractions.<fmt>."""
    from atlas.store.outputs import check_output

    dim = str(ds.attrs["swept_parameter"])
    folder = Path(outdir) if outdir is not None else path.parent
    stem = path.name.removesuffix(path.suffix)
    wide = 12 if ds.sizes["attractor_id"] > 24 else 10.5
    rows = -(-(ds.sizes["attractor_id"] + 1) // 4)  # the fractions' legend, 4 columns
    figures = [(f"{stem}_orbits", (wide, 7.0), _orbit_diagram(ds, dim)),
               (f"{stem}_fractions", (10.5, 6.5 + 0.16 * rows), _fraction_curves(ds, dim))]
    paths = [folder / f"{name}.{fmt}" for name, _, _ in figures]
    for out in paths:
        check_output(out, "figure", inputs=(path,), option="--outdir", command="atlas plot")
    folder.mkdir(parents=True, exist_ok=True)
    return [_figure(out, size, draw, dpi) for out, (_, size, draw) in zip(paths, figures)]
