"""The shooting kernel's pieces (atlas.kernels.shooting) against independent computations:
the tangent it carries is the RK4 map's Jacobian (a complex-step derivative of a plain RK4
step), its bound β holds the true image of a segment (the segment's points integrated one
by one), and the cones its saddle box certifies are mapped as the certificate assumes
(sampled in the box)."""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest

from atlas.boundaries.shooting import saddle_box
from atlas.kernels.shooting import LANES, _advance
from atlas.physics.pendulum import Pendulum

DT = 0.01


def rk4(x, v, alpha, omega0, torque, dt=DT, sin=math.sin):
    """One classical RK4 step of θ̈ = τ − ω0² sin θ − 2αθ̇, written out (no atlas code)."""
    def f(a, b):
        return b, torque - omega0**2 * sin(a) - 2.0 * alpha * b

    k1 = f(x, v)
    k2 = f(x + 0.5 * dt * k1[0], v + 0.5 * dt * k1[1])
    k3 = f(x + 0.5 * dt * k2[0], v + 0.5 * dt * k2[1])
    k4 = f(x + dt * k3[0], v + dt * k3[1])
    return (x + dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
            v + dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]))


@pytest.mark.parametrize("torque", [0.0, 0.5, -0.8])
def test_the_tangent_is_the_jacobian_of_the_rk4_step(torque):
    """(yθ, yθ̇) after one step of the kernel's _advance = DF·(yθ, yθ̇), DF by the complex
    step Im F(x + i·h·y)/h (exact to rounding, no cancellation), for 32 lanes of random
    states and directions; the state itself is the plain RK4 step's."""
    rng = np.random.default_rng(3)
    x, v = rng.uniform(-7, 7, LANES), rng.uniform(-4, 4, LANES)
    yt, yv = rng.normal(size=(2, LANES))
    th, speed, tt, tv = x.copy(), v.copy(), yt.copy(), yv.copy()
    _advance(th, speed, tt, tv, *_lanes(*[0.0] * 4), *_lanes(*[0.0] * 10), 0.0, 1.0, 0.05,
             1.1, torque, DT)
    h = 1e-30
    for lane in range(LANES):
        fx, fv = rk4(complex(x[lane], h * yt[lane]), complex(v[lane], h * yv[lane]), 0.05,
                     1.1, torque, sin=cmath.sin)
        np.testing.assert_allclose([tt[lane], tv[lane]], [fx.imag / h, fv.imag / h],
                                   rtol=1e-13, atol=1e-15 * math.hypot(yt[lane], yv[lane]))
        np.testing.assert_allclose([th[lane], speed[lane]],
                                   rk4(x[lane], v[lane], 0.05, 1.1, torque), rtol=0,
                                   atol=1e-14)


@pytest.mark.parametrize("torque,omega0,alpha", [(0.0, 1.0, 0.05), (0.5, 1.3, 0.1),
                                                (-0.2, 0.7, 1.5)])
def test_step_norm_bounds_the_jacobian_of_a_step(torque, omega0, alpha):
    """step_norm, from the weighted mean of cos θ at a step's stages, is at least ‖DF‖_W of
    that step (the Jacobian by complex steps along both axes, then its largest singular
    value in |·|_W), at 300 random states; and not loosely: within dt·ω0 plus the part
    that does not follow the orbit."""
    from atlas.kernels.shooting import step_norm

    p = Pendulum(alpha, omega0, torque)
    box = saddle_box(p, DT)
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(300):
        x, v = rng.uniform(-7, 7), rng.uniform(-6, 6)
        columns = []
        for e in ((1.0, 0.0), (0.0, 1.0)):
            fx, fv = rk4(complex(x, 1e-30 * e[0]), complex(v, 1e-30 * e[1]), alpha, omega0,
                         torque, sin=cmath.sin)
            columns.append((fx.imag / 1e-30, fv.imag / 1e-30))
        jac = np.array(columns).T
        weight = np.diag([omega0, 1.0])
        exact = np.linalg.norm(weight @ jac @ np.linalg.inv(weight), 2)
        k1 = v, torque - omega0**2 * math.sin(x) - 2 * alpha * v
        stages = [x, x + 0.5 * DT * k1[0]]
        k2v = v + 0.5 * DT * k1[1]
        k2 = k2v, torque - omega0**2 * math.sin(stages[1]) - 2 * alpha * k2v
        stages.append(x + 0.5 * DT * k2[0])
        k3v = v + 0.5 * DT * k2[1]
        k3 = k3v, torque - omega0**2 * math.sin(stages[2]) - 2 * alpha * k3v
        stages.append(x + DT * k3[0])
        cos = np.cos(stages)
        bound = step_norm((cos[0] + 2 * cos[1] + 2 * cos[2] + cos[3]) / 6, omega0, DT,
                          box.step_base)
        assert bound >= exact, (x, v, bound, exact)
        worst = max(worst, bound - exact)
    assert worst < DT * omega0 + (box.step_base - 1.0)


