"""The shape of an atlas: its physical parameters, its grid of initial conditions, its tiles.

One data model serves a single atlas and a parameter atlas alike, whatever its model
(:mod:`atlas.models`: the parameters and the grid's axes are the model's; the pendulum's are
α, ω0, τ and θ0, θ̇0). Every physical parameter is a coordinate of the root group: a *scalar*
coordinate where the config gives one value, a *dimension* (leading, in the order of the
model's parameters) where it gives a list. A *parameter point* is one value of each; a single
atlas has one, a parameter atlas the product of its swept values. Readers never ask which
kind of atlas they hold: :func:`points` lists the points of any root dataset and
:func:`at_point` selects one (each point's dataset carries every parameter as a scalar
coordinate), and :func:`point_group` finds a point's node of a per-point group
(``/separatrices``, ``/critical_points``: one DataTree node per parameter point, the group
itself when the atlas has one point).

The grid (the velocity axis along rows × the position axis along columns) of each point is
cut into tiles of whole rows; tile ``i`` is row band ``i % bands`` of the ``i // bands``-th
point, points in C order over the swept dims.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the readers only call the datasets' methods: no import at start-up
    import xarray as xr

from atlas.models.base import Model
from atlas.models.registry import DEFAULT as DEFAULT_MODEL
from atlas.models.registry import lookup, of_attrs

__all__ = ["Layout", "points", "at_point", "point_of", "first_point", "parameter_names",
           "point_group", "point_nodes", "point_label", "node_name", "per_point"]


@dataclass(frozen=True, eq=False)
class Layout:
    """Parameter values, grid axes and the row-band tiling of an atlas of ``model``.

    ``x0`` and ``v0`` are the grid's column and row values: the model's two axes, its
    initial positions and velocities (for the pendulum θ0 [rad] and θ̇0 [rad s⁻¹]).
    ``parameters`` maps every parameter of the model to its values (1-D, one value where it
    is not swept); ``swept`` names the parameters that are dims, in the model's order. A
    tile is one row band ``rows`` of one parameter point.
    """

    x0: np.ndarray
    v0: np.ndarray
    parameters: dict
    swept: tuple
    rows_per_tile: int
    model: Model = lookup(DEFAULT_MODEL)

    @property
    def parameter_shape(self) -> tuple[int, ...]:
        return tuple(self.parameters[name].size for name in self.swept)

    @property
    def n_params(self) -> int:
        return math.prod(self.parameter_shape)

    @property
    def bands(self) -> int:
        return -(-self.v0.size // self.rows_per_tile)

    @property
    def n_tiles(self) -> int:
        return self.n_params * self.bands

    @property
    def dims(self) -> tuple[str, ...]:
        """The basin map's dims: the swept parameters, then the rows (the model's velocity
        axis), the columns (its position axis)."""
        columns, rows = self.model.axes
        return (*self.swept, rows.name, columns.name)

    @property
    def chunk_rows(self) -> int:
        return min(self.rows_per_tile, self.v0.size)

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
                     min((band + 1) * self.rows_per_tile, self.v0.size))
        return self.point_index(p), rows

    def coords(self) -> dict[str, tuple]:
        """The root group's coordinates: name → (dims, values, attrs); the swept parameters
        and the grid axes as dimension coordinates, the others as scalars."""
        out = {}
        for name, (units, long_name) in self.model.parameters.items():
            values = self.parameters[name]
            dims = (name,) if name in self.swept else ()
            out[name] = (dims, values if dims else values[0],
                         {"units": units, "long_name": long_name})
        columns, rows = self.model.axes
        for axis, values in ((rows, self.v0), (columns, self.x0)):
            out[axis.name] = ((axis.name,), values,
                              {"units": axis.units, "long_name": axis.long_name})
        return out

    def to_json(self) -> dict:
        data = {"theta0": self.x0.tolist(), "theta_dot0": self.v0.tolist(),
                "parameters": {k: v.tolist() for k, v in self.parameters.items()},
                "swept": list(self.swept), "rows_per_tile": self.rows_per_tile}
        if self.model.name != DEFAULT_MODEL:  # the manifests of earlier runs stay valid
            data["model"] = self.model.name
        return data

    @classmethod
    def from_json(cls, data: dict) -> Layout:
        model = lookup(data.get("model", DEFAULT_MODEL))
        parameters = {name: np.array(data["parameters"][name], np.float64)
                      for name in model.parameters}
        return cls(x0=np.array(data["theta0"], np.float64),
                   v0=np.array(data["theta_dot0"], np.float64),
                   parameters=parameters, swept=tuple(data["swept"]),
                   rows_per_tile=int(data["rows_per_tile"]), model=model)


# --------------------------------------------------------------------------- reading

def parameter_names(ds: xr.Dataset) -> tuple[str, ...]:
    """The parameters of the model of ``ds`` (an atlas's dataset, or a one-point dataset of
    it: its ``model`` attribute, the pendulum's where absent), in the model's order."""
    return tuple(of_attrs(ds.attrs).parameters)


def _swept(ds: xr.Dataset) -> list[str]:
    return [name for name in parameter_names(ds) if name in ds.dims]


def points(ds: xr.Dataset) -> list[dict[str, float]]:
    """Every parameter point of an atlas's root dataset (C order over its swept dims), each
    as {parameter: value} of every parameter present."""
    names = parameter_names(ds)
    swept = _swept(ds)
    fixed = {name: float(ds[name]) for name in names if name in ds.coords
             and name not in swept}
    out = []
    for values in itertools.product(*(ds[name].values for name in swept)):
        out.append({**{n: float(v) for n, v in zip(swept, values)}, **fixed})
    return [{name: p[name] for name in names if name in p} for p in out]


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
    return {name: float(ds[name]) for name in parameter_names(ds) if name in ds.coords}


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


def per_point(layout: Layout, group: str, datasets: list[xr.Dataset | None]
              ) -> dict[str, xr.Dataset]:
    """The nodes of a per-point group to write (path → dataset): one per parameter point
    (None: the point has none), each with the point's parameters as attributes, named by
    :func:`node_name` (the group itself for an atlas of one point)."""
    out = {}
    for p, ds in enumerate(datasets):
        if ds is None:
            continue
        path = "/".join(filter(None, (group, node_name(layout, p))))
        out[path] = ds.assign_attrs(layout.point(p))
    return out


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
