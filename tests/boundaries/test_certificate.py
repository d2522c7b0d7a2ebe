"""Labels certified for the exact equation, and the grid fractions' error
(atlas.boundaries.certificate).

References: scipy's DOP853 at rtol 1e-12 labelling orbits of the exact equation; the exact
areas of atlas.boundaries.manifold (themselves checked in tests/boundaries/test_manifold.py);
the cell geometry.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import atlas
from atlas.boundaries.certificate import SAFETY, Certifier, add_tallies, cert_distance, labelled
from atlas.boundaries.trace import trace
from atlas.kernels import NEAR_BOUNDARY, TRAPPED
from atlas.physics.pendulum import Pendulum

PI = math.pi
WINDOW = ((-3 * PI, 3 * PI), (-4.0, 4.0))


def exact_label(p: Pendulum, theta0: float, theta_dot0: float) -> int | None:
    """The well reached by the exact equation: DOP853 (rtol 1e-12, atol 1e-14) until the
    orbit is deep in a well (E_k < ω0², far below the saddles' 2ω0²), None if not by t = 400."""
    w2, a2 = p.omega0**2, 2 * p.alpha

    def rhs(_, y):
        return [y[1], -w2 * math.sin(y[0]) - a2 * y[1]]

    def deep(_, y):
        k = round(y[0] / (2 * PI))
        return 0.5 * y[1] ** 2 + w2 * (1 - math.cos(y[0] - 2 * PI * k)) - w2

    deep.terminal = True
    sol = solve_ivp(rhs, (0, 400), [theta0, theta_dot0], method="DOP853", rtol=1e-12,
                    atol=1e-14, events=deep)
    return round(sol.y[0, -1] / (2 * PI)) if sol.status == 1 else None


@pytest.fixture(scope="module", params=[(0.1, 1.0), (2.0, 1.0)], ids=["under", "over"])
def traced(request):
    """(pendulum, its separatrices over the default window, a Certifier with their shift)."""
    p = Pendulum(*request.param)
    sep = trace(p, *WINDOW)
    theta0, theta_dot0 = np.linspace(*WINDOW[0], 64), np.linspace(*WINDOW[1], 48)
    cert = Certifier(p, theta0, theta_dot0, float(sep.attrs["discrepancy"]),
                     float(sep.attrs["tol"]))
    return p, sep, cert


@pytest.mark.slow
def test_d_cert_covers_the_measured_shift_tenfold(traced):
    """d_cert exceeds ten times the RK4 map's measured boundary shift, and is not much more:
    the reference's own error (rtol 1e-13) is far below the shift."""
    _, sep, cert = traced
    assert 0 < cert.reference_error < 1e-10
    assert SAFETY * sep.attrs["discrepancy"] < cert.d_cert < SAFETY * 1.5 * (
        sep.attrs["discrepancy"] + sep.attrs["tol"])
    assert math.isnan(cert_distance(float("nan"), 1e-12, 1e-11))


@pytest.mark.slow
def test_certified_labels_are_the_exact_equations(traced):
    """Points on either side of the exact boundaries at 10·d_cert: every label atlas certifies
    is DOP853's; at 0.1·d_cert none is certified, so the flag is not vacuous."""
    p, _, cert = traced
    manifold = cert.exact._index(1.0).manifold
    rng = np.random.default_rng(11)
    # points on the exact boundaries through saddles in and outside the window
    picks = rng.choice(manifold.theta.size, 12, replace=False)
    shifts = rng.choice([-4, -2, 0, 2], 12) * PI  # copies of L: saddles −3π … 3π
    base_theta = manifold.theta[picks] + shifts
    base_speed = manifold.theta_dot[picks]
    f0, f1 = base_speed, -p.omega0**2 * np.sin(base_theta) - 2 * p.alpha * base_speed
    norm = np.hypot(f0, f1)
    normal = np.column_stack([-f1 / norm, f0 / norm])  # larger θ̇ side
    for factor, must_flag in ((10.0, False), (0.1, True)):
        offset = factor * cert.d_cert * np.concatenate([np.ones(12), -np.ones(12)])
        theta = np.tile(base_theta, 2) + offset * np.tile(normal[:, 0], 2)
        speed = np.tile(base_speed, 2) + offset * np.tile(normal[:, 1], 2)
        res = atlas.label(theta, speed, alpha=p.alpha, omega0=p.omega0, t_max=400.0)
        status, dist, side, _ = cert.certify(theta, speed, res.attractor, res.status)
        np.testing.assert_allclose(dist, factor * cert.d_cert, rtol=1e-3)
        if must_flag:
            assert np.all(status[labelled(res.status)] == NEAR_BOUNDARY)
            continue
        assert np.count_nonzero(status == TRAPPED) >= 20  # the certificate is not empty
        for i in np.flatnonzero(status == TRAPPED):
            assert res.attractor[i] == side[i] == exact_label(p, theta[i], speed[i])


@pytest.mark.slow
def test_grid_error_bound_holds_and_shrinks_at_first_order():
    p = Pendulum(0.1, 1.0)
    sep = trace(p, *WINDOW)
    errors, bounds = [], []
    for num in (64, 128, 256):
        theta0, theta_dot0 = np.linspace(*WINDOW[0], num), np.linspace(*WINDOW[1], num)
        res = atlas.label(theta0[None, :], theta_dot0[:, None], alpha=0.1, omega0=1.0)
        cert = Certifier(p, theta0, theta_dot0, float(sep.attrs["discrepancy"]),
                         float(sep.attrs["tol"]))
        halves = (slice(0, num // 2), slice(num // 2, num))
        f = cert.summary(add_tallies(cert.tile(rows, res.attractor[rows], res.status[rows])[2]
                                     for rows in halves))
        counted = [np.count_nonzero(res.attractor == k) / num**2 for k in f["k"]]
        np.testing.assert_array_equal(f["basin_fraction"], counted)
        assert np.all(f["basin_fraction_grid_error"] <= f["basin_fraction_grid_error_bound"])
        errors.append(f["basin_fraction_grid_error"].sum())
        bounds.append(f["basin_fraction_grid_error_bound"].sum())
    h = np.array([1 / 63, 1 / 127, 1 / 255])
    order_error = np.polyfit(np.log(h), np.log(errors), 1)[0]
    order_bound = np.polyfit(np.log(h), np.log(bounds), 1)[0]
    assert 0.7 < order_error < 1.4 and 0.9 < order_bound < 1.1


def test_without_a_measured_shift_no_label_is_certified():
    p = Pendulum(0.1, 1.0)
    theta0, theta_dot0 = np.linspace(-1, 1, 5), np.linspace(-1, 1, 4)
    res = atlas.label(theta0[None, :], theta_dot0[:, None], alpha=0.1, omega0=1.0)
    cert = Certifier(p, theta0, theta_dot0, float("nan"), float("nan"))
    status, dist, tally = cert.tile(slice(0, 4), res.attractor, res.status)
    assert np.all(status == NEAR_BOUNDARY) and np.all(dist > 0) and tally["certified"] == 0


@pytest.mark.slow
def test_an_atlas_file_stores_the_certificate(tmp_path):
    """Through atlas.run: distances, d_cert and statuses are consistent, and the fractions
    and their errors are those of the file's own labels."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"""\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 41}}
  theta_dot0: {{start: -4, stop: 4, num: 31}}
output: {tmp_path / 'c.h5'}
""")
    ds = atlas.run(atlas.load_config(cfg), quiet=True).to_dataset(inherit=False)
    sep = atlas.open(tmp_path / "c.h5")["separatrices"]
    d_cert = float(ds["d_cert"])
    assert d_cert == cert_distance(sep.attrs["discrepancy"], sep.attrs["tol"],
                                   float(ds["boundary_reference_error"]))
    assert float(ds["boundary_shift"]) == sep.attrs["discrepancy"]
    status, dist = ds["status"].values, ds["boundary_distance"].values
    assert np.all(np.isfinite(dist)) and np.all(dist >= 0)
    assert np.all(dist[labelled(status)] > 0)  # distance 0: only the saddles at the corners
    np.testing.assert_array_equal(status == TRAPPED, labelled(status) & (dist > d_cert))
    assert float(ds["certified_fraction"]) == np.mean(status == TRAPPED)
    assert int(ds["side_mismatches"]) == 0


@pytest.mark.parametrize("window", [WINDOW, ((-0.5, 0.5), (-0.3, 0.3))],
                         ids=["default", "inside a basin"])
def test_distances_are_those_of_one_index_over_everything(window):
    """The certifier searches a box around the window and searches again, in a larger one,
    only the points whose distance found exceeds their distance to that box's edge: the
    same distances and saddles as one index whose box holds every point's nearest boundary.
    Inside a basin every boundary lies beyond the first margin, so the second search must
    find them."""
    from atlas.boundaries.exact import _FIRST_MARGIN
    from atlas.boundaries.manifold import BoundaryIndex, StableManifold

    p = Pendulum(0.1, 1.0)
    # even counts: no grid point on a symmetry centre, where two boundaries are equally near
    cert = Certifier(p, np.linspace(*window[0], 32), np.linspace(*window[1], 16), 1e-9, 1e-12)
    th, v = np.meshgrid(cert.theta0, cert.theta_dot0)
    dist, n = cert.distance(th, v)
    assert np.all(np.isfinite(dist)) and np.count_nonzero(dist > _FIRST_MARGIN) > 10
    reach = float(dist.max()) + 1.0
    (t0, t1), (v0, v1) = window
    big = BoundaryIndex(StableManifold(p, max(abs(v0), abs(v1)) + reach),
                        ((t0 - reach, t1 + reach), (v0 - reach, v1 + reach)))
    ref, ref_n = big.nearest(th, v)
    np.testing.assert_allclose(dist, ref, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(n, ref_n)
