"""The traced separatrices with torque (atlas.boundaries.trace_tilted, through trace) and
the certificate built on them, checked directly: the RK4 labels differ across every located
point at ±tol, and labels certified between d_cert and 10·d_cert of the exact boundaries are
the exact equation's (scipy's DOP853 at rtol 1e-12, classified by the same certificates)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.boundaries.bisection import NO_LABEL, Labeller, field_normal, linger
from atlas.boundaries.certificate import Certifier
from atlas.boundaries.exact import RUNNING_SIDE, exact_boundaries
from atlas.boundaries.trace import trace
from atlas.kernels import RUNNING, TRAPPED
from atlas.physics.pendulum import Pendulum
from atlas.physics.running import running_certificate
from tests.pipeline.test_swing import _dop853_label

DT, T_MAX, TOL = 0.01, 400.0, 1e-12


@pytest.fixture(scope="module", params=[(0.05, 1.0, 0.5), (0.1, 1.0, -0.2)],
                ids=["bistable", "monostable"])
def traced(request):
    """(pendulum, barrier, exact boundaries, separatrices) over a window around the saddle
    of well 0 (bistable: a tongue and the running basin; monostable: two wells)."""
    p = Pendulum(*request.param)
    saddle = p.saddle_angle
    window = ((saddle - 1.2, saddle + 1.0), (-1.5, 1.5))
    _, barrier = running_certificate(p, DT)
    exact = exact_boundaries(p, window)
    sep = trace(p, *window, tol=TOL, dt=DT, t_max=T_MAX, exact=exact, barrier=barrier)
    return p, barrier, exact, sep


def test_polyline_error_is_the_stored_polylines(traced):
    """polyline_error is how far the exact boundary strays from the polyline through the
    stored points: the largest distance of points on their chords (15 a chord, consecutive
    vertices of a branch) from the exact boundaries, to a tenth (both measure the chords'
    sagitta), and below max_spacing²/8 per rad of curvature at most 1."""
    _, _, exact, sep = traced
    n, b, vertex = (sep[name].values for name in ("saddle_n", "branch", "vertex"))
    theta, theta_dot = sep["theta"].values, sep["theta_dot"].values
    order = np.lexsort((vertex, b, n))
    same = (np.diff(n[order]) == 0) & (np.diff(b[order]) == 0) & (np.diff(vertex[order]) == 1)
    i0, i1 = order[:-1][same], order[1:][same]
    f = np.linspace(0.0, 1.0, 17)[1:-1, None]
    x = theta[i0] + f * (theta[i1] - theta[i0])
    v = theta_dot[i0] + f * (theta_dot[i1] - theta_dot[i0])
    dist, _ = exact.distance(x.ravel(), v.ravel())
    error = sep.attrs["polyline_error"]
    assert i0.size > 20
    assert dist.max() == pytest.approx(error, rel=0.1)
    assert error < sep.attrs["max_spacing"] ** 2 / 8


@pytest.mark.slow
def test_labels_differ_across_every_located_point(traced):
    """At every located point ± tol along the normal of the vector field: two certified RK4
    labels, different; the located points lie within the measured shift of the exact
    boundaries, which is the RK4 map's O(dt⁴) shift."""
    p, barrier, exact, sep = traced
    theta, theta_dot = sep["theta"].values, sep["theta_dot"].values
    assert theta.size >= 20 and not sep.attrs["warnings"]
    assert np.all(sep["bracket_width"].values < TOL)
    labels = Labeller(p, DT, T_MAX + linger(p, TOL), barrier=barrier)
    n_theta, n_speed = field_normal(p, theta, theta_dot)
    below = labels(theta - TOL * n_theta, theta_dot - TOL * n_speed)
    above = labels(theta + TOL * n_theta, theta_dot + TOL * n_speed)
    assert np.all(below != NO_LABEL) and np.all(above != NO_LABEL)
    assert np.all(below != above)
    dist, _ = exact.distance(theta, theta_dot)
    assert dist.max() == pytest.approx(float(sep.attrs["discrepancy"]), rel=1e-12)
    assert 0.0 < dist.max() < 1e-7  # the RK4 map's boundary shift at dt = 0.01: ≈ 1e-9


