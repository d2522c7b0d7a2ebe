"""The basin polygons held tightly (issue 43, 4): the area of each well's basin polygon in the
window (atlas.stability.polygons.window_basins, shapely) over the window's area equals the
exact fraction the exact boundaries store (curved polygons or quadrature, an independent
computation) to about the polylines' chord error, without torque, with torque and with a
negative one; the running basin's polygon is the rest of the window."""

from __future__ import annotations

import math

import pytest

from atlas.boundaries.basins import RUNNING_SIDE
from atlas.boundaries.exact import exact_boundaries
from atlas.physics.pendulum import Pendulum
from atlas.stability.polygons import basin_shape, window_basins

WINDOW = ((-5 * math.pi / 6, 7 * math.pi / 6), (-6.0, 6.0))


@pytest.mark.slow
@pytest.mark.parametrize("alpha, torque", [(0.1, 0.0), (0.05, 0.5), (0.05, -0.5),
                                           (0.2, 0.3), (0.2, -0.3)])
def test_polygon_areas_equal_the_exact_fractions(alpha, torque):
    b = exact_boundaries(Pendulum(alpha, 1.0, torque), WINDOW)
    shape = basin_shape(b)
    basins = window_basins(shape, WINDOW, b.areas.k, b.running_possible)
    (t0, t1), (v0, v1) = WINDOW
    area = (t1 - t0) * (v1 - v0)
    # a chord error e moves the polygon's edge by at most e along the boundaries inside the
    # window: the area by at most e × their length (and the exact fractions' own error)
    length = sum(g.boundary.length for k, g in basins.items() if k != RUNNING_SIDE)
    for k, exact, error in zip(b.areas.k.tolist(), b.areas.fraction, b.areas.error):
        got = basins[int(k)].area / area
        tolerance = (shape.chord_error * length) / area + error + 1e-12
        assert abs(got - exact) <= tolerance, (k, got, exact, tolerance)
        assert tolerance < 1e-6  # "to about the chord error": the check says something
    running = basins[RUNNING_SIDE].area / area
    assert running == pytest.approx(b.areas.running, abs=1e-6)
    assert (running > 0.05) == b.running_possible
