"""The shape of an atlas: its physical parameters, its grid of initial conditions, its tiles.

One data model serves a single atlas and a parameter atlas alike. Every physical parameter
(:data:`PARAMETERS`: α, ω0, τ) is a coordinate of the root group: a *scalar* coordinate
where the config gives one value, a *dimension* (leading, in the order of
:data:`PARAMETERS`) where it gives a list. A *parameter point* is one value of each; a single
atlas has one, a parameter atlas the product of its swept values. Readers never ask which
kind of atlas they hold: :func:`points` lists the points of any root dataset and
:func:`at_point` selects one (each point's dataset carries every parameter as a scalar
coordinate), and :func:`point_group` finds a point's node of a per-point group
(``/separatrices``, ``/critical_points``: one DataTree node per parameter point, the group
itself when the atlas has one point).

The grid (θ̇0 rows × θ0 columns) of each point is cut into tiles of whole rows; tile ``i``
is row band ``i % bands`` of the ``i // bands``-th point, points in C order over the swept
dims.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the readers only call the datasets' methods: no import at start-up
    import xarray as xr

__all__ = ["PARAMETERS", "Layout", "points", "at_point", "point_of", "first_point",
           "point_group", "point_nodes", "point_label", "node_name"]

#: The physical parameters: name → (units, long_name). Their order is the order of the
#: leading dims of a parameter atlas.
PARAMETERS = {
    "alpha": ("s-1", "damping constant"),
    "omega0": ("rad s-1", "natural angular frequency"),
    "torque": ("rad s-2", "constant torque per unit moment of inertia"),
}


@dataclass(frozen=True, eq=False)
class Layout:
    """Parameter values, grid axes and the row-band tiling of an atlas.

    ``parameters`` maps every name of :data:`PARAMETERS` to its values (1-D, one value where
    it is not swept); ``swept`` names the parameters that are dims, in :data:`PARAMETERS`
    order. A tile is one row band ``rows`` of one parameter point.
    """

    theta0: np.ndarray
    theta_dot0: np.ndarray
    parameters: dict
    swept: tuple
    rows_per_tile: int

    @property
    def parameter_shape(self) -> tuple[int, ...]:
        return tuple(self.parameters[name].size for name in self.swept)

    @property
    def n_params(self) -> int:
        return math.prod(self.parameter_shape)

    @property
    def bands(self) -> int:
        return -(-self.theta_dot0.size // self.rows_per_tile)

    @property
    def n_tiles(self) -> int:
        return self.n_params * self.bands

    @property
    def dims(self) -> tuple[str, ...]:
        """The basin map's dims: the swept parameters, then θ̇0 rows, θ0 columns."""
        return (*self.swept, "theta_dot0", "theta0")

    @property
    def chunk_rows(self) -> int:
        return min(self.rows_per_tile, self.theta_dot0.size)

    def point_index(self, p: int) -> tuple[int, ...]:
        """Index over the swept dims of the ``p``-th parameter point."""
        return tuple(int(i) for i in np.unravel_index(p, self.parameter_shape))

    def point(self, p: int) -> dict[str, float]:
        """Every parameter's value at the ``p``-th parameter point."""
        index = dict(zip(self.swept, self.point_index(p)))
        return {name: float(values[index.get(name, 0)])
                for name, values in self.parameters.items()}

    def tile(self, index: int) -> tuple[tuple[int, ...], slice]:
        """(index over the swept dims, row slice) of tile ``index``."""
        p, band = divmod(index, self.bands)
        rows = slice(band * self.rows_per_tile,
                     min((band + 1) * self.rows_per_tile, self.theta_dot0.size))
        return self.point_index(p), rows

    def coords(self) -> dict[str, tuple]:
        """The root group's coordinates: name → (dims, values, attrs); the swept parameters
        and the grid axes as dimension coordinates, the others as scalars."""
        out = {}
        for name, (units, long_name) in PARAMETERS.items():
            values = self.parameters[name]
            dims = (name,) if name in self.swept else ()
            out[name] = (dims, values if dims else values[0],
                         {"units": units, "long_name": long_name})
        out["theta_dot0"] = (("theta_dot0",), self.theta_dot0,
                             {"units": "rad s-1", "long_name": "initial angular velocity"})
        out["theta0"] = (("theta0",), self.theta0, {"units": "rad", "long_name": "initial angle"})
        return out

    def to_json(self) -> dict:
        return {"theta0": self.theta0.tolist(), "theta_dot0": self.theta_dot0.tolist(),
                "parameters": {k: v.tolist() for k, v in self.parameters.items()},
                "swept": list(self.swept), "rows_per_tile": self.rows_per_tile}

    @classmethod
    def from_json(cls, data: dict) -> Layout:
        parameters = {name: np.array(data["parameters"][name], np.float64)
                      for name in PARAMETERS}
        return cls(theta0=np.array(data["theta0"], np.float64),
                   theta_dot0=np.array(data["theta_dot0"], np.float64),
                   parameters=parameters, swept=tuple(data["swept"]),
                   rows_per_tile=int(data["rows_per_tile"]))


