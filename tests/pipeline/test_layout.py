"""The one data model (atlas.layout): the same readers for a single atlas and a parameter
atlas, and a README whose module map matches the package."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from atlas.layout import Layout, at_point, first_point, node_name, points
from atlas.models.pendulum.description import PARAMETERS

REPO = Path(__file__).resolve().parents[2]


def _layout(swept: dict) -> Layout:
    parameters = {name: np.array(swept.get(name, [default]), np.float64)
                  for name, default in zip(PARAMETERS, (0.1, 1.0, 0.0))}
    return Layout(x0=np.linspace(-1, 1, 5), v0=np.linspace(-2, 2, 7),
                  parameters=parameters, swept=tuple(n for n in PARAMETERS if n in swept),
                  rows_per_tile=3)


def _dataset(layout: Layout) -> xr.Dataset:
    shape = (*layout.parameter_shape, layout.v0.size, layout.x0.size)
    values = np.arange(np.prod(shape), dtype=float).reshape(shape)
    return xr.Dataset({"x": (layout.dims, values)},
                      coords={n: (d, v, a) for n, (d, v, a) in layout.coords().items()})


@pytest.mark.parametrize("swept", [{}, {"alpha": [0.1, 0.2]},
                                   {"omega0": [1.0, 2.0], "torque": [0.0, 0.3, 0.6]}])
def test_points_and_tiles_agree_for_every_kind_of_atlas(swept):
    """The tile order, the points of a dataset and their selection agree, with one code
    path whatever is swept: each tile's block of the dataset is its point's block."""
    layout = _layout(swept)
    ds = _dataset(layout)
    listed = points(ds)
    assert len(listed) == layout.n_params and layout.n_tiles == layout.n_params * 3
    assert [layout.point(p) for p in range(layout.n_params)] == listed
    for index in range(layout.n_tiles):
        params, rows = layout.tile(index)
        point = layout.point(index // layout.bands)
        one = at_point(ds, point)
        assert one["x"].dims == ("theta_dot0", "theta0")
        assert {n: float(one[n]) for n in PARAMETERS} == point
        np.testing.assert_array_equal(one["x"].values[rows], ds["x"].values[params][rows])
    assert first_point(ds)["x"].shape == (7, 5)
    names = {node_name(layout, p) for p in range(layout.n_params)}
    assert len(names) == layout.n_params  # one node per point ("" = the group itself)
    assert names == {""} if not swept else "" not in names


def test_a_point_not_in_the_atlas_is_named():
    ds = _dataset(_layout({"alpha": [0.1, 0.2]}))
    with pytest.raises(KeyError, match="alpha = 0.3"):
        at_point(ds, {"alpha": 0.3, "omega0": 1.0, "torque": 0.0})


def test_layout_round_trips_through_json():
    layout = _layout({"omega0": [1.0, 2.0], "torque": [0.0, 0.5]})
    again = Layout.from_json(layout.to_json())
    assert again.swept == layout.swept and again.to_json() == layout.to_json()