def _lanes(*values):
    return [np.full(LANES, float(value)) for value in values]


@pytest.mark.parametrize("torque,omega0", [(0.0, 1.0), (0.5, 1.0), (0.3, 1.3)])
def test_beta_holds_the_true_image_of_a_segment(torque, omega0):
    """A segment wide enough (w = 3e-3) for its image to bend visibly: after every 50 of
    300 steps of _advance, each of 41 points c + σ·w·d, integrated on its own by the plain RK4
    step, lies within β (in |v|_W = √(ω0²vθ² + vθ̇²)) of the line x + σ·w·y; and the bend is
    there (a few % of β at the least), so a β without its quadratic term would fail."""
    p = Pendulum(0.05, omega0, torque)
    box = saddle_box(p, DT)
    c, d, w = (2.0, 1.0), (0.6, 0.8), 3e-3
    th, v, yt, yv = _lanes(c[0], c[1], d[0], d[1])
    beta, drift, pull, width = _lanes(0.0, 0.0, 0.0, w)
    scratch = _lanes(*[0.0] * 10)
    sigma = np.linspace(-1.0, 1.0, 41)
    points = [(c[0] + s * w * d[0], c[1] + s * w * d[1]) for s in sigma]
    largest = 0.0
    for step in range(1, 301):
        _advance(th, v, yt, yv, beta, drift, pull, width, *scratch, 0.5 * box.curvature_w,
                 box.step_base, p.alpha, p.omega0, p.torque, DT)
        points = [rk4(x, u, p.alpha, p.omega0, p.torque) for x, u in points]
        if step % 50 == 0:
            line = np.array([(th[0] + s * w * yt[0], v[0] + s * w * yv[0]) for s in sigma])
            gap = np.array(points) - line
            off = np.hypot(omega0 * gap[:, 0], gap[:, 1]).max()
            assert off <= beta[0] + 1e-13, (step, off, beta[0])
            largest = max(largest, off / beta[0])
    assert largest > 0.02


@pytest.mark.parametrize("torque", [0.0, 0.5])
@pytest.mark.parametrize("r", [1e-3, 1e-2, 0.05])
def test_the_cones_of_the_saddle_box_map_as_certified(torque, r):
    """In the box ‖z‖∞ ≤ r of the saddle's eigen-coordinates, with the slope κ and the inner
    box ρ that SaddleBox.cone certifies there: 5,000 sampled points, mapped by the plain RK4
    step, do what the certificate assumes — U±_κ = {±u ≥ κ|s|} into itself with |u| growing;
    S_κ = {|u| < κ|s|} within ρ into S_κ within ρ or into U_κ within r."""
    p = Pendulum(0.05, 1.0, torque)
    box = saddle_box(p, DT)
    slope, rho = box.cone(r)
    assert 0.0 < slope <= 1.0 and 0.0 < rho < r
    pmat = np.linalg.inv(box.pinv)
    q = p.saddle_angle
    rng = np.random.default_rng(int(r * 1e4) + int(torque * 10))
    for z in rng.uniform(-r, r, (5000, 2)):
        u, s = z
        x = q + pmat[0] @ z
        xv = pmat[1] @ z
        nx, nv = rk4(x, xv, p.alpha, p.omega0, p.torque)
        u2, s2 = box.pinv @ np.array([nx - q, nv])
        if abs(u) >= slope * abs(s):
            assert abs(u2) >= slope * abs(s2) and abs(u2) > abs(u) and u2 * u > 0
        elif max(abs(u), abs(s)) <= rho:
            inside_s = abs(u2) < slope * abs(s2) and max(abs(u2), abs(s2)) <= rho
            inside_u = abs(u2) >= slope * abs(s2) and max(abs(u2), abs(s2)) <= r
            assert inside_s or inside_u


