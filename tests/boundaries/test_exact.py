"""The exact boundaries' one interface (atlas.boundaries.exact): the factory picks the right
implementation for every torque, and each implementation keeps the interface's invariants.

Invariants: the area fractions lie in [0, 1] and, with the running basin's, sum to 1 (the
basins tile the window) to their stated errors; distances are ≥ 0 and no boundary is nearer
than the distance said (the side is constant within it); the points just either side of a
boundary traced on the RK4 map's labels (atlas.boundaries.trace) lie on the two basins the
trace says, and the traced points lie on the exact boundaries to the measured shift; the
saddles near a point include the nearest boundary's; a certifier sent to a worker (pickled)
answers the same.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from atlas.boundaries.bisection import field_normal
from atlas.boundaries.certificate import Certifier, NoBoundaries, certifier_for
from atlas.boundaries.exact import (
    RUNNING_SIDE,
    ExactBoundaries,
    TiltedExact,
    UnboundedExact,
    UntiltedExact,
    exact_boundaries,
)
from atlas.boundaries.trace import trace
from atlas.physics.pendulum import Pendulum
from atlas.physics.running import running_barrier

PI = math.pi
#: name: (α, ω0, τ, window); the windows hold several boundaries each.
CASES = {
    "untilted": (0.1, 1.0, 0.0, ((-2.0 * PI, 2.0 * PI), (-3.0, 3.0))),
    "bistable": (0.05, 1.0, 0.5, ((-5 * PI / 6, 7 * PI / 6), (-4.0, 4.0))),
    "monostable": (0.1, 1.0, 0.1, ((-PI, PI), (-3.0, 3.0))),
    "reversed": (0.05, 1.0, -0.5, ((-7 * PI / 6, 5 * PI / 6), (-4.0, 4.0))),
}
BOUNDED = list(CASES)


@pytest.fixture(scope="module")
def built():
    return {name: exact_boundaries(Pendulum(a, w, t), window)
            for name, (a, w, t, window) in CASES.items()}


@pytest.mark.parametrize("torque, kind", [(0.0, UntiltedExact), (0.5, TiltedExact),
                                          (-0.5, TiltedExact), (0.9, TiltedExact),
                                          (1.5, UnboundedExact), (-4.0, UnboundedExact)])
def test_the_factory_picks_the_implementation_by_torque(torque, kind):
    window = ((-PI, PI), (-2.0, 2.0))
    exact = exact_boundaries(Pendulum(0.1, 1.0, torque), window)
    assert type(exact) is kind
    assert isinstance(exact, ExactBoundaries)  # the interface, all of it
    assert exact.window == window and exact.pendulum.torque == torque


def test_the_saddle_node_has_no_certified_boundaries():
    with pytest.raises(ValueError, match="saddle-node"):
        exact_boundaries(Pendulum(0.1, 1.0, 1.0), ((-PI, PI), (-2.0, 2.0)))


@pytest.mark.parametrize("name", BOUNDED)
def test_the_basins_tile_the_window(name, built):
    """Area fractions in [0, 1], summing with the running basin's to 1 within their errors;
    the running basin exists exactly where the interface says it may."""
    exact = built[name]
    a = exact.areas
    assert a.k.dtype == np.int64 and np.all(np.diff(a.k) > 0)
    assert np.all((a.fraction >= 0) & (a.fraction <= 1)) and 0 <= a.running <= 1
    assert np.all(a.error >= 0) and a.running_error >= 0
    total = float(a.fraction.sum()) + a.running
    assert abs(total - 1.0) <= float(a.error.sum()) + a.running_error + 1e-12
    assert (a.running > 0) == exact.running_possible
    assert 0.0 <= exact.reference_error < 1e-8


@pytest.mark.parametrize("name", BOUNDED)
def test_no_boundary_is_nearer_than_the_distance(name, built):
    """Distances are ≥ 0; every point within 0.9·d of a point at distance d lies on its side
    (no boundary crosses the ball), and the saddles near a point with radius d include the
    nearest boundary's."""
    exact = built[name]
    (t0, t1), (v0, v1) = exact.window
    rng = np.random.default_rng(7)
    theta, theta_dot = rng.uniform(t0, t1, 400), rng.uniform(v0, v1, 400)
    dist, n = exact.distance(theta, theta_dot)
    side = exact.side(theta, theta_dot)
    assert side.shape == theta.shape and side.dtype == np.int64
    assert np.all(dist >= 0) and np.all(np.isfinite(dist)) and np.all(n % 2 == 1)
    angle = rng.uniform(0, 2 * PI, theta.size)
    step = 0.9 * dist
    mx, mv = theta + step * np.cos(angle), theta_dot + step * np.sin(angle)
    # sides are asked of points in the window
    check = (dist > 10 * exact.reference_error) & (mx > t0) & (mx < t1) & (mv > v0) & (mv < v1)
    assert check.sum() > 200
    np.testing.assert_array_equal(exact.side(mx, mv)[check], side[check])
    near = dist <= 0.5
    lo, hi = exact.saddles_within(theta[near], theta_dot[near], 0.5)
    assert near.sum() > 100 and np.all((lo <= n[near]) & (n[near] <= hi))


