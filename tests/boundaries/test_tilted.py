"""The exact basin boundaries of the pendulum with torque (atlas.boundaries.tilted) against
independent references.

References: scipy's DOP853 on θ̈ = τ − ω0² sin θ − 2αθ̇ in the actual coordinates (forward
time; orbits classified by the energy trap of a well or by running); the running limit cycle
of atlas.physics.running (which decides the topology); the kernels' attractor index (atlas.label);
brute-force distances; Monte-Carlo and grid estimates of the areas; the symmetries
θ → θ + 2π (well k → k + 1) and (θ, θ̇, τ) → (−θ, −θ̇, −τ) (well k → −k); and the published
basin stability of the bSTAB pendulum (Stender & Hoffmann, Nonlinear Dyn. 107, 1451–1468
(2022), doi:10.1007/s11071-021-06786-5).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import atlas
from atlas.boundaries.basins import RUNNING_SIDE
from atlas.boundaries.tilted import CHORD_TOL, CURVE_CHORD_TOL, TiltedBoundaries
from atlas.physics.pendulum import Pendulum
from atlas.physics.running import homoclinic_threshold, limit_cycle, running_barrier

TWO_PI = 2 * math.pi
BSTAB_WINDOW = ((-5 * math.pi / 6, 7 * math.pi / 6), (-10.0, 10.0))


def _window(p: Pendulum, speed: float):
    """The window θ ∈ [−π + θ*, π + θ*] (one well, between its saddles), θ̇ ∈ [−speed, speed]."""
    return ((-math.pi + p.rest_angle, math.pi + p.rest_angle), (-speed, speed))


#: (α, ω0, τ, window speed): the bSTAB pendulum (bistable), another bistable case, a case of
#: monostable wells (below the homoclinic torque: no running basin), and the bSTAB case
#: mirrored.
CASES = {
    "bstab": (0.05, 1.0, 0.5, 10.0),
    "bistable": (0.1, 1.0, 0.4, 6.0),
    "monostable": (0.1, 1.0, 0.1, 4.0),
    "reversed": (0.05, 1.0, -0.5, 10.0),
}


@pytest.fixture(scope="module")
def built():
    out = {}
    for name, (alpha, omega0, torque, speed) in CASES.items():
        p = Pendulum(alpha, omega0, torque)
        out[name] = TiltedBoundaries(p, *_window(p, speed))
    return out


def dop853_side(p: Pendulum, theta, theta_dot, t_end=400.0):
    """Reference basins: the orbits integrated by DOP853 (rtol 1e-11, all at once) to t_end;
    well k where the final state is in well k's energy trap (below the lower saddle energy,
    so it never leaves), running where θ̇ kept the sign of τ over the last 50 s, else None
    (unresolved)."""
    n = theta.size
    w2, a2, tau = p.omega0**2, 2 * p.alpha, p.torque

    def rhs(_, y):
        return np.concatenate([y[n:], tau - w2 * np.sin(y[:n]) - a2 * y[n:]])

    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([theta, theta_dot]), method="DOP853",
                    rtol=1e-11, atol=1e-11, t_eval=np.linspace(t_end - 50, t_end, 101))
    th, v = sol.y[:n], sol.y[n:]
    k = p.well(th[:, -1])
    trapped = p.energy(th[:, -1], v[:, -1], k) < p.saddle_energy
    running = np.all(np.sign(tau) * v > 0, axis=1)
    return [int(kk) if t else (RUNNING_SIDE if r else None)
            for kk, t, r in zip(k, trapped, running)]


def branch_points(tb: TiltedBoundaries, n: int, seed: int):
    """n random vertices of the branches in the window (not the saddles' neighbourhoods),
    with the unit normal there (the branch is an orbit: the normal of the vector field,
    turned as the neighbouring vertices run) and their saddle index."""
    rng = np.random.default_rng(seed)
    runs = [c for c in tb.curves() if c[2].size > 20]
    points = []
    for _ in range(n):
        j, _, theta, theta_dot = runs[rng.integers(len(runs))]
        i = rng.integers(5, theta.size - 5)
        p = tb.pendulum
        t = np.array([theta_dot[i], p.torque - p.omega0**2 * np.sin(theta[i])
                      - 2 * p.alpha * theta_dot[i]])
        t /= np.hypot(*t)
        t *= np.sign(t[0] * (theta[i + 1] - theta[i - 1])
                     + t[1] * (theta_dot[i + 1] - theta_dot[i - 1]))
        points.append((theta[i], theta_dot[i], -t[1], t[0], j))
    return np.array(points).T


# --------------------------------------------------------------------------- topology

@pytest.mark.parametrize("case", CASES)
def test_topology_agrees_with_the_limit_cycle(case, built):
    """A running basin exactly where a running limit cycle exists (above the homoclinic
    torque); the left branch folds (θ̇ changes sign) exactly then."""
    tb = built[case]
    alpha, omega0, torque, _ = CASES[case]
    cycle = limit_cycle(alpha, omega0, torque)
    assert tb.bistable == (cycle is not None)
    assert tb.bistable == (abs(torque) > homoclinic_threshold(alpha, omega0))
    arriving_up = "left" if torque > 0 else "right"  # the branch that arrives with θ̇·τ > 0
    for _, branch, _, theta_dot in tb.curves(clip=False):
        if branch == arriving_up:
            assert np.any(np.sign(torque) * theta_dot < 0) == tb.bistable


def test_monostable_case_has_no_running_basin(built):
    tb = built["monostable"]
    assert limit_cycle(0.1, 1.0, 0.1) is None and not tb.bistable
    theta = np.linspace(*tb.window[0], 200)
    speed = np.linspace(*tb.window[1], 200)
    assert not np.any(tb.side(theta[None, :], speed[:, None]) == RUNNING_SIDE)
    a = tb.areas()
    assert a.running == 0.0 and a.fraction.sum() == pytest.approx(1.0, abs=1e-12)


# --------------------------------------------------------------------------- the branches

@pytest.mark.parametrize("case", CASES)
def test_branches_end_at_their_saddles(case, built):
    tb = built[case]
    p = tb.pendulum
    seen = set()
    for j, branch, theta, theta_dot in tb.curves(clip=False):
        seen.add(branch)
        assert math.hypot(theta[0] - tb.saddle_theta(j), theta_dot[0]) < 1e-6
        # 'left' arrives from θ < saddle with θ̇ > 0, 'right' from θ > saddle with θ̇ < 0
        side = -1 if branch == "left" else 1
        assert np.all(side * (theta[1:50] - tb.saddle_theta(j)) > 0)
        assert np.all(side * theta_dot[1:50] < 0)
        assert tb.saddle_theta(j) == pytest.approx(
            math.pi - math.asin(p.torque / p.omega0**2) + TWO_PI * j)
    assert seen == {"left", "right"}
    assert 0 < tb.chord_error <= 1.1 * CHORD_TOL and 0 < tb.reference_error < 1e-8
    assert 0 < tb.curves_chord_error <= 1.1 * CURVE_CHORD_TOL


@pytest.mark.parametrize("case", ["bstab", "monostable", "reversed"])
def test_branches_are_orbits_into_the_saddle(case, built):
    """Points of the branches, integrated forward by DOP853, come within 1e-4 of their saddle
    (a point 1e-2 off the branch does not)."""
    tb = built[case]
    p = tb.pendulum
    theta, theta_dot, n0, n1, j = branch_points(tb, 5, seed=1)
    start = np.concatenate([theta, theta + 1e-2 * n0, theta_dot, theta_dot + 1e-2 * n1])
    m = start.size // 2
    w2, a2, tau = p.omega0**2, 2 * p.alpha, p.torque

    def rhs(_, y):
        return np.concatenate([y[m:], tau - w2 * np.sin(y[:m]) - a2 * y[m:]])

    sol = solve_ivp(rhs, (0.0, 100.0), start, method="DOP853", rtol=1e-12, atol=1e-12,
                    dense_output=True)
    y = sol.sol(np.linspace(0.0, 100.0, 10_001))
    saddle = np.tile([tb.saddle_theta(int(jj)) for jj in j], 2)
    closest = np.hypot(y[:m] - saddle[:, None], y[m:]).min(axis=1)
    assert np.all(closest[:5] < 1e-4) and np.all(closest[5:] > 1e-3)


# --------------------------------------------------------------------------- sides

def test_well_index_is_the_kernels_attractor(built):
    """Well k is the rest state (arcsin(τ/ω0²) + 2πk, 0): what atlas.label reports as
    ``attractor`` and side() returns, for both signs of τ."""
    for case in ("bstab", "reversed"):
        tb = built[case]
        p = tb.pendulum
        k = np.arange(-3, 4)
        theta = p.rest_angle + TWO_PI * k + 0.01
        res = atlas.label(theta, np.zeros(k.size), alpha=p.alpha, omega0=p.omega0,
                          torque=p.torque)
        np.testing.assert_array_equal(res.attractor, k)
        np.testing.assert_array_equal(tb.side(theta, np.zeros(k.size)), k)


@pytest.mark.parametrize("case", CASES)
def test_side_agrees_with_dop853(case, built):
    """Random points of the window, and points 2e-3 to 1e-2 off the branches on either side,
    all farther than 1e-3 from every boundary: side() is the basin DOP853 reaches."""
    tb = built[case]
    rng = np.random.default_rng(7)
    (a, b), (lo, hi) = tb.window
    theta, theta_dot = rng.uniform(a, b, 60), rng.uniform(lo, hi, 60)
    bt, bv, n0, n1, _ = branch_points(tb, 40, seed=3)
    off = rng.uniform(2e-3, 1e-2, bt.size) * rng.choice([-1, 1], bt.size)
    theta = np.concatenate([theta, bt + off * n0])
    theta_dot = np.concatenate([theta_dot, bv + off * n1])
    dist, _ = tb.distance(theta, theta_dot)
    keep = dist > 1e-3
    assert keep.sum() >= 90
    side = tb.side(theta[keep], theta_dot[keep])
    assert dop853_side(tb.pendulum, theta[keep], theta_dot[keep]) == side.tolist()
    assert len(set(side.tolist())) >= 3


def test_side_agrees_with_the_certified_kernel_labels(built):
    """Certified RK4 labels (energy trap, running barrier) of random bSTAB points farther
    than 1e-3 from the boundaries are the exact sides."""
    tb = built["bstab"]
    p = tb.pendulum
    rng = np.random.default_rng(11)
    (a, b), (lo, hi) = tb.window
    theta, theta_dot = rng.uniform(a, b, 3000), rng.uniform(lo, hi, 3000)
    far = tb.distance(theta, theta_dot)[0] > 1e-3
    theta, theta_dot = theta[far], theta_dot[far]
    res = atlas.label(theta, theta_dot, alpha=p.alpha, omega0=p.omega0, torque=p.torque,
                      running=running_barrier(p.alpha, p.omega0, p.torque, dt=0.01), dt=0.01)
    side = tb.side(theta, theta_dot)
    trapped, running = res.status == 0, res.status == 4
    assert trapped.sum() > 300 and running.sum() > 2000
    np.testing.assert_array_equal(res.attractor[trapped], side[trapped])
    assert np.all(side[running] == RUNNING_SIDE)


@pytest.mark.parametrize("case", CASES)
def test_shift_by_two_pi_is_the_next_well(case, built):
    tb = built[case]
    rng = np.random.default_rng(5)
    (a, b), (lo, hi) = tb.window
    theta, theta_dot = rng.uniform(a, b, 20_000), rng.uniform(lo, hi, 20_000)
    side = tb.side(theta, theta_dot)
    for turns in (1, -2):
        shifted = tb.side(theta + TWO_PI * turns, theta_dot)
        expected = np.where(side == RUNNING_SIDE, RUNNING_SIDE, side + turns)
        np.testing.assert_array_equal(shifted, expected)


def test_reversed_torque_mirrors_everything(built):
    """(θ, θ̇, τ) → (−θ, −θ̇, −τ): well k ↦ −k, the running basin to itself, distances and
    area fractions unchanged."""
    tb, mirror = built["bstab"], built["reversed"]
    rng = np.random.default_rng(9)
    (a, b), (lo, hi) = tb.window
    theta, theta_dot = rng.uniform(a, b, 20_000), rng.uniform(lo, hi, 20_000)
    side, side_m = tb.side(theta, theta_dot), mirror.side(-theta, -theta_dot)
    np.testing.assert_array_equal(side_m, np.where(side == RUNNING_SIDE, side, -side))
    d, j = tb.distance(theta[:1000], theta_dot[:1000])
    d_m, j_m = mirror.distance(-theta[:1000], -theta_dot[:1000])
    np.testing.assert_allclose(d_m, d, rtol=0, atol=1e-12)
    # the mirror of the saddle s_j = π − θ* + 2πj is −s_j, the reversed pendulum's s_{−j−1}
    np.testing.assert_array_equal(j_m, -j - 1)
    areas, areas_m = tb.areas(), mirror.areas()
    np.testing.assert_array_equal(areas_m.k, -areas.k[::-1])
    np.testing.assert_allclose(areas_m.fraction, areas.fraction[::-1], rtol=1e-12)
    assert areas_m.running == pytest.approx(areas.running, rel=1e-12)


def test_side_refuses_points_beyond_the_band(built):
    tb = built["bstab"]
    with pytest.raises(ValueError, match="band"):
        tb.side([0.0], [tb.band[0] - 1.0])


def test_refuses_untilted_and_runaway_pendulums():
    for torque in (0.0, 1.0, -1.5):
        with pytest.raises(ValueError, match="torque"):
            TiltedBoundaries(Pendulum(0.1, 1.0, torque), (-3, 3), (-3, 3))
    with pytest.raises(ValueError, match="alpha"):
        TiltedBoundaries(Pendulum(0.0, 1.0, 0.5), (-3, 3), (-3, 3))


# --------------------------------------------------------------------------- distances

@pytest.mark.parametrize("case", ["bstab", "monostable"])
@pytest.mark.parametrize("offset", [1e-2, 1e-4])
def test_distance_of_points_off_a_branch_along_its_normal(case, offset, built):
    """A point at distance d along a branch's normal is d from it (where no other branch
    comes nearer): exactly (the distance is to the branch's dense output, not to the
    chords searched, 1e-6 off), and names the branch's saddle."""
    tb = built[case]
    theta, theta_dot, n0, n1, j = branch_points(tb, 100, seed=2)
    checked = 0
    for sign in (1, -1):
        x, v = theta + sign * offset * n0, theta_dot + sign * offset * n1
        dist, saddle = tb.distance(x, v)
        mask = dist > offset - 1e-6  # no other branch nearer than d
        np.testing.assert_allclose(dist[mask], offset, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(saddle[mask], j[mask])
        checked += mask.sum()
    assert checked >= 150


def brute_distance(tb: TiltedBoundaries, theta, theta_dot, reach=1.0):
    """Distance to the branches' dense output, point by point, by an independent method:
    the nearest vertex of every translate's fine polyline (chord error ≤ 1e-8, every vertex
    a point of the branch) within ``reach`` of the point's θ, then scipy's bounded scalar
    minimisation of the distance over the reversed times of its two segments, and the
    straight pieces at the saddles."""
    from scipy.optimize import minimize_scalar

    from atlas.boundaries.segments import segment_distance

    f = tb.fundamental
    poly = f.polyline(CURVE_CHORD_TOL)
    out = []
    for px, py in zip(tb.sign * np.asarray(theta), tb.sign * np.asarray(theta_dot)):
        best = np.inf
        for i, xy in enumerate((poly.left, poly.right)):
            times, dense = poly.times[i], f.branches[i][0]
            for k in tb._translates(px - reach, px + reach):
                shift = 2 * np.pi * k
                best = min(best, float(segment_distance(
                    np.array([px]), np.array([py]), xy[0, 0] + shift, xy[1, 0],
                    xy[0, 1] + shift, xy[1, 1])[0]))
                d = np.hypot(xy[0, 1:] + shift - px, xy[1, 1:] - py)
                m = int(np.argmin(d))
                lo, hi = times[max(m - 1, 0)], times[min(m + 1, times.size - 1)]

                def gap(t, shift=shift, dense=dense, px=px, py=py):
                    x, v = dense(np.array([t]))
                    return math.hypot(x[0] + shift - px, v[0] - py)

                res = minimize_scalar(gap, bounds=(lo, hi), method="bounded",
                                      options={"xatol": 1e-14 * max(1.0, hi)})
                best = min(best, res.fun, d[m])
        out.append(best)
    return np.array(out)


@pytest.mark.parametrize("case", ["bstab", "reversed"])
def test_reference_error_is_the_distance_between_the_two_tolerances(case, built):
    """reference_error, the largest distance of the rtol 1e-12 branches' vertices from the
    1e-13 branches, is at least the distance scipy's bounded minimisation finds (over the
    offset from each vertex's own reversed time) for 100 sampled vertices, and of their
    order (the drift along the curve, ~1e-5, does not enter)."""
    from scipy.optimize import minimize_scalar

    tb = built[case]
    rng = np.random.default_rng(11)
    found = []
    for i, coarse in enumerate((tb._coarse.left, tb._coarse.right)):
        dense, sol, _ = tb.fundamental.branches[i]
        times, last = tb._coarse.times[i], sol.t[-1]
        for j in rng.choice(np.arange(coarse.shape[1] - 2), 50, replace=False):
            c, t = coarse[:, j + 1], min(times[j], last)

            def gap(u, c=c, t=t, dense=dense):
                return math.hypot(*(dense(np.array([t + u]))[:, 0] - c))

            found.append(minimize_scalar(gap, bounds=(-0.05, min(0.05, last - t)),
                                         method="bounded", options={"xatol": 1e-18}).fun)
    found = np.array(found)
    assert np.all(found <= tb.reference_error * (1 + 1e-6))
    assert 0 < tb.reference_error < 100 * found.max() and tb.reference_error < 1e-9


@pytest.mark.parametrize("case", ["bstab", "monostable", "reversed"])
def test_sides_between_a_chord_and_its_arc_are_the_branchs(case, built):
    """Points 1e-7 and 1e-9 off a branch, along its normal (inside the search chords' 1e-6
    of it, where the ray's parity over the chords can err), get the side of the points 1e-3
    off on the same side, and the two sides differ; the chords alone err for some of them
    (so the nearest point's side is what decides)."""
    tb = built[case]
    theta, theta_dot, n0, n1, _ = branch_points(tb, 200, seed=8)
    far = [tb.side(theta + s * 1e-3 * n0, theta_dot + s * 1e-3 * n1) for s in (1, -1)]
    keep = far[0] != far[1]  # not a tongue thinner than 2e-3 there
    assert keep.sum() > 150
    wrong = 0
    for offset in (1e-7, 1e-9):
        for s, expected in zip((1, -1), far):
            x, v = theta + s * offset * n0, theta_dot + s * offset * n1
            np.testing.assert_array_equal(tb.side(x, v)[keep], expected[keep])
            chords = tb._ray_sides(*tb._canonical(x, v))
            chords = np.where(chords == RUNNING_SIDE, chords, tb.sign * chords)
            wrong += int((chords[keep] != expected[keep]).sum())
    assert wrong > 0


@pytest.mark.parametrize("case", ["bstab", "monostable"])
def test_distance_equals_brute_force(case, built):
    """The pruned search of the chords, each arc within reach measured by Newton's method,
    equals the distance to the branches found by scipy's minimisation near the nearest
    vertex of every translate, for points in the middle of the window (whose nearest
    boundary passes through the window)."""
    tb = built[case]
    rng = np.random.default_rng(4)
    (a, b), (lo, hi) = tb.window
    theta, theta_dot = rng.uniform(a + 1, b - 1, 200), rng.uniform(lo + 1, hi - 1, 200)
    dist, _ = tb.distance(theta, theta_dot)
    near = dist < 1.0
    theta, theta_dot, dist = theta[near][:25], theta_dot[near][:25], dist[near][:25]
    np.testing.assert_allclose(dist, brute_distance(tb, theta, theta_dot), rtol=1e-9,
                               atol=1e-13)


@pytest.mark.parametrize("case", ["bstab", "reversed"])
def test_distance_rounds_are_one_search_of_every_boundary_within_reach(case, built,
                                                                         monkeypatch):
    """A grid of the window, a third of it farther than ``margin`` from every boundary: the
    points the window's index cannot answer are searched again on a wider one, from the
    distances found and skipping what was searched. The same doubles and saddles as one
    search of an index holding every boundary within θ ± 12 of the window, and for the
    farthest points the brute-force minimum."""
    tb = built[case]
    monkeypatch.setattr(tb, "_indices", {})
    (a, b), (lo, hi) = tb.window
    theta, theta_dot = (g.ravel() for g in np.meshgrid(np.linspace(a, b, 128),
                                                        np.linspace(lo, hi, 96)))
    dist, saddle = tb.distance(theta, theta_dot)
    assert len(tb._indices) == 2 and np.mean(dist > tb.margin) > 0.2  # a second round
    (ca, cb), _ = tb.canonical_window()
    wide = (ca - 12.0, cb + 12.0)
    monkeypatch.setattr(tb, "_indices", {wide: tb._segments(*wide)})
    one, one_saddle = tb.distance(theta, theta_dot)
    assert len(tb._indices) == 1 and dist.max() < 10.0  # one round
    np.testing.assert_array_equal(one, dist)
    np.testing.assert_array_equal(one_saddle, saddle)
    far = np.argsort(dist)[-8:]
    np.testing.assert_allclose(dist[far], brute_distance(tb, theta[far], theta_dot[far], 12.0),
                               rtol=1e-9, atol=1e-13)


def test_one_index_serves_every_query_in_the_window(built, monkeypatch):
    """Sides of a grid, of points 1e-3 off the branches, of points just beyond the window's
    θ range and of the axis θ = 0, and distances of those off the branches, all come from
    one index, the window's, built once; each equals what an index built for the query's own
    θ range (the segments within reach of its points) gives, bit for bit."""
    tb = built["bstab"]
    monkeypatch.setattr(tb, "_indices", {})
    (a, b), (lo, hi) = tb.window
    grid = np.meshgrid(np.linspace(a, b, 64), np.linspace(lo, hi, 48))
    theta, theta_dot, n0, n1, _ = branch_points(tb, 300, seed=6)
    off = (theta + 1e-3 * n0, theta_dot - 1e-3 * n1)
    queries = [grid, off, (np.full(20, b + 5e-3), np.linspace(lo, hi, 20)),
               (np.zeros(30), np.linspace(lo, hi, 30))]
    sides = [tb.side(*q) for q in queries]
    dist, saddle = tb.distance(*off)
    assert len(tb._indices) == 1
    assert len(set(np.concatenate([side.ravel() for side in sides]).tolist())) >= 5
    monkeypatch.setattr(tb, "_index", tb._segments)  # each query's own range
    for q, side in zip(queries, sides):
        np.testing.assert_array_equal(tb.side(*q), side)
    own_dist, own_saddle = tb.distance(*off)
    np.testing.assert_array_equal(own_dist, dist)
    np.testing.assert_array_equal(own_saddle, saddle)


@pytest.mark.parametrize("case", CASES)
def test_axis_speeds_are_the_crossings_of_the_clipped_curves(case, built):
    """axis_speeds (found on Γ_0, by bisection on the dense output) are the crossings of
    θ = 0 by the segments of curves()' clipped runs, each translate's fine polyline walked
    whole (chord error 1e-8: to 1e-7), and each lies on a branch (its distance to them,
    measured by Newton's method, below 1e-12)."""
    tb = built[case]
    speeds = []
    for _, _, theta, theta_dot in tb.curves(clip=True):
        s = np.sign(theta)
        for i in np.flatnonzero(s[:-1] * s[1:] < 0):
            f = theta[i] / (theta[i] - theta[i + 1])
            speeds.append(theta_dot[i] + f * (theta_dot[i + 1] - theta_dot[i]))
    assert len(speeds) >= 2
    found = tb.axis_speeds()
    np.testing.assert_allclose(np.sort(found), np.sort(speeds), rtol=0, atol=1e-7)
    dist, _ = tb.distance(np.zeros(found.size), found)
    assert dist.max() < 1e-12


@pytest.mark.parametrize("case", ["bstab", "reversed"])
@pytest.mark.parametrize("margin", [0.5, math.inf])
def test_vertices_within_a_box_are_the_branches_vertices_there(case, margin, built):
    """vertices_within (Γ_0 sorted by θ once, each translate a slice) gives the vertices of
    every unclipped branch (the search polylines, :meth:`branches`) in the box, with their
    saddles: the same points as masking each translate's whole polyline."""
    tb = built[case]
    (a, b), (lo, hi) = tb.window
    box = (a - margin, b + margin), (lo - margin, hi + margin)
    expected = []
    for j, _, vertices, _ in tb.branches():
        theta, theta_dot = vertices()
        keep = ((theta >= box[0][0]) & (theta <= box[0][1]) & (theta_dot >= box[1][0])
                & (theta_dot <= box[1][1]))
        expected.append(np.stack([theta[keep], theta_dot[keep], np.full(keep.sum(), j)]))
    expected = np.concatenate(expected, axis=1)
    got = np.stack(tb.vertices_within(*box))
    assert expected.shape[1] > 5_000

    def by_point(points):
        return points[:, np.lexsort(points)]

    np.testing.assert_array_equal(by_point(got), by_point(expected))


# --------------------------------------------------------------------------- areas

@pytest.mark.parametrize("case", CASES)
def test_areas_against_monte_carlo(case, built):
    """Exact fractions against side() on 2e5 uniform random points (no integration), within
    4 binomial standard errors; they sum to 1 with the running basin."""
    tb = built[case]
    areas = tb.areas()
    assert areas.fraction.sum() + areas.running == pytest.approx(1.0, abs=1e-12)
    assert np.all(areas.fraction > 0) and np.all(areas.error < 1e-8)
    n = 200_000
    rng = np.random.default_rng(13)
    (a, b), (lo, hi) = tb.window
    side = tb.side(rng.uniform(a, b, n), rng.uniform(lo, hi, n))
    fractions = dict(zip(areas.k.tolist(), areas.fraction.tolist()))
    if tb.bistable:
        fractions[RUNNING_SIDE] = areas.running
    assert set(np.unique(side).tolist()) <= set(fractions)
    for k, f in fractions.items():
        sigma = math.sqrt(f * (1 - f) / n)
        assert abs(np.mean(side == k) - f) <= 4 * sigma + 1e-12, k


@pytest.mark.parametrize("case", ["bstab", "bistable", "reversed"])
def test_areas_against_scipy_branches_clipped_by_shapely(case, built):
    """The tongues' areas, exact for the dense output, against an independent construction:
    both branches by scipy's DOP853 (rtol = atol = 1e-13) sampled at 2·10⁵ points each (chord
    error < 1e-10), each tongue closed along the band's bottom and clipped to the window by
    shapely; to 1e-9 of the window, and within the areas' own error plus that."""
    from shapely.geometry import Polygon, box

    tb = built[case]
    p = tb.pendulum
    sign = 1.0 if p.torque > 0 else -1.0
    tau = abs(p.torque)
    s = math.pi - math.asin(tau / p.omega0**2)
    e0, e1 = Pendulum(p.alpha, p.omega0, tau).saddle_stable_direction()
    bottom = min(tb._band)

    def back(_, y):
        return [-y[1], -(tau - p.omega0**2 * math.sin(y[0]) - 2 * p.alpha * y[1])]

    def below(_, y):
        return y[1] - bottom

    below.terminal = True
    parts = []
    for side in (-1, 1):
        start = [s + side * 1e-7 * e0, side * 1e-7 * e1]
        sol = solve_ivp(back, (0.0, 1e4), start, method="DOP853", rtol=1e-13, atol=1e-13,
                        dense_output=True, events=below)
        parts.append(sol.sol(np.linspace(0.0, sol.t[-1], 200_001)))
    (lt, lv), (rt, rv) = parts
    tongue = Polygon(np.column_stack([np.concatenate([lt[::-1], [s], rt]),
                                      np.concatenate([lv[::-1], [0.0], rv])]))
    assert tongue.is_valid
    (a, b), (lo, hi) = tb.window
    area = (b - a) * (hi - lo)
    areas = tb.areas()
    for k, fraction, error in zip(areas.k, areas.fraction, areas.error):
        # well k is canonical well sign·k, the tongue translated by 2π·sign·k: the window
        # (canonical) translated back instead
        canon_a, canon_b = sorted((sign * a, sign * b))
        canon_lo, canon_hi = sorted((sign * lo, sign * hi))
        back_by = 2 * math.pi * sign * k
        shape = box(canon_a - back_by, canon_lo, canon_b - back_by, canon_hi)
        reference = tongue.intersection(shape).area / area
        assert abs(fraction - reference) <= error + 1e-9, (k, fraction, reference)


@pytest.mark.parametrize("case", ["bstab", "monostable"])
def test_areas_against_grid_refinement(case, built):
    """Cell-centre counts on N×N grids converge to the exact fractions, at least at first
    order in the cell size (only cells cut by a boundary are miscounted): 16-fold smaller
    cells, a 16-fold smaller error."""
    tb = built[case]
    areas = tb.areas()
    exact = np.append(areas.fraction, areas.running)
    (a, b), (lo, hi) = tb.window
    errors = []
    for n in (100, 400, 1600):
        theta = a + (np.arange(n) + 0.5) * (b - a) / n
        theta_dot = lo + (np.arange(n) + 0.5) * (hi - lo) / n
        side = tb.side(theta[None, :], theta_dot[:, None])
        grid = np.array([np.mean(side == k) for k in areas.k] + [np.mean(side == RUNNING_SIDE)])
        errors.append(np.abs(grid - exact).max())
    assert errors[2] < errors[0] / 16 and errors[2] < 1e-4


def test_published_basin_stability_of_the_bstab_pendulum(built):
    """S_B(FP) = 0.152 with standard error 0.0036 (N = 10 000) for θ̈ = −0.1θ̇ + 0.5 − sin θ on
    θ ∈ [−π + asin 0.5, π + asin 0.5] × θ̇ ∈ [−10, 10] (Stender & Hoffmann, Nonlinear Dyn.
    107, 1451–1468 (2022), the pendulum case): the exact fraction of all wells lies within
    three standard errors, and is far more precise."""
    tb = built["bstab"]
    np.testing.assert_allclose(tb.window, BSTAB_WINDOW, rtol=1e-15)
    areas = tb.areas()
    assert abs(areas.fraction.sum() - 0.152) < 3 * 0.0036
    assert areas.error.sum() < 1e-7 and areas.running_error < 1e-7


@pytest.mark.parametrize("torque, published", [(0.16, 0.483), (0.36, 0.238), (0.56, 0.1279),
                                               (0.76, 0.0545), (0.96, 0.0071)])
def test_published_torque_sweep_of_the_bstab_pendulum(torque, published):
    """The T-sweep of the same paper (N = 10 000 per T, window fixed at the T = 0.5 one):
    every fourth entry, within three binomial standard errors √(S(1 − S)/10⁴)."""
    tb = TiltedBoundaries(Pendulum(0.05, 1.0, torque), *BSTAB_WINDOW)
    assert tb.bistable
    sigma = math.sqrt(published * (1 - published) / 1e4)
    assert abs(tb.areas().fraction.sum() - published) < 3 * sigma


@pytest.mark.parametrize("half", [1e-2, 1e-3, 1e-4])
def test_a_small_window_inside_one_basin_is_all_of_it_within_the_stated_error(half):
    """A window of half-width ``half`` around the rest state lies wholly in well 0's basin:
    its fraction is exactly 1 and the running basin's 0. The computed ones differ from that
    by the rounding of the coordinates at the window's scale (about eps·|θ|/half), which the
    fine and coarse curves share: the stated errors must cover it."""
    p = Pendulum(0.1, 1.0, 0.5)
    c = p.rest_angle
    areas = TiltedBoundaries(p, (c - half, c + half), (-half, half)).areas()
    assert list(areas.k) == [0]
    assert abs(areas.fraction[0] - 1.0) <= areas.error[0]
    assert abs(areas.running) <= areas.running_error
    assert areas.error[0] < 1e-12 / half  # a bound, not a shrug: ~16 eps·|θ + 2πk| / half
