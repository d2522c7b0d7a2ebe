"""The look of every atlas figure, written once: the matplotlib style, the sizes, the colours
(wells, the running basin, separatrices, the limit cycle) and the axes' furniture (θ ticks at
multiples of π, titles naming the parameter point, critical-point markers).

The basin maps (:mod:`atlas.views.maps`), the parameter curves (:mod:`atlas.views.curves`),
the page (:mod:`atlas.views.page`) and ``atlas orbit``'s figure all draw with these.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STYLE", "MAP_SIZE", "CURVE_SIZE", "PNG_OPTIONS", "WELL_COLORS", "RUNNING_COLOR",
           "SEPARATRIX_COLOR", "CYCLE_COLOR", "pi_label", "pi_ticks", "point_title",
           "critical_point_markers", "axes", "window_ticks"]

#: One style for every atlas figure.
STYLE = {"figure.dpi": 110, "savefig.dpi": 150, "axes.grid": False, "font.size": 10,
         "axes.titlesize": 11, "legend.fontsize": 8, "legend.frameon": False}
#: Figure sizes [in]: the maps, and the curves against a swept parameter.
MAP_SIZE, CURVE_SIZE = (8, 4.8), (7, 4.5)
#: PNG options of the written figures: zlib's fastest level (deflating the smooth colour maps
#: at the default level took longer than drawing them; the files are about 40 % larger).
PNG_OPTIONS = {"compress_level": 1}
SEPARATRIX_COLOR = "red"
#: The colour of well k: WELL_COLORS[k mod 10], matplotlib's tab10 (maps and page alike).
WELL_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
               "#7f7f7f", "#bcbd22", "#17becf")
#: The running basin's colour, and the running limit cycle's.
RUNNING_COLOR, CYCLE_COLOR = "0.82", "black"


def pi_label(n: int) -> str:
    """nπ as a tick label: "0", "π", "−π", "2π", "−2π", …"""
    return "0" if n == 0 else f"{'−' if n < 0 else ''}{'' if abs(n) == 1 else abs(n)}π"


def pi_ticks(ax, lo: float, hi: float, axis: str = "x") -> None:
    """θ ticks at the multiples of π in [lo, hi] [rad] on ``axis`` ("x" or "y"), labelled
    −2π, −π, 0, π, 2π, …"""
    n = np.arange(np.ceil(lo / np.pi), np.floor(hi / np.pi) + 1).astype(int)
    getattr(ax, f"set_{axis}ticks")(n * np.pi)
    getattr(ax, f"set_{axis}ticklabels")([pi_label(k) for k in n])



#: SI prefixes of the tick scales of a narrow window: 10⁻³ m, 10⁻⁶ µ, …
_PREFIXES = {0: "", -3: "m", -6: "µ", -9: "n", -12: "p", -15: "f"}


def window_ticks(ax, lo: float, hi: float, axis: str, name: str, unit: str,
                 pi: bool = False) -> None:
    """Ticks and label of one axis of a map over [lo, hi] (``unit`` "rad" or "rad/s"),
    readable at any width: at multiples of π where ``pi`` and two of them fit (θ of a wide
    window); else plain numbers, which in a window too narrow for plain ticks to tell apart
    (zooms: hi − lo below 1, or far from 0) are the offsets from a reference near the
    centre, in units with an SI prefix: "θ̇0 − 2.4149382176 [µrad/s]", ticks −0.4 … 0.4."""
    from matplotlib.ticker import MaxNLocator

    width, centre = hi - lo, 0.5 * (lo + hi)
    if pi and np.floor(hi / np.pi) - np.ceil(lo / np.pi) >= 1:
        pi_ticks(ax, lo, hi, axis)
        getattr(ax, f"set_{axis}label")(f"{name} [{unit}]")
        return
    power = int(min(0, max(-15, 3 * np.floor(np.log10(width) / 3)))) if width > 0 else 0
    if power == 0 and abs(centre) <= 100 * width:
        getattr(ax, f"set_{axis}label")(f"{name} [{unit}]")
        return
    ref, text = 0.0, "0"
    if abs(centre) > 10 * width:  # the reference: the centre, to the digits that matter
        text = next(f"{centre:.{d}g}" for d in range(1, 18)
                    if abs(float(f"{centre:.{d}g}") - centre) <= width * 1e-4)
        ref = float(text)
    scale = 10.0 ** power
    ticks = MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]).tick_values(
        (lo - ref) / scale, (hi - ref) / scale)
    ticks = ticks[(ticks >= (lo - ref) / scale - 1e-9) & (ticks <= (hi - ref) / scale + 1e-9)]
    getattr(ax, f"set_{axis}ticks")(ref + ticks * scale)
    getattr(ax, f"set_{axis}ticklabels")([f"{t:g}".replace("-", "−") for t in ticks])
    shown = (f"{name} − {text}" if ref > 0 else f"{name} + {text.lstrip('-')}" if ref
             else name)
    getattr(ax, f"set_{axis}label")(f"{shown} [{_PREFIXES[power]}{unit}]")


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



def axes(ax, size: tuple[float, float]):
    """``ax``, or the Axes of a new pyplot figure of ``size`` [in] (pyplot manages it, as an
    interactive session expects; :func:`atlas.views.plotting.plot_atlas` draws
    into figures of its own)."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=size)[1]
