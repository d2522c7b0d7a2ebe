"""Figures of an atlas: a leaf layer that only reads Datasets (it computes nothing).

* :func:`basin_map` — colour by attractor k, separatrices in red, saddles as open circles,
  attractors as filled dots;
* :func:`trap_time_map` — the certified trapping time on a log colour scale;
* :func:`boundary_distance_map` — each state's distance to the nearest basin boundary (how
  far it is from tipping into another well), with the band d_cert where labels hold for the
  RK4 map only;
* :func:`fraction_curves` — exact basin fractions against a swept parameter, with the grid
  counts and their error bounds.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm  # noqa: E402

from .kernels import NEAR_BOUNDARY, RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED  # noqa: E402
from .layout import PARAMETERS, first_point, point_group, point_label, point_of  # noqa: E402

__all__ = ["basin_map", "trap_time_map", "boundary_distance_map", "fraction_curves",
           "plot_atlas", "pi_ticks", "critical_point_markers", "STYLE"]

#: One style for every atlas figure.
STYLE = {"figure.dpi": 110, "savefig.dpi": 150, "axes.grid": False, "font.size": 10,
         "axes.titlesize": 11, "legend.fontsize": 8, "legend.frameon": False}
SEPARATRIX_COLOR = "red"
#: The running basin's colour, and the running limit cycle's.
RUNNING_COLOR, CYCLE_COLOR = "0.82", "black"
TWO_PI = 2.0 * np.pi


def pi_ticks(ax, lo: float, hi: float) -> None:
    """θ ticks at the multiples of π in [lo, hi] [rad], labelled −2π, −π, 0, π, 2π, …"""
    n = np.arange(np.ceil(lo / np.pi), np.floor(hi / np.pi) + 1).astype(int)
    ax.set_xticks(n * np.pi)
    ax.set_xticklabels(["0" if k == 0 else f"{'−' if k < 0 else ''}{'' if abs(k) == 1 else abs(k)}π"
                        for k in n])


def _single(ds: xr.Dataset, **index) -> xr.Dataset:
    """The basin map of one parameter point (the first along each swept dim unless
    indexed)."""
    return first_point(ds, **index)


def point_title(point: dict[str, float]) -> str:
    """"α = 0.1 s⁻¹, ω0 = 1 rad/s" (and τ where the pendulum has a torque)."""
    text = f"α = {point['alpha']:g} s⁻¹, ω0 = {point['omega0']:g} rad/s"
    torque = point.get("torque", 0.0)
    return text + (f", τ = {torque:g} rad/s²" if torque else "")


def critical_point_markers(ax, theta, is_saddle, tilted: bool = False) -> None:
    """Mark the critical points (θ [rad], 0) on the θ axis: attractors (2πk, 0) as black dots,
    saddles ((2j+1)π, 0) as open red circles (essay Figure 9), labelled for the legend;
    ``tilted``: a pendulum with torque, whose rest states sit at θ* + 2πk, θ* = asin(τ/ω0²),
    and saddles at π − θ* + 2πk."""
    theta, is_saddle = np.asarray(theta, float), np.asarray(is_saddle, bool)
    ax.plot(theta[~is_saddle], np.zeros((~is_saddle).sum()), "o", color="black", ms=5,
            label="attractors (θ* + 2πk, 0)" if tilted else "attractors (2πk, 0)", zorder=5)
    ax.plot(theta[is_saddle], np.zeros(is_saddle.sum()), "o", mfc="none",
            mec=SEPARATRIX_COLOR, mew=1.5, ms=7,
            label="saddles (π − θ* + 2πk, 0)" if tilted else "saddles ((2j+1)π, 0)", zorder=5)


def _critical(ax, tree: xr.DataTree, ds: xr.Dataset) -> None:
    """The critical points of the parameter point that ``ds`` shows, if stored, as
    :func:`critical_point_markers`."""
    cp = point_group(tree, "critical_points", point_of(ds))
    if cp is None:
        return
    critical_point_markers(ax, cp["theta"].values, cp["n"].values % 2 != 0,  # odd n: saddles
                           tilted=bool(float(ds["torque"])))


def _limit_cycle(ax, tree: xr.DataTree, ds: xr.Dataset) -> None:
    """The running limit cycle of the parameter point that ``ds`` shows (if it has one),
    repeated 2π-periodically across the window."""
    cycle = point_group(tree, "limit_cycle", point_of(ds))
    if cycle is None:
        return
    theta, speed = cycle["theta"].values, cycle["theta_dot"].values
    lo, hi = float(ds["theta0"][0]), float(ds["theta0"][-1])
    order = np.argsort(theta)
    theta, speed = theta[order], speed[order]
    shifts = np.arange(np.floor((lo - theta.max()) / TWO_PI), np.ceil((hi - theta.min()) / TWO_PI)
                       + 1)
    for i, shift in enumerate(shifts):
        ax.plot(theta + TWO_PI * shift, speed, color=CYCLE_COLOR, lw=1.6, ls="--",
                label=f"limit cycle (period {float(cycle.attrs['period']):.4g} s)"
                if i == 0 else None)


def _separatrices(ax, tree: xr.DataTree, ds: xr.Dataset) -> None:
    """The separatrices of the parameter point that ``ds`` shows, in red."""
    from .separatrices import branches

    sep = point_group(tree, "separatrices", point_of(ds))
    if sep is None:
        return
    for i, (_, _, theta, theta_dot) in enumerate(branches(sep)):
        ax.plot(theta, theta_dot, color=SEPARATRIX_COLOR, lw=1.2,
                label="separatrices" if i == 0 else None)


#: Largest image drawn per axis [pixels]: a figure is 8 in wide at 150 dpi. Larger maps are
#: coarsened to it first (labels by their mode, never averaged into a k that no orbit reached).
MAX_PIXELS = 1200


def _coarsen(values: np.ndarray, how: str) -> np.ndarray:
    """Block-reduce ``values`` (rows × columns, NaN = no value) to at most MAX_PIXELS per axis:
    ``mode`` for labels, ``min`` or ``max`` for continuous maps (keeping their extremes)."""
    fr, fc = (-(-n // MAX_PIXELS) for n in values.shape)
    if fr == fc == 1:
        return values
    rows, cols = -(-values.shape[0] // fr), -(-values.shape[1] // fc)
    padded = np.full((rows * fr, cols * fc), np.nan)
    padded[:values.shape[0], :values.shape[1]] = values
    blocks = padded.reshape(rows, fr, cols, fc).transpose(0, 2, 1, 3).reshape(rows, cols, -1)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN blocks stay NaN
        if how == "min":
            return np.nanmin(blocks, axis=2)
        if how == "max":
            return np.nanmax(blocks, axis=2)
    finite = blocks[np.isfinite(blocks)]
    if not finite.size:
        return blocks[..., 0]
    lo = int(finite.min())
    counts = np.stack([(blocks == k).sum(axis=2) for k in range(lo, int(finite.max()) + 1)])
    mode = (lo + counts.argmax(axis=0)).astype(float)
    return np.where(counts.max(axis=0) > 0, mode, np.nan)


def _grid_image(ax, ds: xr.Dataset, values: np.ndarray, how: str, **kwargs):
    """Draw a map over the grid (rows θ̇0, columns θ0) as an image whose pixels are the grid's
    cells (centred on the grid points), coarsened to the figure's resolution."""
    th, v = ds["theta0"].values, ds["theta_dot0"].values
    half_t = 0.5 * (th[-1] - th[0]) / max(th.size - 1, 1)
    half_v = 0.5 * (v[-1] - v[0]) / max(v.size - 1, 1)
    image = ax.imshow(np.ma.masked_invalid(_coarsen(values, how)), origin="lower",
                      extent=(th[0] - half_t, th[-1] + half_t, v[0] - half_v, v[-1] + half_v),
                      aspect="auto", interpolation="nearest", **kwargs)
    ax.set_xlim(th[0], th[-1])
    ax.set_ylim(v[0], v[-1])
    pi_ticks(ax, th[0], th[-1])
    ax.set_xlabel("θ0 [rad]")
    ax.set_ylabel("θ̇0 [rad/s]")
    return image