@pytest.mark.slow
def test_certified_between_d_cert_and_ten_d_cert_is_the_exact_equations(traced):
    """Points placed at 1.5, 3 and 7 d_cert on either side of the exact boundaries (off
    exact vertices, along the normal): every label the certificate passes (trapped or
    running) is DOP853's fate; and most are passed, so the check is not vacuous."""
    p, barrier, exact, sep = traced
    (t0, t1), (v0, v1) = exact.window
    cert = Certifier(p, np.linspace(t0, t1, 33), np.linspace(v0, v1, 25),
                     float(sep.attrs["discrepancy"]), float(sep.attrs["tol"]), exact)
    base = []
    for j, _, x, v in exact.tilted.curves(clip=True):
        far = np.hypot(x - exact.tilted.saddle_theta(j), v) > 0.1  # the normal is defined
        base += list(zip(x[far][::400], v[far][::400]))
    base = np.array(base)[:12]
    n = np.column_stack(field_normal(p, base[:, 0], base[:, 1]))
    factors = np.array([1.5, 3.0, 7.0, -1.5, -3.0, -7.0])
    points = (base[:, None, :] + cert.d_cert * factors[None, :, None] * n[:, None, :])
    theta, theta_dot = points[..., 0].ravel(), points[..., 1].ravel()
    import atlas

    res = atlas.label(theta, theta_dot, alpha=p.alpha, omega0=p.omega0, torque=p.torque,
                      dt=DT, t_max=T_MAX, running=barrier)
    status, dist, side, _ = cert.certify(theta, theta_dot, res.attractor, res.status)
    np.testing.assert_allclose(dist, cert.d_cert * np.abs(np.tile(factors, base.shape[0])),
                               rtol=0.02)
    certified = np.flatnonzero((status == TRAPPED) | (status == RUNNING))
    assert certified.size >= 0.8 * theta.size
    assert np.unique(side[certified]).size >= 2  # both sides of the boundaries
    for i in certified:
        fate = _dop853_label(p, float(theta[i]), float(theta_dot[i]), barrier, T_MAX)
        stored = "running" if status[i] == RUNNING else int(res.attractor[i])
        assert fate == stored, (theta[i], theta_dot[i], fate, stored)
    assert RUNNING_SIDE not in side[certified] or exact.running_possible
    assert math.isfinite(cert.d_cert)


@pytest.mark.parametrize("offset", [-1000.0, -40.0, 0.3, 300.0, 5000.0])
def test_bisect_between_on_a_known_boundary_labels_each_end_once(offset):
    """bisect_between on its own, along lines s·(1, 0) with the boundary at a known s* (in
    tol) between the running side below and well 2 above: every bracket holds s*, is
    narrower than tol, ends on the two sides; an end that carried the other side became the
    other end, so the widening labels only the end pushed out: two labels, one per widening
    (×8 from ±32·tol), then one per halving — counted."""
    from atlas.boundaries.bisection import FIRST_BRACKET, bisect_between

    tol, n = 2.0**-40, 5  # a power of two: the brackets' widths are exact
    star = offset * tol * (1.0 + 0.1 * np.arange(n))  # five lines, five boundaries
    calls = []

    def labels(theta, theta_dot):
        calls.append(theta.size)
        return np.where(theta - base_of(theta_dot) < star_of(theta_dot), RUNNING_SIDE, 2)

    base = np.column_stack([np.zeros(n), np.arange(n, dtype=float)])  # line i at θ̇ = i

    def base_of(theta_dot):
        return base[np.rint(theta_dot).astype(int), 0]

    def star_of(theta_dot):
        return star[np.rint(theta_dot).astype(int)]

    normal = np.tile([1.0, 0.0], (n, 1))
    below, above = np.full(n, RUNNING_SIDE), np.full(n, 2)
    lo, hi, ok = bisect_between(labels, base, normal, below, above, tol=tol,
                                half_width=FIRST_BRACKET * tol)
    assert ok.all()
    assert np.all((lo < star) & (star <= hi)) and np.all(hi - lo < tol)
    widenings = np.maximum(np.ceil(np.log(np.abs(star) / (FIRST_BRACKET * tol))
                                   / np.log(8.0)), 0)
    far = FIRST_BRACKET * tol * 8.0 ** widenings  # the far end after the widenings
    width = np.where(widenings > 0, far * 7 / 8, 2 * FIRST_BRACKET * tol)
    halvings = np.floor(np.log2(width / tol)) + 1  # until narrower than tol
    assert sum(calls) == 2 * n + widenings.sum() + halvings.sum()


def test_bisect_between_refuses_a_growth_that_does_not_widen():
    from atlas.boundaries.bisection import bisect_between

    with pytest.raises(ValueError, match="grow must be > 1"):
        bisect_between(None, np.zeros((1, 2)), np.ones((1, 2)), np.zeros(1), np.ones(1),
                       tol=1e-12, half_width=1e-12, grow=1.0)


def test_bisect_between_a_prediction_off_by_up_to_three_halfwidths_costs_one_label():
    """The trace's last level: a first bracket of ±0.45·tol around the prediction, widened
    ×3: a boundary within 1.35·tol of the prediction (but beyond 0.45·tol) is bracketed to
    0.9·tol by one more label, and no halving."""
    from atlas.boundaries.bisection import bisect_between

    tol = 1e-12
    star = np.array([-1.3, -0.6, 0.5, 1.0, 1.3]) * tol
    base = np.column_stack([np.zeros(star.size), np.arange(star.size, dtype=float)])
    calls = []

    def labels(theta, theta_dot):
        calls.append(theta.size)
        return np.where(theta < star[np.rint(theta_dot).astype(int)], RUNNING_SIDE, 2)

    lo, hi, ok = bisect_between(labels, base, np.tile([1.0, 0.0], (star.size, 1)),
                                np.full(star.size, RUNNING_SIDE), np.full(star.size, 2),
                                tol=tol, half_width=0.45 * tol, grow=3.0)
    assert ok.all() and np.all((lo < star) & (star <= hi))
    np.testing.assert_allclose(hi - lo, 0.9 * tol, rtol=1e-12)
    assert calls == [2 * star.size, star.size]
