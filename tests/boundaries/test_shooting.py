"""Shooting to the saddle (atlas.boundaries.shooting) against bisection on certified labels,
an independent locator of the same boundary: a segment across the labels' boundary is
certified, one beside it is not, Newton steps converge onto it, and what the certificate
cannot cover (another saddle, rounding above tol, another method) is left uncertified."""

from __future__ import annotations

import numpy as np
import pytest

from atlas.boundaries.bisection import Labeller, bisect_between, field_normal, linger
from atlas.boundaries.shooting import HALF_WIDTH, Shooter
from atlas.boundaries.trace import trace
from atlas.kernels.shooting import CROSSED, SAME, shoot
from atlas.physics.pendulum import Pendulum

DT, T_MAX, TOL = 0.01, 200.0, 1e-12


@pytest.fixture(scope="module", params=[(0.1, 1.0, 0.0), (0.05, 1.0, 0.5)],
            ids=["untilted", "tilted"])
def boundary(request):
    """(pendulum, points on the RK4 map's boundary as the labels see it (base + s*·normal,
    bisected to tol/64), unit normals, their saddles' θ, the labels' t_max)."""
    p = Pendulum(*request.param)
    q = p.saddle_angle
    sep = trace(p, (q - 2.5, q + 0.5), (-1.0, 2.0), tol=TOL, dt=DT, t_max=T_MAX)
    pick = np.linspace(0, sep.sizes["point"] - 1, 12).round().astype(int)
    base = np.column_stack([sep["theta"].values[pick], sep["theta_dot"].values[pick]])
    normal = np.column_stack(field_normal(p, base[:, 0], base[:, 1]))
    labels = Labeller(p, DT, T_MAX + linger(p, TOL))
    below = labels(*(base - 1e-6 * normal).T)
    above = labels(*(base + 1e-6 * normal).T)
    assert np.all(below != above)
    lo, hi, ok = bisect_between(labels, base, normal, below, above, tol=TOL / 64,
                                half_width=TOL)
    assert ok.all()
    star = 0.5 * (lo + hi)
    saddle = sep["saddle_theta"].values[pick]
    return p, base + star[:, None] * normal, normal, saddle, labels.t_max


def _shoot(p, shooter, centre, normal, w, **narrower):
    box = shooter.box
    return shoot(centre[:, 0], centre[:, 1], normal[:, 0], normal[:, 1],
                 np.full(centre.shape[0], w), box.pinv, box.constants, r_max=box.r_max,
                 saddle0=p.saddle_angle, alpha=p.alpha, omega0=p.omega0, torque=p.torque,
                 dt=DT, n_checks=shooter.n_checks, **narrower)


def test_across_the_labels_boundary_certified_beside_it_not(boundary):
    """Segments of half-width w = 0.45·tol centred within 0.4·w of the labels' boundary are
    certified (CROSSED); centred 3·w or 30·w off, on either side, they are not (SAME), and
    their Newton estimate lands within 0.1·w of the labels' boundary."""
    p, star, normal, _, t_max = boundary
    shooter = Shooter(p, TOL, dt=DT, t_max=t_max)
    w = HALF_WIDTH * TOL
    for delta in (-0.4, 0.0, 0.4):
        kind, *_ = _shoot(p, shooter, star + delta * w * normal, normal, w)
        assert np.all(kind == CROSSED), delta
    for delta in (-30.0, -3.0, 3.0, 30.0):
        kind, _, sigma, *_ = _shoot(p, shooter, star + delta * w * normal, normal, w)
        assert np.all(kind == SAME), delta
        np.testing.assert_allclose(delta + sigma, 0.0, atol=0.1)


@pytest.mark.parametrize("wide", [8.0, 128.0, 512.0])
def test_a_wide_segment_is_narrowed_in_one_orbit(boundary, wide):
    """A segment ``wide`` times w across the labels' boundary, off-centre by 0.6 of its
    half-width, asked for a part of half-width w: one orbit certifies a part no wider than
    2w (plus rounding) that holds the labels' boundary (bisected to tol/64; up to the
    rounding estimate), with its Newton estimate inside the part."""
    p, star, normal, _, t_max = boundary
    shooter = Shooter(p, TOL, dt=DT, t_max=t_max)
    w, big = HALF_WIDTH * TOL, wide * HALF_WIDTH * TOL
    for side in (-1.0, 1.0):
        off = side * 0.6 * big
        kind, _, sigma, rounding, _, part = _shoot(p, shooter, star - off * normal, normal,
                                                   big, target=w, budget=TOL)
        assert np.all(kind == CROSSED)
        lo, hi = part[:, 0] * big, part[:, 1] * big  # from the centre, star at +off
        assert np.all(hi - lo <= 2.0 * w * (1.0 + 1e-9))
        slack = TOL / 64 + rounding
        assert np.all((lo - slack <= off) & (off <= hi + slack))
        assert np.all((part[:, 0] <= sigma) & (sigma <= part[:, 1]))