def basin_map(tree: xr.DataTree, ax=None, **index):
    """Draw the basin map of ``tree`` (colour by k) with critical points and separatrices."""
    ds = _single(tree.to_dataset(inherit=False), **index)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.8))
    k = ds["attractor"].values.astype(float)
    status = ds["status"].values
    k[~np.isin(status, (TRAPPED, NEAR_BOUNDARY))] = np.nan
    finite = k[np.isfinite(k)]
    kmin, kmax = (int(finite.min()), int(finite.max())) if finite.size else (0, 0)
    colors = list(plt.get_cmap("tab10")(np.arange(kmin, kmax + 1) % 10))
    ticks, names = list(range(kmin, kmax + 1)), [f"{k:+d}" for k in range(kmin, kmax + 1)]
    running = (status == RUNNING) | (status == RUNNING_NEAR_BOUNDARY)
    if running.any():  # the running basin: one more colour after the wells
        k[running] = kmax + 1
        colors.append(RUNNING_COLOR)
        ticks.append(kmax + 1)
        names.append("running")
    cmap = ListedColormap(colors).with_extremes(bad="white")
    levels = np.arange(kmin, kmin + len(colors) + 1) - 0.5
    mesh = _grid_image(ax, ds, k, "mode", cmap=cmap, norm=BoundaryNorm(levels, cmap.N))
    cbar = ax.figure.colorbar(mesh, ax=ax, ticks=ticks)
    cbar.ax.set_yticklabels(names)
    cbar.set_label("attractor k: orbit settles at the rest state of well k"
                   + ("; running: rotates" if running.any() else ""))
    _separatrices(ax, tree, ds)
    _limit_cycle(ax, tree, ds)
    _critical(ax, tree, ds)
    ax.set_title(f"Basins of attraction, {point_title(point_of(ds))}")
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=3, borderaxespad=0)
    return ax


