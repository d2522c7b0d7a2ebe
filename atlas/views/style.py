"""The look of every atlas figure, written once: the matplotlib style, the sizes, the colours
(wells, the running basin, separatrices, the limit cycle) and the axes' furniture (θ ticks at
multiples of π, titles naming the parameter point, critical-point markers).

The basin maps (:mod:`atlas.views.maps`), the parameter curves (:mod:`atlas.views.curves`),
the page (:mod:`atlas.views.page`) and ``atlas orbit``'s figure all draw with these.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STYLE", "MAP_SIZE", "CURVE_SIZE", "PNG_OPTIONS", "basin_colours",
           "RUNNING_COLOR_HEX", "NO_LABEL_COLOR", "SEPARATRIX_COLOR", "SEPARATRIX_WIDTH",
           "SEPARATRIX_ALPHA", "SEPARATRIX_FAINT", "CYCLE_COLOR", "LABELLED_WELLS", "pi_label",
           "pi_ticks", "point_title", "critical_point_markers", "axes", "window_ticks"]

#: One style for every atlas figure.
STYLE = {"figure.dpi": 110, "savefig.dpi": 150, "axes.grid": False, "font.size": 10,
         "axes.titlesize": 11, "legend.fontsize": 8, "legend.frameon": False}
#: Figure sizes [in]: the maps, and the curves against a swept parameter (a panel of the
#: measured error below, the legend on the right).
MAP_SIZE, CURVE_SIZE = (8, 4.8), (9, 5.4)
#: PNG options of the written figures: zlib's fastest level (deflating the smooth colour maps
#: at the default level took longer than drawing them; the files are about 40 % larger).
PNG_OPTIONS = {"compress_level": 1}
#: The separatrices over a basin map: thin (0.5 pt, about one pixel of a saved map), near-black
#: and translucent, so that a tongue a few pixels wide keeps its colour between its two
#: outlines; over the t_trap and distance maps they are fainter still (SEPARATRIX_FAINT).
SEPARATRIX_COLOR, SEPARATRIX_WIDTH, SEPARATRIX_ALPHA = "#1a1a1a", 0.5, 0.75
SEPARATRIX_FAINT = {"color": "white", "lw": 0.4, "alpha": 0.45}
#: The running limit cycle's colour.
CYCLE_COLOR = "black"
#: Basin maps with more wells than this label each band "k = …" inside it: past it, the
#: lightness steps of the palette are too fine to name a band by colour alone.
LABELLED_WELLS = 16

# The basin palette (:func:`basin_colours`), defined in Oklab (B. Ottosson, "A perceptual
# color space for image processing", 2020), whose lightness L (0 black … 1 white), chroma C
# and hue h [deg] are perceptually uniform enough to place colours by: hue by the sign of k
# (k > 0 warm, yellow → crimson; k < 0 cool, cyan → violet, the blue–yellow axis that
# red–green colour-blind readers keep), lightness by |k| (the nearest wells lightest), k = 0
# green, the running basin a neutral grey, no certified label white. Each colour takes the
# largest chroma up to _CHROMA that sRGB can show at its L and h. The distances are
# checked in CAM02-UCS, also under simulated deuteranopia and protanopia (colorspacious),
# by tests/views/test_palette.py.
_L_NEAR, _L_FAR = 0.90, 0.35        # Oklab L of |k| = 1 and of the farthest well
_L_NEAR_LINES, _L_FAR_LINES = 0.80, 0.30  # the same, for lines and markers on white
_HUE_POSITIVE, _HUE_NEGATIVE = (95.0, 0.0), (200.0, 300.0)  # h [deg] from |k| = 1 to the farthest
_CHROMA = 0.16
_ZERO_LCH = (0.72, 0.14, 150.0)     # k = 0: green (0.60 for lines)
_RUNNING_L = 0.62                   # the running basin: neutral grey (0.45 for lines)
#: Colour of "no certified label" (status unresolved or nonfinite) on every map: white.
NO_LABEL_COLOR = "#ffffff"

# Oklab → linear sRGB (Ottosson 2020): the inverse of his M2, then of M1.
_LAB_TO_LMS = np.array([[1.0, 0.3963377774, 0.2158037573],
                        [1.0, -0.1055613458, -0.0638541728],
                        [1.0, -0.0894841775, -1.2914855480]])
_LMS_TO_RGB = np.array([[4.0767416621, -3.3077115913, 0.2309699292],
                        [-1.2684380046, 2.6097574011, -0.3413193965],
                        [-0.0041960863, -0.7034186147, 1.7076147010]])


def _linear_rgb(lightness: float, chroma: float, hue: float) -> np.ndarray:
    """Linear sRGB (0…1 where in gamut) of the Oklab colour (L, C, h [deg])."""
    h = np.radians(hue)
    lab = np.array([lightness, chroma * np.cos(h), chroma * np.sin(h)])
    return _LMS_TO_RGB @ (_LAB_TO_LMS @ lab) ** 3


def _oklch_hex(lightness: float, chroma: float, hue: float) -> str:
    """"#rrggbb" of Oklab (L, C, h [deg]), its chroma lowered (bisection, to 1e-6) until sRGB
    holds it, at the same lightness and hue."""
    def inside(c):
        rgb = _linear_rgb(lightness, c, hue)
        return bool(np.all((rgb >= -1e-9) & (rgb <= 1 + 1e-9)))

    lo, hi = 0.0, chroma
    if not inside(chroma):
        while hi - lo > 1e-6:
            lo, hi = ((lo + hi) / 2, hi) if inside((lo + hi) / 2) else (lo, (lo + hi) / 2)
        chroma = lo
    rgb = np.clip(_linear_rgb(lightness, chroma, hue), 0.0, 1.0)
    # the sRGB transfer function (IEC 61966-2-1)
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * rgb ** (1 / 2.4) - 0.055)
    return "#" + "".join(f"{round(255 * v):02x}" for v in srgb)


def basin_colours(ks, running: bool = False, lines: bool = False) -> dict[int | str, str]:
    """The colour ("#rrggbb") of each well k in ``ks`` in one figure, and of "none" (no
    certified label) and, with ``running``, of "running" (the running basin): every one
    distinct, no colour repeated whatever the number of wells (no cycling).

    Hue by the sign of k, lightness by |k| (Oklab L from 0.90 at |k| = 1 down by
    0.55/max(K − 1, 3) per well, K the figure's largest |k|: to 0.35 at |k| = K when K ≥ 4),
    k = 0 green, the
    running basin neutral grey, no label white: so +k and −k are one pair, a light and a
    dark band are near and far wells, and the colours stay apart for colour-blind readers
    (deuteranopia, protanopia: the warm and the cool side differ along blue–yellow). The
    palette depends on the figure's largest |k| only; the maps, ``atlas orbit``'s figure,
    the curves and the page all take their colours from here. ``lines``: the same scheme
    darker (L from 0.80 to 0.30), for thin lines and markers on a white page (the curves),
    where the lightest map colours would vanish."""
    ks = [int(k) for k in ks]
    far = max([abs(k) for k in ks] + [1])
    near_l, far_l = (_L_NEAR_LINES, _L_FAR_LINES) if lines else (_L_NEAR, _L_FAR)
    colours: dict[int | str, str] = {}
    for k in ks:
        if k == 0:
            colours[k] = _oklch_hex(0.60 if lines else _ZERO_LCH[0], *_ZERO_LCH[1:])
            continue
        t = (abs(k) - 1) / max(far - 1, 3)
        hues = _HUE_POSITIVE if k > 0 else _HUE_NEGATIVE
        colours[k] = _oklch_hex(near_l - t * (near_l - far_l), _CHROMA,
                                hues[0] + t * (hues[1] - hues[0]))
    if running:
        colours["running"] = _oklch_hex(0.45, 0.0, 0.0) if lines else RUNNING_COLOR_HEX
    colours["none"] = NO_LABEL_COLOR
    return colours


#: The running basin's colour: a neutral grey, "#rrggbb".
RUNNING_COLOR_HEX = _oklch_hex(_RUNNING_L, 0.0, 0.0)


def pi_label(n: int, halves: bool = False) -> str:
    """nπ as a tick label: "0", "π", "−π", "2π", "−2π", …; with ``halves``, (n/2)π:
    "π/2", "−3π/2", "π", …"""
    if halves and n % 2:
        return f"{'−' if n < 0 else ''}{'' if abs(n) == 1 else abs(n)}π/2"
    n = n // 2 if halves else n
    return "0" if n == 0 else f"{'−' if n < 0 else ''}{'' if abs(n) == 1 else abs(n)}π"


def _pi_multiples(lo: float, hi: float, step: float) -> np.ndarray:
    """The integers n with n·step·π in [lo, hi]."""
    return np.arange(np.ceil(lo / (step * np.pi)), np.floor(hi / (step * np.pi)) + 1).astype(int)


def pi_ticks(ax, lo: float, hi: float, axis: str = "x", most: int = 9) -> None:
    """θ ticks in [lo, hi] [rad] on ``axis`` ("x" or "y") at the multiples of π/2, π, 2π,
    4π, … — the finest step that gives at most ``most`` ticks — labelled "−π/2", "0", "π",
    "2π", …"""
    step = 0.5
    while _pi_multiples(lo, hi, step).size > most:
        step *= 2
    n = _pi_multiples(lo, hi, step)
    getattr(ax, f"set_{axis}ticks")(n * step * np.pi)
    getattr(ax, f"set_{axis}ticklabels")([pi_label(int(k * step * 2), halves=True)
                                          for k in n])


#: SI prefixes of the tick scales of a narrow window: 10⁻³ m, 10⁻⁶ µ, …
_PREFIXES = {0: "", -3: "m", -6: "µ", -9: "n", -12: "p", -15: "f"}


def window_ticks(ax, lo: float, hi: float, axis: str, name: str, unit: str,
                 pi: bool = False) -> None:
    """Ticks and label of one axis of a map over [lo, hi] (``unit`` "rad" or "rad/s"),
    readable at any width: at multiples of π/2 or π where ``pi`` and three multiples of π/2
    fit (θ of a wide window: :func:`pi_ticks`); else plain numbers, which in a window too
    narrow for plain ticks to tell apart (zooms: hi − lo below 1, or far from 0) are the
    offsets from a reference near the centre, in units with an SI prefix:
    "θ̇0 − 2.4149382176 [µrad/s]", ticks −0.4 … 0.4."""
    from matplotlib.ticker import MaxNLocator

    width, centre = hi - lo, 0.5 * (lo + hi)
    if pi and _pi_multiples(lo, hi, 0.5).size >= 3:
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


def critical_point_markers(ax, theta, is_saddle, tilted: bool = False,
                           on_map: bool = False) -> None:
    """Mark the critical points (θ [rad], 0) on the θ axis: attractors (2πk, 0) as black
    dots, saddles ((2j+1)π, 0) as open red circles (essay Figure 9), labelled for the
    legend; ``on_map``: over a basin map, where they must show on every basin colour, the
    dots ringed in white and the saddles open black circles filled white; ``tilted``: a
    pendulum with torque, whose rest states sit at θ* + 2πk, θ* = asin(τ/ω0²), and saddles
    at π − θ* + 2πk."""
    theta, is_saddle = np.asarray(theta, float), np.asarray(is_saddle, bool)
    if (~is_saddle).any():  # none in a narrow window: no legend entry for what is not there
        ax.plot(theta[~is_saddle], np.zeros((~is_saddle).sum()), "o", color="black",
                mec="white" if on_map else "black", ms=6 if on_map else 5, zorder=5,
                label="attractors (θ* + 2πk, 0)" if tilted else "attractors (2πk, 0)")
    if is_saddle.any():
        ax.plot(theta[is_saddle], np.zeros(is_saddle.sum()), "o",
                mfc="white" if on_map else "none", mec="black" if on_map else "red", mew=1.5,
                ms=7, zorder=5,
                label="saddles (π − θ* + 2πk, 0)" if tilted else "saddles ((2j+1)π, 0)")


def axes(ax, size: tuple[float, float]):
    """``ax``, or the Axes of a new pyplot figure of ``size`` [in] (pyplot manages it, as an
    interactive session expects; :func:`atlas.views.plotting.plot_atlas` draws
    into figures of its own)."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=size)[1]