# --------------------------------------------------------------------------- reading

def _swept(ds: xr.Dataset) -> list[str]:
    return [name for name in PARAMETERS if name in ds.dims]


def points(ds: xr.Dataset) -> list[dict[str, float]]:
    """Every parameter point of an atlas's root dataset (C order over its swept dims), each
    as {parameter: value} of every parameter present."""
    swept = _swept(ds)
    fixed = {name: float(ds[name]) for name in PARAMETERS if name in ds.coords
             and name not in swept}
    out = []
    for values in itertools.product(*(ds[name].values for name in swept)):
        out.append({**{n: float(v) for n, v in zip(swept, values)}, **fixed})
    return [{name: p[name] for name in PARAMETERS if name in p} for p in out]


def at_point(ds: xr.Dataset, point: dict[str, float]) -> xr.Dataset:
    """The dataset of one parameter point: every swept dim selected (each parameter is then
    a scalar coordinate); ``ds`` itself for an atlas of one point."""
    index = {}
    for name in _swept(ds):
        hits = np.flatnonzero(ds[name].values == point[name])
        if hits.size == 0:
            raise KeyError(f"{name} = {point[name]:g} is not a point of this atlas")
        index[name] = int(hits[0])
    return ds.isel(index) if index else ds


def point_of(ds: xr.Dataset) -> dict[str, float]:
    """The parameter point of a one-point dataset (:func:`at_point`'s result, or the root of
    an atlas of one point): every parameter's scalar value."""
    return {name: float(ds[name]) for name in PARAMETERS if name in ds.coords}


def first_point(ds: xr.Dataset, **index) -> xr.Dataset:
    """One point of an atlas: index ``index[name]`` (default 0) along each swept dim."""
    return ds.isel({name: index.get(name, 0) for name in _swept(ds)})


def point_label(point: dict[str, float]) -> str:
    """"alpha = 0.1, omega0 = 1, torque = 0" (for messages and titles)."""
    return ", ".join(f"{name} = {value:g}" for name, value in point.items())


def node_name(layout: Layout, p: int) -> str:
    """The name of the ``p``-th point's node in a per-point group of a parameter atlas:
    the swept dims with the point's indices, e.g. ``alpha2_omega0_0``; "" (the group itself)
    for an atlas of one point."""
    return "_".join(f"{name}{i}" for name, i in zip(layout.swept, layout.point_index(p)))


def point_nodes(tree: xr.DataTree, group: str) -> list[xr.DataTree]:
    """The nodes of a per-point group that hold data (the group itself in an atlas of one
    point, its children in a parameter atlas); none if the group is absent."""
    if group not in tree.children:
        return []
    return [node for node in tree[group].subtree if node.has_data]


def point_group(tree: xr.DataTree, group: str, point: dict[str, float]) -> xr.Dataset | None:
    """The dataset of ``point`` in the per-point group ``group`` (its own variables and
    attributes; each node's attributes name its parameter point), or None if absent."""
    for node in point_nodes(tree, group):
        attrs = node.attrs
        if all(float(attrs.get(name, math.nan)) == value for name, value in point.items()):
            return node.to_dataset(inherit=False)
    return None
