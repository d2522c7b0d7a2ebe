"""The parameter points a reader names: ``--point I`` (an index into the atlas's points) or
``--alpha A`` / ``--omega0 W`` / ``--torque T`` (the nearest stored value), for ``atlas plot``
and ``atlas info`` of a parameter atlas; and the parameters' symbols and units for the titles
and tables that name a point.

A value outside the atlas's range of that parameter is refused (an
:class:`~atlas.errors.AtlasError`, one line naming the option and the range), never moved to
the nearest end: the reader asked for a point the atlas does not hold. Inside the range the
nearest stored value is taken (the smaller of two equally near ones).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from atlas.errors import AtlasError
from atlas.layout import parameter_names, points

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["SYMBOLS", "UNITS", "choose_points", "point_index", "point_suffix", "swept",
           "value_text"]

#: Each parameter's symbol and unit in figures: name → (symbol, unit).
SYMBOLS = {"alpha": ("α", "s⁻¹"), "omega0": ("ω0", "rad/s"), "torque": ("τ", "rad/s²"),
           "amplitude": ("A", "rad/s²"), "frequency": ("Ω", "rad/s"), "phase": ("φ", "rad")}
#: Each parameter's unit in plain text (``atlas info``, messages): name → unit.
UNITS = {"alpha": "1/s", "omega0": "rad/s", "torque": "rad/s^2", "amplitude": "rad/s^2",
         "frequency": "rad/s", "phase": "rad"}
#: A value this close to the end of a range (relative to the range's scale) is inside it:
#: a value typed as printed (``%g``) is never refused for its last digit.
_RANGE_TOLERANCE = 1e-9


def swept(ds: xr.Dataset) -> list[str]:
    """The swept parameters of an atlas's root dataset (its parameter dims), in
    the order of its model's parameters."""
    return [name for name in parameter_names(ds) if name in ds.dims]


def value_text(name: str, value: float) -> str:
    """"α = 0.02 s⁻¹": one parameter's value with its symbol and unit (``%g``; another
    model's parameter by its name)."""
    symbol, unit = SYMBOLS.get(name, (name, ""))
    return f"{symbol} = {value:g} {unit}"


def point_index(ds: xr.Dataset, point: dict[str, float]) -> dict[str, int]:
    """The indices of ``point`` (a dict of :func:`atlas.layout.points`) along the swept dims
    of ``ds``: the ``index`` of :func:`atlas.views.coarsen.read_maps` and the map figures."""
    return {name: int(np.flatnonzero(ds[name].values == point[name])[0])
            for name in swept(ds)}


def point_suffix(ds: xr.Dataset, point: dict[str, float]) -> str:
    """"_alpha_0.5" (``_torque_0.16``, ``_alpha_0.1_omega0_1.5``): the swept parameters'
    values of ``point``, for the names of its figures; "" for an atlas of one point."""
    return "".join(f"_{name}_{point[name]:g}" for name in swept(ds))


def _nearest(ds: xr.Dataset, name: str, value: float) -> float:
    """The stored value of parameter ``name`` nearest ``value``; AtlasError where ``value``
    lies outside the atlas's range of it."""
    stored = np.atleast_1d(np.asarray(ds[name].values, float))
    lo, hi = float(stored.min()), float(stored.max())
    slack = _RANGE_TOLERANCE * max(abs(lo), abs(hi), hi - lo, 1e-300)
    if not (lo - slack <= value <= hi + slack):  # NaN too
        held = (f"one {name}, {lo:g}" if stored.size == 1 else
                f"{name} from {lo:g} to {hi:g} ({stored.size} values)")
        raise AtlasError(f"--{name} {value:g} is outside this atlas's range: it holds "
                         f"{held} [{UNITS[name]}]")
    return float(stored[np.argmin(np.abs(stored - value))])


def choose_points(ds: xr.Dataset, point: list[int] | None = None,
                  **values: list[float] | None) -> list[dict[str, float]] | None:
    """The parameter points of ``ds`` (an atlas's root dataset) that a reader chose, in the
    atlas's order (:func:`atlas.layout.points`), or None where nothing was chosen.

    ``point``: indices into the points (0 the first, −1 the last); ``values``: for ``alpha``,
    ``omega0``, ``torque``, values each taken to the nearest stored one (several per
    parameter allowed): the points whose parameters are among those chosen. Not both kinds
    at once. AtlasError (one line naming the option) for an index or a value the atlas does
    not hold."""
    asked = {name: list(v) for name, v in values.items() if v}
    unknown = sorted(set(asked) - set(parameter_names(ds)))
    if unknown:
        raise AtlasError(f"--{unknown[0]}: not a parameter of this atlas (its parameters: "
                         f"{', '.join(parameter_names(ds))}; --point I chooses any point)")
    if not point and not asked:
        return None
    every = points(ds)
    if point and asked:
        raise AtlasError("give --point, or --alpha/--omega0/--torque, not both")
    if point:
        bad = [i for i in point if not -len(every) <= i < len(every)]
        if bad:
            raise AtlasError(f"--point {bad[0]}: this atlas has {len(every)} parameter "
                             f"point{'s' if len(every) != 1 else ''}, numbered 0 to "
                             f"{len(every) - 1}")
        chosen = {i % len(every) for i in point}
    else:
        near = {name: {_nearest(ds, name, v) for v in given} for name, given in asked.items()}
        chosen = {i for i, p in enumerate(every)
                  if all(p[name] in wanted for name, wanted in near.items())}
    return [every[i] for i in sorted(chosen)]