@pytest.fixture(scope="module")
def traced(built):
    """Each bounded case traced on the RK4 map's labels, on its own exact boundaries (coarse
    vertices, tol 1e-10: the invariants, not the accuracy, are tested here)."""
    out = {}
    for name in BOUNDED:
        exact = built[name]
        p = exact.pendulum
        cycle = getattr(getattr(exact, "tilted", None), "cycle", None)
        barrier = (running_barrier(p.alpha, p.omega0, p.torque, cycle, dt=0.01)
                   if cycle is not None else None)
        out[name] = trace(p, *exact.window, tol=1e-10, max_spacing=0.25, exact=exact,
                          barrier=barrier)
    return out


@pytest.mark.parametrize("name", BOUNDED)
def test_the_sides_of_a_traced_boundary_are_its_two_basins(name, built, traced):
    """Just below and above every traced point (along the normal of the vector field, 1e-6
    away: far beyond the RK4 map's shift) the exact sides differ; without torque they are the
    wells (n − 1)/2 and (n + 1)/2 of the saddle nπ. The traced points lie within the measured
    shift of the exact boundaries, which the interface names by the same saddles."""
    exact, sep = built[name], traced[name]
    p = exact.pendulum
    (t0, t1), (v0, v1) = exact.window
    assert sep.sizes["point"] > 20 and sep.attrs["discrepancy"] < 1e-8
    inside = ((sep["theta"] >= t0) & (sep["theta"] <= t1) & (sep["theta_dot"] >= v0)
              & (sep["theta_dot"] <= v1)).values  # sides are asked of points in the window
    sep = sep.isel(point=inside)
    theta, theta_dot = sep["theta"].values, sep["theta_dot"].values
    n0, n1 = field_normal(p, theta, theta_dot)
    below = exact.side(theta - 1e-6 * n0, theta_dot - 1e-6 * n1)
    above = exact.side(theta + 1e-6 * n0, theta_dot + 1e-6 * n1)
    assert np.all(below != above)
    if p.torque == 0.0:
        n = sep["saddle_n"].values
        np.testing.assert_array_equal(below, (n - 1) // 2)
        np.testing.assert_array_equal(above, (n + 1) // 2)
    else:
        wells = np.concatenate([below, above])
        assert np.all((wells == RUNNING_SIDE) | (np.abs(wells) < 10))
        assert (np.any(wells == RUNNING_SIDE)) == exact.running_possible
    dist, n_near = exact.distance(theta, theta_dot)
    assert dist.max() <= sep.attrs["discrepancy"] + exact.reference_error + 1e-12
    np.testing.assert_array_equal(n_near, sep["saddle_n"].values)


def test_without_rest_states_there_is_nothing_to_trace_and_all_runs():
    p = Pendulum(0.1, 1.0, 1.5)
    window = ((-PI, PI), (-2.0, 2.0))
    exact = exact_boundaries(p, window)
    theta, theta_dot = np.meshgrid(np.linspace(-PI, PI, 5), np.linspace(-2, 2, 3))
    assert np.all(exact.side(theta, theta_dot) == RUNNING_SIDE)
    dist, n = exact.distance(theta, theta_dot)
    assert dist.shape == theta.shape and np.all(np.isinf(dist)) and np.all(n == 0)
    lo, hi = exact.saddles_within(theta, theta_dot, 1.0)
    assert np.all(lo == 0) and np.all(hi == 0)
    assert exact.areas.running == 1.0 and exact.areas.k.size == 0
    assert exact.reference_error == 0.0 and exact.running_possible
    assert trace(p, *window) is None
    assert isinstance(certifier_for(p, np.linspace(-PI, PI, 5), np.linspace(-2, 2, 3),
                                    math.nan, math.nan, exact), NoBoundaries)


@pytest.mark.parametrize("name", BOUNDED)
def test_a_certifier_on_the_interface_pickles_and_answers_the_same(name, built):
    """The pipeline builds the exact boundaries once and hands them to the certifier, which
    is sent to Dask workers: pickled without its search indices, it answers the same."""
    exact = built[name]
    (t0, t1), (v0, v1) = exact.window
    cert = certifier_for(exact.pendulum, np.linspace(t0, t1, 9), np.linspace(v0, v1, 7),
                         1e-9, 1e-12, exact)
    assert isinstance(cert, Certifier) and cert.exact is exact
    again = pickle.loads(pickle.dumps(cert))
    theta, theta_dot = np.meshgrid(cert.theta0, cert.theta_dot0)
    for a, b in zip(cert.distance(theta, theta_dot), again.distance(theta, theta_dot)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(cert.exact.side(theta, theta_dot),
                                  again.exact.side(theta, theta_dot))