def test_a_part_left_undecided_keeps_the_whole_segments_certificate(boundary):
    """A segment 10⁶ times w across the boundary (its enclosure's β, growing as its width
    squared, keeps a part of width 2w from being read before the orbit leaves the box):
    the whole segment's certificate is returned, and it holds the labels' boundary."""
    p, star, normal, _, t_max = boundary
    shooter = Shooter(p, TOL, dt=DT, t_max=t_max)
    big = 1e6 * HALF_WIDTH * TOL
    kind, *_, part = _shoot(p, shooter, star + 0.3 * big * normal, normal, big,
                            target=HALF_WIDTH * TOL, budget=TOL)
    whole = (part[:, 0] == -1.0) & (part[:, 1] == 1.0)
    assert np.all(kind == CROSSED) and whole.all()
    # the whole segment: star lies at −0.3 of its half-width from its centre
    assert np.all((part[:, 0] <= -0.3) & (-0.3 <= part[:, 1]))


def test_newton_steps_from_the_exact_curves_distance(boundary):
    """From 3e-9 off (the RK4 map's boundary shift from the exact one at dt = 0.01), refine
    certifies every point within three shots, with the labels' boundary inside each bracket
    (up to the rounding estimate it reports), and its Newton estimate within 0.1·w of it."""
    p, star, normal, saddle, t_max = boundary
    shooter = Shooter(p, TOL, dt=DT, t_max=t_max)
    n = star.shape[0]
    for off in (3e-9, -3e-9):
        lo, hi, ok, estimate = shooter.refine(star, normal, np.full(n, off), saddle)
        assert ok.all()
        assert np.all(hi - lo < TOL)
        slack = shooter.rounding
        assert np.all((lo - slack <= 0.0) & (0.0 <= hi + slack))
        np.testing.assert_allclose(estimate, 0.0, atol=0.1 * HALF_WIDTH * TOL)
    assert shooter.shots <= 2 * 3 * n


def test_a_shot_read_at_another_saddle_is_not_used(boundary):
    """A vertex said to belong to the next saddle (2π on) is not certified by a shot that
    reaches its own, nor given an estimate."""
    p, star, normal, saddle, t_max = boundary
    shooter = Shooter(p, TOL, dt=DT, t_max=t_max)
    lo, hi, ok, estimate = shooter.refine(star, normal, np.zeros(star.shape[0]),
                                          saddle + 2.0 * np.pi)
    assert not ok.any() and np.isnan(estimate).all() and np.isnan(lo).all()


def test_rounding_above_tol_is_not_certified(boundary):
    """At tol = 1e-15 every orbit's rounding estimate exceeds tol: nothing is certified
    (the points are left to the labels, which report what they reach)."""
    p, star, normal, saddle, t_max = boundary
    shooter = Shooter(p, 1e-15, dt=DT, t_max=t_max)
    _, _, ok, _ = shooter.refine(star, normal, np.zeros(star.shape[0]), saddle)
    assert not ok.any() and shooter.shots > 0


def test_another_method_is_not_shot():
    """The kernel integrates classical RK4 on (θ, θ̇): for rk4-trigfree no shot is taken."""
    p = Pendulum(0.1, 1.0)
    shooter = Shooter(p, TOL, dt=DT, t_max=T_MAX, method="rk4-trigfree")
    lo, hi, ok, _ = shooter.refine(np.array([[0.0, 1.9]]), np.array([[0.0, 1.0]]),
                                   np.zeros(1), np.array([np.pi]))
    assert shooter.box is None and shooter.shots == 0 and not ok.any()


def test_a_whole_crossing_at_the_last_check_is_kept(boundary):
    """A wide segment crossed at its very last check (no check left to read a part in)
    keeps the whole segment's certificate: the same kind and part as without a target."""
    p, star, normal, _, t_max = boundary
    shooter = Shooter(p, TOL, dt=DT, t_max=t_max)
    big = 512 * HALF_WIDTH * TOL
    kind, n_steps, *_ = _shoot(p, shooter, star, normal, big)
    assert np.all(kind == CROSSED)
    box = shooter.box
    from atlas.kernels.shooting import CHECK_EVERY

    for i in range(star.shape[0]):
        last = int(n_steps[i]) // CHECK_EVERY  # the check at which the whole was crossed
        got = shoot(star[i:i + 1, 0], star[i:i + 1, 1], normal[i:i + 1, 0], normal[i:i + 1, 1],
                    np.array([big]), box.pinv, box.constants, r_max=box.r_max,
                    saddle0=p.saddle_angle, alpha=p.alpha, omega0=p.omega0, torque=p.torque,
                    dt=DT, n_checks=last, target=HALF_WIDTH * TOL, budget=TOL)
        assert got[0][0] == CROSSED and tuple(got[5][0]) == (-1.0, 1.0)
