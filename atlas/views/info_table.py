"""``atlas info`` of a parameter atlas: one compact table of basin k × parameter point.

Each column is a parameter point (``#i``, the index ``atlas info FILE --point I`` takes for
the point's detail), each row a basin: the exact area fraction of the window in the basin
of well k (``basin_fraction_exact``, from the exact basin boundaries, rounded to 6 decimals
for the table), the running basin as a row of its own where any point has one; then per
point the largest measured error of the grid counts (|grid count − exact| over the
basins), d_cert, the share of certified labels and the separatrices' check. Notes under the
table say what each number is and how exact it is. Wide atlases are cut into blocks of at
most MAX_COLUMNS points; a row empty in a block (no basin beyond its error) is left out.
Everything is read from the file; nothing is computed but the largest of stored errors.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from atlas.layout import at_point, point_group, points
from atlas.views.selectors import UNITS, swept

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["MAX_COLUMNS", "table_lines"]

#: The most points one block of the table shows side by side (about 90 characters).
MAX_COLUMNS = 8
_LABEL, _CELL = 16, 10  # widths of the row names and of a column


#: The cells that say nothing is there: no area, or none beyond the error estimate.
_EMPTY = ("-", "~0")


def _fraction(value: float, error: float) -> str:
    """An exact area fraction as the table shows it: 6 decimals; "-" for 0 (the basin does
    not meet the window), "~0" for a value within its error estimate ``error`` of 0 (the
    boundary curves' round-off), "n/c" for NaN (not computed), 2 significant digits below
    5e-7 (so that a thin basin is not shown as 0)."""
    if value != value:
        return "n/c"
    if value == 0.0:
        return "-"
    if abs(value) <= error:
        return "~0"
    return f"{value:.1e}" if value < 5e-7 else f"{value:.6f}"


def _separatrix_check(tree: xr.DataTree, point: dict) -> str:
    """The separatrices' check against the DOP853 stable manifold, in a word: "ok" (within
    the bound), "EXCEEDS", "n/m" (boundary shift not measured), "off" (not traced)."""
    sep = point_group(tree, "separatrices", point)
    if sep is None:
        return "off"
    disc = float(sep.attrs.get("discrepancy", math.nan))
    if disc != disc:
        return "n/m"
    return "ok" if disc <= float(sep.attrs["discrepancy_bound"]) else "EXCEEDS"


def _columns(tree: xr.DataTree) -> tuple[list[dict], dict[str, list[str]], float]:
    """Per point, its column's cells by row name; the rows in order; the largest error
    estimate of the exact fractions shown."""
    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    shown = (ds["basin_fraction_exact"] > 0) | (ds["basin_fraction"] > 0)
    ks = ds["k"].values[shown.any(dim=[d for d in shown.dims if d != "k"]).values]
    running = bool((ds["running_fraction_exact"] > 0).any() | (ds["running_fraction"] > 0).any())
    cells, worst = [], 0.0
    for point in every:
        at = at_point(ds, point)
        exact = at["basin_fraction_exact"].sel(k=ks).values
        error = at["basin_fraction_exact_error"].sel(k=ks).values
        measured = list(at["basin_fraction_grid_error"].sel(k=ks).values)
        column = {f"k = {int(k):+d}".replace("+0", "0"): _fraction(v, e)
                  for k, v, e in zip(ks, exact, error, strict=True)}
        errors = list(error)
        if running:
            column["running"] = _fraction(float(at["running_fraction_exact"]),
                                          float(at["running_fraction_exact_error"]))
            errors.append(float(at["running_fraction_exact_error"]))
            measured.append(abs(float(at["running_fraction"])
                                - float(at["running_fraction_exact"])))
        worst = max([worst, *(e for e in errors if e == e)])
        largest = max((m for m in measured if m == m), default=math.nan)
        d_cert = float(at["d_cert"])
        column |= {"|grid - exact|": "n/c" if largest != largest else f"{largest:.1e}",
                   "d_cert": "n/m" if d_cert != d_cert else f"{d_cert:.1e}",
                   "certified": f"{float(at['certified_fraction']):.2%}",
                   "separatrices": _separatrix_check(tree, point)}
        if float(at["side_mismatches"]):
            column["mismatches"] = f"{int(at['side_mismatches'])}"
        cells.append(column)
    rows = list(dict.fromkeys(name for column in cells for name in column))
    return cells, rows, worst


def table_lines(tree: xr.DataTree) -> list[str]:
    """The table of a parameter atlas (:mod:`atlas.views.info_table`), as lines: what the
    points share, the blocks of columns, the notes that say what each number is."""
    ds = tree.to_dataset(inherit=False)
    every = points(ds)
    names = swept(ds)
    cells, rows, worst = _columns(tree)
    fixed = [f"{name} = {value:g}" for name, value in every[0].items() if name not in names]
    lines = [f"pendulum  {', '.join(fixed)} at every point; "
             + ", ".join(f"{name} [{UNITS[name]}] over {ds.sizes[name]} values"
                         for name in names)
             + f": {len(every)} parameter points, #0 to #{len(every) - 1}",
             "basins    exact area fraction of the window in each basin (rows) at each "
             "parameter point (columns); what each row is: below the table"]
    blocks = math.ceil(len(every) / MAX_COLUMNS)
    width = math.ceil(len(every) / blocks)
    for start in range(0, len(every), width):
        block = range(start, min(start + width, len(every)))
        lines.append(f"{'point':<{_LABEL}}" + "".join(f"{'#' + str(i):>{_CELL}}"
                                                      for i in block))
        lines += [f"{f'{name} [{UNITS[name]}]':<{_LABEL}}"
                  + "".join(f"{every[i][name]:>{_CELL}g}" for i in block) for name in names]
        lines += [f"{row:<{_LABEL}}" + "".join(f"{cells[i].get(row, '-'):>{_CELL}}"
                                               for i in block)
                  for row in rows if any(cells[i].get(row, "-") not in _EMPTY
                                         for i in block)]
    lines += [
        "k = ..., running: exact area fraction of the window in the basin of well k (of the "
        "running limit cycle), from the exact basin boundaries, error <= "
        f"{worst:.0e}, shown to 6 decimals; -: the basin does not meet the window; ~0: "
        "within its error estimate of 0",
        "|grid - exact|: the largest measured error of the grid counts (fraction of the grid "
        "points labelled k, a count, not an area) over the basins of the point",
        "d_cert: labels farther than this from every basin boundary are certified for the "
        "exact equation (n/m: not measured); certified: that share of the grid's labels",
        "separatrices: traced basin boundaries vs the DOP853 stable manifold (ok: within "
        "the bound; off: not traced)"
        + ("; mismatches: labels beyond d_cert that disagree with the exact boundaries"
           if "mismatches" in rows else ""),
        "detail of one point (grid counts, errors, separatrices): atlas info FILE --point I, "
        f"or --{names[0]} {every[-1][names[0]]:g}",
    ]
    return lines
