"""The look of every atlas figure, written once: the matplotlib style, the sizes, the colours
(wells, the running basin, separatrices, the limit cycle) and the axes' furniture (θ ticks at
multiples of π, titles naming the parameter point, critical-point markers).

The basin maps (:mod:`atlas.views.maps`), the parameter curves (:mod:`atlas.views.curves`),
the page (:mod:`atlas.views.page`) and ``atlas orbit``'s figure all draw with these.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STYLE", "MAP_SIZE", "CURVE_SIZE", "PNG_OPTIONS", "well_colour", "well_palette",
           "basin_colours", "attractor_colours", "WELL_CYCLE", "RUNNING_COLOR_HEX",
           "RUNNING_LINE_COLOR_HEX",
           "NO_LABEL_COLOR", "NEAR_BOUNDARY_COLOR", "T_TRAP_CMAP", "DISTANCE_CMAP",
           "colormap_table", "SEPARATRIX_COLOR", "SEPARATRIX_WIDTH", "SEPARATRIX_ALPHA",
           "SEPARATRIX_FAINT", "CYCLE_COLOR", "LABELLED_WELLS", "SADDLE_MARKER",
           "ATTRACTOR_MARKER", "ORBIT_START_MARKER", "pi_label", "pi_ticks", "point_title",
           "critical_point_markers", "axes", "window_ticks"]

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
#: Basin maps with more wells than this label each band "k = …" inside it: the palette
#: repeats every WELL_CYCLE wells on each side, and a band is best named, not matched.
LABELLED_WELLS = 16

# The basin palette (:func:`well_colour`), defined in Oklab (B. Ottosson, "A perceptual
# color space for image processing", 2020), whose lightness L (0 black … 1 white), chroma C
# and hue h [deg] are perceptually uniform enough to place colours by. The colour of a well
# is a function of k alone, the same in every figure and on the page, so that two figures can
# be compared by colour. With m = (|k| − 1) mod WELL_CYCLE:
# * hue by the sign of k (k > 0 warm, amber … orange … crimson; k < 0 cool, cyan … blue …
#   violet: the blue–yellow axis that red–green colour-blind readers keep), k = 0 green;
# * lightness by m mod 4: two light levels for odd |k| and two dark ones for even |k|
#   (_L_LEVELS: |k| = 1, 2, 3, 4 light, dark, less light, darkest), so that two neighbouring
#   wells k, k + 1, whose bands touch on every map, differ most in lightness, which every
#   reader sees (at least 27 CAM02-UCS units apart, also for a protanope), and so that the
#   four wells of each sign in the default map's −4 … 4 have four lightnesses: told apart by
#   a colour-blind reader too; the levels drift by _L_DRIFT every four wells;
# * hue by m mod 6: six places in the sign's hue range (_HUE_STEPS, fractions of the way from
#   its first to its last hue), in an order chosen so that the wells sharing a lightness
#   level (|k|, |k| + 4, |k| + 8) lie far apart in hue; ±k take the same place in their two
#   ranges and the same lightness: a pair.
# Within a cycle the pair (m mod 4, m mod 6) takes each of its 12 values once: no two wells
# of |k| ≤ WELL_CYCLE share a colour, and past WELL_CYCLE the sequence repeats (such maps
# name their bands). The levels, the hue order and the ranges were chosen by searching for
# the largest least distance between the wells of −4 … 4 (maps) and of −6 … 6 (lines), every
# pair of a figure distinct and neighbours far apart, for normal vision, deuteranopia and
# protanopia (the numbers below, rounded; tests/views/test_palette.py checks the distances
# that they reach). Each colour takes the largest chroma up to _CHROMA that sRGB
# can show at its L and h.
WELL_CYCLE = 12
# Oklab L of m mod 4 = 0 … 3, and its change every four wells
_L_LEVELS, _L_DRIFT = (0.917, 0.476, 0.695, 0.324), -0.036
_HUE_STEPS = (0.129, 0.139, 0.734, 0.244, 0.741, 0.559)    # m mod 6 = 0 … 5
_HUE_POSITIVE, _HUE_NEGATIVE = (89.1, -28.1), (189.7, 296.0)  # h [deg] at steps 0 and 1
_CHROMA = 0.120
_ZERO_LCH = (0.568, 0.15, 145.0)    # k = 0: green, between the light and the dark levels
_RUNNING_L = 0.556                  # the running basin: neutral grey
# Lines and markers on a white page (the curves, atlas orbit's certificate): the same hues
# and chroma at levels of their own (_LINE_LEVELS, drifting by _LINE_DRIFT every four wells,
# none lighter than 0.8), so that the light colours show as thin lines and the parity
# alternation remains; k = 0 and the running basin at lightnesses of their own.
_LINE_LEVELS, _LINE_DRIFT = (0.720, 0.317, 0.597, 0.202), 0.035
_ZERO_LINE_L, _RUNNING_LINE_L = 0.423, 0.444
#: Colour of "no certified label" (status unresolved or nonfinite) on every map, and of "no
#: value" (no t_trap, no distance) on the t_trap and distance maps: white.
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


def _well_lch(k: int, lines: bool) -> tuple[float, float, float]:
    """Oklab (L, C, h [deg]) of well k (the scheme above)."""
    if k == 0:
        return (_ZERO_LINE_L if lines else _ZERO_LCH[0]), *_ZERO_LCH[1:]
    m = (abs(k) - 1) % WELL_CYCLE              # 0 … WELL_CYCLE − 1
    levels, drift = (_LINE_LEVELS, _LINE_DRIFT) if lines else (_L_LEVELS, _L_DRIFT)
    lightness = levels[m % 4] + drift * (m // 4)
    first, last = _HUE_POSITIVE if k > 0 else _HUE_NEGATIVE
    hue = first + _HUE_STEPS[m % 6] * (last - first)
    return lightness, _CHROMA, hue


#: The palette's tables, computed once: ("zero", "positive", "negative") → "#rrggbb" of k = 0
#: and of k = ±1 … ±WELL_CYCLE, for maps (False) and for lines (True).
_TABLES = {lines: {"zero": _oklch_hex(*_well_lch(0, lines)),
                   "positive": [_oklch_hex(*_well_lch(j, lines))
                                for j in range(1, WELL_CYCLE + 1)],
                   "negative": [_oklch_hex(*_well_lch(-j, lines))
                                for j in range(1, WELL_CYCLE + 1)]}
           for lines in (False, True)}


def well_palette(lines: bool = False) -> dict:
    """The palette as tables, for the page (which looks a colour up as :func:`well_colour`
    does, never computing one): {"zero": "#rrggbb", "positive": [k = 1 … WELL_CYCLE],
    "negative": [k = −1 … −WELL_CYCLE], "cycle": WELL_CYCLE}."""
    table = _TABLES[lines]
    return {"zero": table["zero"], "positive": list(table["positive"]),
            "negative": list(table["negative"]), "cycle": WELL_CYCLE}


def well_colour(k: int, lines: bool = False) -> str:
    """The colour ("#rrggbb") of well k: a function of k alone, the same in every figure and
    on the page (module notes above: hue by sign, lightness alternating with the parity of k
    over four levels, repeating every WELL_CYCLE wells on each side). ``lines``: the same
    hues at line lightnesses, for
    thin lines and markers on a white page, where the light map colours would vanish."""
    k, table = int(k), _TABLES[lines]
    if k == 0:
        return table["zero"]
    return table["positive" if k > 0 else "negative"][(abs(k) - 1) % WELL_CYCLE]


def basin_colours(ks, running: bool = False, lines: bool = False) -> dict[int | str, str]:
    """The colour ("#rrggbb") of each well k in ``ks`` (:func:`well_colour`: the same
    whatever else the figure holds), of "none" (no certified label: white) and, with
    ``running``, of "running" (the running basin: neutral grey); ``lines`` as
    :func:`well_colour`. The maps, ``atlas orbit``'s figure, the curves and the page all
    take their colours from here."""
    colours: dict[int | str, str] = {int(k): well_colour(k, lines) for k in ks}
    if running:
        colours["running"] = RUNNING_LINE_COLOR_HEX if lines else RUNNING_COLOR_HEX
    colours["none"] = NO_LABEL_COLOR
    return colours


# The driven pendulum's attractors (:func:`attractor_colours`) are coloured by kind, from the
# same families, so that what a colour family means carries over from the wells: an
# oscillation (periodic, winding 0, as the rest state k = 0 it swings about) green, the first
# one the green of k = 0 and the next ones greens of other lightnesses; a rotation
# with winding > 0 the warm family and winding < 0 the cool one (the i-th of a sign the
# colour of well ±i, as a well's: neighbours far apart in lightness); a chaotic attractor
# greys of no hue (light, then dark, ...): no one orbit, no one hue.
_CHAOTIC_L = (0.80, 0.40, 0.62, 0.27)
# the second, third, ... oscillation's green (the first is k = 0's): dark first, so that
# mirror twins differ in lightness from each other and from the light rotations
_OSCILLATION_L = (0.33, 0.80, 0.45)


def attractor_colours(kinds, windings, lines: bool = False) -> list[str]:
    """The colour ("#rrggbb") of each attractor of a driven pendulum's point, from its
    ``kinds`` ("periodic" | "chaotic") and ``windings`` (net turns per period of the orbit),
    in their order (the scheme above): attractors that differ in kind (oscillation, rotation
    either way, chaotic) take colours of different families; ``lines`` as
    :func:`well_colour`."""
    seen = {"oscillation": 0, "forward": 0, "backward": 0, "chaotic": 0}
    out = []
    for kind, winding in zip(kinds, windings):
        family = ("chaotic" if str(kind) == "chaotic" else "oscillation" if int(winding) == 0
                  else "forward" if int(winding) > 0 else "backward")
        j = seen[family]
        seen[family] += 1
        if family == "forward":
            out.append(well_colour(j + 1, lines))
        elif family == "backward":
            out.append(well_colour(-(j + 1), lines))
        elif family == "oscillation":
            level = _OSCILLATION_L[(j - 1) % len(_OSCILLATION_L)]
            out.append(well_colour(0, lines) if j == 0 else
                       _oklch_hex(min(level, 0.72) if lines else level, *_ZERO_LCH[1:]))
        else:
            level = _CHAOTIC_L[j % len(_CHAOTIC_L)]
            out.append(_oklch_hex(min(level, 0.55) if lines else level, 0.0, 0.0))
    return out


#: The running basin's colour: a neutral grey, "#rrggbb" (and, darker, as a line).
RUNNING_COLOR_HEX = _oklch_hex(_RUNNING_L, 0.0, 0.0)
RUNNING_LINE_COLOR_HEX = _oklch_hex(_RUNNING_LINE_L, 0.0, 0.0)

#: The colour maps of the two continuous maps, the PNGs' and the page's alike: t_trap
#: (plasma) and the boundary distance (viridis), two perceptually uniform sequential maps of
#: matplotlib (van der Walt and Smith, 2015) that stay readable to colour-blind readers and
#: whose ends (dark blue-violet, yellow) are neither "no value" white nor the running grey;
#: two different maps, so that the two quantities are not read one for the other.
T_TRAP_CMAP, DISTANCE_CMAP = "plasma", "viridis"
#: The distance map's colour for a state closer than d_cert to a boundary (its label
#: certified for the RK4 map only): black, below the scale's dark end.
NEAR_BOUNDARY_COLOR = "#000000"


def colormap_table(name: str, n: int = 256) -> list[str]:
    """The matplotlib colour map ``name`` sampled at n equally spaced points, "#rrggbb" from
    its low end to its high end: what the page interpolates (linearly) so that its layers
    show the PNGs' colours."""
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    cmap = colormaps[name]
    return [to_hex(cmap(i / (n - 1))) for i in range(n)]


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
    """"α = 0.1 s⁻¹, ω0 = 1 rad/s" (and τ where the pendulum has a torque; A, Ω and a
    nonzero φ where it is driven); another model's point as "name = value" of each
    parameter."""
    if not {"alpha", "omega0"} <= set(point):
        return ", ".join(f"{name} = {value:g}" for name, value in point.items())
    text = f"α = {point['alpha']:g} s⁻¹, ω0 = {point['omega0']:g} rad/s"
    torque = point.get("torque", 0.0)
    text += f", τ = {torque:g} rad/s²" if torque else ""
    if "amplitude" in point:  # the driven pendulum: its drive A cos(Ω t + φ)
        text += f", A = {point['amplitude']:g} rad/s², Ω = {point['frequency']:g} rad/s"
        text += f", φ = {point['phase']:g} rad" if point.get("phase") else ""
    return text