def trap_time_map(tree: xr.DataTree, ax=None, **index):
    """Draw the certified trapping time t_trap [s] on a log colour scale."""
    ds = _single(tree.to_dataset(inherit=False), **index)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.8))
    t = ds["t_trap"].values.astype(float)
    positive = t[np.isfinite(t) & (t > 0)]
    lo = positive.min() if positive.size else 1e-2
    hi = max(positive.max() if positive.size else 1.0, lo * 10)
    cmap = plt.get_cmap("magma").with_extremes(under="0.8", bad="white")
    # t_trap = 0 (already inside the trap) is drawn below the scale, in grey
    mesh = _grid_image(ax, ds, np.where(t > 0, t, lo / 2), "max", cmap=cmap,
                       norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label("trapping time t_trap [s]")
    _separatrices(ax, tree, ds)
    ax.set_title("Time to certified trapping (grey: trapped at t = 0; white: never)")
    return ax


def boundary_distance_map(tree: xr.DataTree, ax=None, **index):
    """Draw ``boundary_distance`` on a log colour scale, the separatrices, and in white the
    states closer than d_cert (labels certified for the RK4 map only)."""
    ds = _single(tree.to_dataset(inherit=False), **index)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.8))
    d = ds["boundary_distance"].values.astype(float)
    d_cert = float(ds["d_cert"])
    positive = d[np.isfinite(d) & (d > 0)]
    lo = max(positive.min() if positive.size else 1e-12, d_cert if d_cert > 0 else 0, 1e-12)
    hi = max(positive.max() if positive.size else 1.0, lo * 10)
    cmap = plt.get_cmap("viridis").with_extremes(under="white", bad="0.5")
    mesh = _grid_image(ax, ds, d, "min", cmap=cmap, norm=LogNorm(lo, hi))
    ax.figure.colorbar(mesh, ax=ax, extend="min").set_label(
        "distance to the nearest basin boundary (rad-ish)")
    _separatrices(ax, tree, ds)
    cert = f"d_cert = {d_cert:.1e}" if d_cert == d_cert else "d_cert not measured"
    ax.set_title(f"Distance to tipping into another well (white: closer than {cert})")
    return ax


#: Axis labels of the parameters.
PARAMETER_AXES = {"alpha": "damping α [1/s]", "omega0": "natural frequency ω0 [rad/s]",
                  "torque": "torque τ [rad/s²]"}