def _on_cone_edge(box, p, slope, r):
    """(points on the edges u = ±slope·|s| of the cones, 0 < |s| ≤ r, in eigen-coordinates;
    whether each stays in its cone after one plain RK4 step with |u| growing)."""
    pmat = np.linalg.inv(box.pinv)
    q = p.saddle_angle
    s = np.concatenate([-np.geomspace(r, r * 1e-3, 200), np.geomspace(r * 1e-3, r, 200)])
    stays = []
    for sign in (1.0, -1.0):
        for z in np.column_stack([sign * slope * np.abs(s), s]):
            nx, nv = rk4(q + pmat[0] @ z, pmat[1] @ z, p.alpha, p.omega0, p.torque)
            u2, s2 = box.pinv @ np.array([nx - q, nv])
            stays.append(abs(u2) >= slope * abs(s2) and abs(u2) > abs(z[0]) and u2 * z[0] > 0)
    return np.array(stays)


@pytest.mark.parametrize("torque", [0.0, 0.5])
def test_the_certified_cones_hold_on_their_edges(torque):
    """The cones' edges, where invariance is tightest: every point of U±_κ's edge stays in
    U±_κ, with |u| growing, for the κ certified in boxes of 1e-3 to 0.05."""
    p = Pendulum(0.05, 1.0, torque)
    box = saddle_box(p, DT)
    for r in (1e-3, 1e-2, 0.05):
        slope, _ = box.cone(r)
        assert _on_cone_edge(box, p, slope, r).all()


def test_a_box_too_large_certifies_no_cone():
    """Where the remainder outgrows the gap between the multipliers no slope is certified
    (κ = inf); and a slope far below the certified one is not invariant: points on its edge
    leave the cone (the edge test above can fail)."""
    p = Pendulum(0.05, 1.0, 0.5)
    box = saddle_box(p, DT)
    assert math.isinf(box.cone(5.0)[0])
    slope, _ = box.cone(0.05)
    assert not _on_cone_edge(box, p, slope / 1000.0, 0.05).all()


def test_shots_do_not_depend_on_the_threads():
    """The same segments shot on one thread and on every thread, so dealt to 16 chunks or to
    16 per thread: the same arrays (each orbit is integrated on its own)."""
    import numba

    from atlas.kernels.shooting import shoot

    p = Pendulum(0.05, 1.0, 0.5)
    box = saddle_box(p, DT)
    rng = np.random.default_rng(5)
    n = 2000
    theta, speed = rng.uniform(-2.0, 3.0, n), rng.uniform(-1.0, 2.0, n)
    d_theta, d_speed = np.full(n, 0.6), np.full(n, 0.8)
    # and a quarter across the saddle's stable eigen-line, 1e-6 to 1e-5 from the saddle
    # (within ~1e-10 of the stable manifold): these are crossed
    lam_u, lam_s = p.saddle_eigenvalues()
    a = rng.uniform(1e-6, 1e-5, n // 4) * rng.choice([-1.0, 1.0], n // 4)
    theta[: n // 4] = p.saddle_angle + a / math.hypot(1.0, lam_s)
    speed[: n // 4] = a * lam_s / math.hypot(1.0, lam_s)
    d_theta[: n // 4], d_speed[: n // 4] = np.array([1.0, lam_u]) / math.hypot(1.0, lam_u)
    args = (theta, speed, d_theta, d_speed, np.full(n, 1e-9), box.pinv, box.constants)
    # a part 1/50 of each segment is read once it is crossed (the parts' own path too)
    kw = dict(r_max=box.r_max, saddle0=p.saddle_angle, alpha=p.alpha, omega0=p.omega0,
              torque=p.torque, dt=DT, n_checks=2000, target=2e-11, budget=1e-10)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = shoot(*args, **kw)
    finally:
        numba.set_num_threads(threads)
    every = shoot(*args, **kw)
    assert numba.get_num_threads() > 1 or pytest.skip("one thread only")
    for a, b in zip(one, every, strict=True):
        np.testing.assert_array_equal(a, b)
    assert np.isin(one[0], (1, 2)).sum() > 0  # some reached a saddle and were read
    assert (one[5][:, 1] - one[5][:, 0] < 2.0).sum() > 0  # and some parts were certified