#: The one look of a saddle in every figure and on the page (maps, ``atlas orbit``'s figure,
#: the essay's Figure 9): an open circle, black edge, white inside, so that it shows on every
#: basin colour and on a white page alike; matplotlib ``plot`` keywords (sizes in points).
SADDLE_MARKER = {"marker": "o", "ms": 7.0, "mfc": "white", "mec": "black", "mew": 1.5,
                 "ls": "none"}
#: The one look of an attractor (a rest state): a black dot ringed in white.
ATTRACTOR_MARKER = {"marker": "o", "ms": 6.0, "mfc": "black", "mec": "white", "mew": 1.0,
                    "ls": "none"}
#: The start of an orbit (its initial condition), in ``atlas orbit``'s figure and on the page:
#: a white square edged black, a shape of its own (an open circle is a saddle).
ORBIT_START_MARKER = {"marker": "s", "ms": 6.5, "mfc": "white", "mec": "black", "mew": 1.5,
                      "ls": "none"}


def critical_point_markers(ax, theta, is_saddle, tilted: bool = False) -> None:
    """Mark the critical points (θ [rad], 0) on the θ axis: attractors (2πk, 0) as
    ATTRACTOR_MARKER, saddles ((2j+1)π, 0) as SADDLE_MARKER (the same on a basin map and on
    a white page), labelled for the legend, drawn whole where they sit on the frame (the
    saddles ±3π of the default window: ``clip_on`` off); ``tilted``: a pendulum with torque,
    whose rest states sit at θ* + 2πk, θ* = asin(τ/ω0²), and saddles at π − θ* + 2πk."""
    theta, is_saddle = np.asarray(theta, float), np.asarray(is_saddle, bool)
    # unclipped, a marker outside fixed limits (a zoom far from θ̇ = 0) would be drawn there,
    # off the map: only those in the window (to rounding) are drawn where the limits are set
    shown = np.ones(theta.shape, bool)
    for axis, values in (("x", theta), ("y", np.zeros_like(theta))):
        if not getattr(ax, f"get_autoscale{axis}_on")():
            lo, hi = sorted(getattr(ax, f"get_{axis}lim")())
            shown &= (values >= lo - 1e-9 * (hi - lo)) & (values <= hi + 1e-9 * (hi - lo))
    for chosen, style, label in (
            (shown & ~is_saddle, ATTRACTOR_MARKER,
             "attractors (θ* + 2πk, 0)" if tilted else "attractors (2πk, 0)"),
            (shown & is_saddle, SADDLE_MARKER,
             "saddles (π − θ* + 2πk, 0)" if tilted else "saddles ((2j+1)π, 0)")):
        if chosen.any():  # none in a narrow window: no legend entry for what is not there
            ax.plot(theta[chosen], np.zeros(chosen.sum()), **style, zorder=5, clip_on=False,
                    label=label)


def axes(ax, size: tuple[float, float]):
    """``ax``, or the Axes of a new pyplot figure of ``size`` [in] (pyplot manages it, as an
    interactive session expects; :func:`atlas.views.plotting.plot_atlas` draws
    into figures of its own)."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=size)[1]