def fraction_curves(tree: xr.DataTree, ax=None, dim: str = "alpha", max_curves: int = 7):
    """Exact basin fraction of each k against the swept parameter ``dim`` (lines), with the
    grid counts and their error bounds (markers with error bars); any other swept parameter
    is held at its first value (named in the title).

    The ``max_curves`` largest basins get a curve each; the rest are summed into one
    "other k" curve. A dashed line marks critical damping α = ω0 when α is swept.
    """
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in full["basin_fraction_exact"].dims if d not in (dim, "k")})
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    x = ds[dim].values
    exact = ds["basin_fraction_exact"].transpose(dim, "k").values
    grid = ds["basin_fraction"].transpose(dim, "k").values
    bound = ds["basin_fraction_grid_error_bound"].transpose(dim, "k").values
    shown = np.sort(np.argsort(exact.max(axis=0))[::-1][:max_curves])
    rest = np.setdiff1d(np.arange(exact.shape[1]), shown)
    curves = [(exact[:, j], grid[:, j], bound[:, j], f"k = {int(ds['k'].values[j]):+d}", None)
              for j in shown]
    if rest.size:
        curves.append((exact[:, rest].sum(axis=1), grid[:, rest].sum(axis=1),
                       bound[:, rest].sum(axis=1), f"other k ({rest.size})", "0.5"))
    for e, g, b, label, color in curves:
        line, = ax.plot(x, e, "-", color=color, label=label)
        ax.errorbar(x, g, yerr=b, fmt="o", ms=3, capsize=2, color=line.get_color())
    if dim == "alpha" and ds["omega0"].ndim == 0:
        ax.axvline(float(ds["omega0"]), color="0.3", ls=":", lw=1, label="α = ω0 (critical)")
    ax.set_xscale("log" if x.min() > 0 and x.max() / x.min() > 20 else "linear")
    ax.set_xlabel(PARAMETER_AXES[dim])
    ax.set_ylabel("basin fraction of the window")
    held = {n: float(ds[n]) for n in PARAMETERS if n != dim and n in full.dims}
    ax.set_title("Basin fractions: exact areas (lines), grid counts with error bounds (dots)"
                 + (f"\nat {point_label(held)}" if held else ""))
    ax.legend(ncol=2)
    return ax


def basin_stability(tree: xr.DataTree, ax=None, dim: str = "torque"):
    """Basin stability against the swept parameter ``dim``: the share of the window that
    settles at a rest state (all wells together) and the running basin's share, as exact
    areas (lines, where computed) and grid counts (markers; error bars: the grid error bound,
    where computed). Any other swept parameter is held at its first value."""
    full = tree.to_dataset(inherit=False)
    ds = full.isel({d: 0 for d in PARAMETERS if d in full.dims and d != dim})
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    x = ds[dim].values
    exact = ds["basin_fraction_exact"].sum("k", skipna=False).values
    grid = ds["basin_fraction"].sum("k").values
    bound = ds["basin_fraction_grid_error_bound"].sum("k", skipna=False).values
    running = ds["running_fraction"].values
    running_exact = ds["running_fraction_exact"].values
    shown = np.isfinite(exact)
    if shown.any():
        ax.plot(x[shown], exact[shown], "-", color="C0", label="rest states, exact area")
        ax.plot(x[shown], running_exact[shown], "-", color="0.4", label="running, exact area")
    ax.errorbar(x, grid, yerr=np.where(np.isfinite(bound), bound, 0.0), fmt="o", ms=3,
                capsize=2, color="C0", label="rest states, grid count")
    ax.plot(x, running, "s", ms=3, color="0.4", label="running, grid count")
    ax.set_xlabel(PARAMETER_AXES[dim])
    ax.set_ylabel("basin stability (fraction of the window)")
    ax.set_ylim(-0.02, 1.02)
    held = {n: float(ds[n]) for n in PARAMETERS if n != dim and n in full.dims}
    ax.set_title("Basin stability of the rest states and of the running cycle"
                 + (f"\nat {point_label(held)}" if held else ""))
    ax.legend()
    return ax


def plot_atlas(tree: xr.DataTree, path: Path) -> list[Path]:
    """Write the figures of the atlas stored at ``path`` next to it; returns the PNG paths."""
    path = Path(path)
    written = []
    ds = tree.to_dataset(inherit=False)
    with plt.rc_context(STYLE):
        jobs = [(path.with_suffix(".png"), basin_map),
                (path.with_name(path.stem + "_t_trap.png"), trap_time_map),
                (path.with_name(path.stem + "_boundary_distance.png"), boundary_distance_map)]
        for dim in (name for name in PARAMETERS if name in ds.dims):
            jobs.append((path.with_name(f"{path.stem}_fractions_{dim}.png"),
                         lambda t, dim=dim: fraction_curves(t, dim=dim)))
            if dim == "torque":
                jobs.append((path.with_name(f"{path.stem}_basin_stability.png"),
                             basin_stability))
        for out, draw in jobs:
            ax = draw(tree)
            ax.figure.tight_layout()
            ax.figure.savefig(out)
            plt.close(ax.figure)
            written.append(out)
    return written
