"""The trig-free method (atlas.kernels.trigfree, ``integrator.method: rk4-trigfree``): its
certified labels are the exact equation's, its kernels against its plain form, how atlas.label
selects it, and a whole atlas run, orbit and separatrices with it.

Order 4 is fitted in tests/kernels/test_rk4.py, the energy trap's margin measured for it in
tests/labels/test_labels.py, the lane machinery's thread independence in
tests/kernels/test_lanes.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.boundaries.certificate import Certifier, labelled
from atlas.boundaries.trace import trace
from atlas.defaults import METHOD as DEFAULT_METHOD
from atlas.kernels import TRAPPED
from atlas.kernels.lanes import label_trigfree
from atlas.kernels.trigfree import label_trigfree_straightforward
from atlas.labels.backends import resolve_method
from atlas.labels.trap import energy_cap, n_checks_for
from atlas.physics.pendulum import Pendulum
from tests.boundaries.test_certificate import exact_label as _exact_after
from tests.helpers import boundary_adjacent

PI = math.pi
WINDOW = ((-3 * PI, 3 * PI), (-4.0, 4.0))


def exact_label(p: Pendulum, theta0: float, theta_dot0: float) -> int | None:
    """DOP853's well (tests/boundaries/test_certificate.py), and the nearest well for a start
    already deep in one (E_k < ω0², where that reference's stopping event cannot fire)."""
    k = round(theta0 / (2 * PI))
    if p.energy(theta0, theta_dot0, k) < p.omega0**2:
        return k
    return _exact_after(p, theta0, theta_dot0)


def test_default_cpu_method_is_classical_rk4():
    assert DEFAULT_METHOD == "rk4"
    assert resolve_method("cpu", None, None) == "rk4"
    assert resolve_method("cpu", None, "rk4-trigfree") == "rk4-trigfree"
    assert resolve_method("cpu", "straightforward", None) == "rk4"
    assert resolve_method("cuda", None, None) == "rk4"
    for bad in ({"method": "rk5"}, {"kernel": "lanes"}, {"backend": "tpu"}):
        args = {"backend": "cpu", "kernel": None, "method": None, **bad}
        with pytest.raises(ValueError, match=next(iter(bad))):
            resolve_method(**args)
    with pytest.raises(ValueError, match="no CUDA kernel"):
        resolve_method("cuda", None, "rk4-trigfree")


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.1, 2.0])
def test_certified_trigfree_labels_are_the_exact_equations(alpha):
    """Random points of the window plus points 1.5 and 3 d_cert off the exact boundaries,
    labelled with method "rk4-trigfree"; d_cert from the separatrix bisection on labels of
    the same method. Every label certified (boundary distance > d_cert, on the exact side)
    must be DOP853's."""
    p = Pendulum(alpha, 1.0)
    sep = trace(p, *WINDOW, method="rk4-trigfree")
    cert = Certifier(p, np.linspace(*WINDOW[0], 64), np.linspace(*WINDOW[1], 48),
                     float(sep.attrs["discrepancy"]), float(sep.attrs["tol"]))
    rng = np.random.default_rng(5)
    theta = rng.uniform(*WINDOW[0], 120)
    speed = rng.uniform(*WINDOW[1], 120)
    manifold = cert.exact._index(1.0).manifold
    picks = rng.choice(manifold.theta.size, 16, replace=False)
    base_theta = manifold.theta[picks] + rng.choice([-4, -2, 0, 2], 16) * PI
    base_speed = manifold.theta_dot[picks]
    f0, f1 = base_speed, -p.omega0**2 * np.sin(base_theta) - 2 * p.alpha * base_speed
    norm = np.hypot(f0, f1)
    for factor in (1.5, -1.5, 3.0, -3.0):
        theta = np.append(theta, base_theta - factor * cert.d_cert * f1 / norm)
        speed = np.append(speed, base_speed + factor * cert.d_cert * f0 / norm)
    res = atlas.label(theta, speed, alpha=p.alpha, omega0=p.omega0, t_max=400.0,
                      method="rk4-trigfree")
    status, dist, side, _ = cert.certify(theta, speed, res.attractor, res.status)
    certified = np.flatnonzero(status == TRAPPED)
    near = certified[certified >= 120]
    # the points close to the boundaries are certified and checked (a few picks on copies of
    # a branch outside the window are nearer to another boundary: far from every boundary)
    assert np.count_nonzero(dist[near] < 3.01 * cert.d_cert) >= 40
    assert certified.size >= 150
    for i in certified:
        assert res.attractor[i] == side[i] == exact_label(p, theta[i], speed[i]), i
    assert np.all(labelled(res.status))


def _grid(n_theta, n_theta_dot):
    th, v = np.meshgrid(np.linspace(-3 * np.pi, 3 * np.pi, n_theta),
                        np.linspace(-4.0, 4.0, n_theta_dot))
    return th.ravel().copy(), v.ravel().copy()


def _run(kernel, theta0, theta_dot0, check_every=16, t_max=200.0, alpha=0.1, dt=0.01):
    n = theta0.size
    out = (np.full(n, 777, np.int32), np.full(n, 99, np.int8), np.full(n, -99, np.int32))
    kernel(theta0, theta_dot0, alpha, 1.0, dt, n_checks_for(t_max, dt, check_every),
           check_every, energy_cap(dt, alpha, 1.0), *out)
    return out


@pytest.mark.parametrize("check_every", [1, 16])
def test_lane_kernel_matches_its_plain_form(check_every):
    """Lanes (polynomial sin/cos at the re-synchronisation) against the plain prange kernel
    (libm): the same discretisation, so statuses equal and labels equal off boundary cells."""
    th, v = _grid(64, 64)
    a, s, n = _run(label_trigfree, th, v, check_every)
    a_ref, s_ref, n_ref = _run(label_trigfree_straightforward, th, v, check_every)
    np.testing.assert_array_equal(s, s_ref)
    differ = a != a_ref
    assert differ.sum() <= 0.005 * th.size
    assert not (differ.reshape(64, 64) & ~boundary_adjacent(a_ref.reshape(64, 64))).any()
    same = ~differ
    assert np.sum(n[same] != n_ref[same]) <= 2
    assert np.all(np.abs(n[same] - n_ref[same]) <= check_every)


def test_edge_cases_take_the_scalar_form():
    """Non-finite input, α < 0 and huge |θ0| go to the scalar form: bit-identical there."""
    th = np.array([0.1, np.nan, 0.0, np.inf, 0.0, 0.5, -2.0, 1.0, 2 * np.pi * 2**30 + 0.1])
    v = np.array([0.0, 0.0, np.nan, 0.0, 4.0, 60.0, -80.0, 1e308, 0.0])
    for alpha in (0.1, -0.05):
        got = _run(label_trigfree, th, v, t_max=5.0, alpha=alpha)
        ref = _run(label_trigfree_straightforward, th, v, t_max=5.0, alpha=alpha)
        counts = label_trigfree(th, v, alpha, 1.0, 0.01, 10, 16, 1.9,
                                *(np.zeros(th.size, t) for t in (np.int32, np.int8, np.int32)))
        scalar = 4 if alpha > 0 else th.size  # NaN θ, NaN/inf θ̇, inf θ, huge θ
        assert list(counts) == [th.size - scalar, 0, scalar]
        for name, x, y in zip(("attractor", "status", "n_trap"), got, ref):
            idx = [1, 2, 3, 8] if alpha > 0 else slice(None)
            np.testing.assert_array_equal(x[idx], y[idx], err_msg=name)


def test_trigfree_labels_differ_from_rk4_only_on_boundary_cells():
    th, v = _grid(64, 64)
    new = atlas.label(th, v, alpha=0.1, omega0=1.0, method="rk4-trigfree")
    old = atlas.label(th, v, alpha=0.1, omega0=1.0)
    np.testing.assert_array_equal(new.status, old.status)
    differ = (new.attractor != old.attractor).reshape(64, 64)
    assert not (differ & ~boundary_adjacent(old.attractor.reshape(64, 64))).any()


@pytest.mark.slow
def test_an_atlas_run_with_the_trigfree_method(tmp_path):
    """``integrator.method: rk4-trigfree``: the file's labels are atlas.label's with that
    method, the file says so, and its separatrices (which set d_cert) are the boundaries of
    that method's RK4 map: trace(method=...)'s, farther from the exact ones than rk4's."""
    from atlas.pipeline.config import load_config
    from tests.helpers import write_config

    cfg = load_config(write_config(tmp_path / "tf.yaml", f"""\
        name: trig-free
        grid:
          theta0: {{start: -3pi, stop: 3pi, num: 40}}
          theta_dot0: {{start: -4, stop: 4, num: 24}}
        integrator: {{method: rk4-trigfree}}
        output: {tmp_path / 'tf.h5'}
    """))
    assert cfg.integrator.method == "rk4-trigfree"
    tree = atlas.run(cfg, quiet=True)
    ds = tree.to_dataset(inherit=False)
    assert ds.attrs["method"] == "rk4-trigfree"
    th, v = np.meshgrid(ds["theta0"].values, ds["theta_dot0"].values)
    ref = atlas.label(th, v, alpha=0.1, omega0=1.0, method="rk4-trigfree")
    np.testing.assert_array_equal(ds["attractor"].values, ref.attractor)
    np.testing.assert_array_equal(ds["t_trap"].values, ref.t_trap)
    sep = tree["separatrices"].to_dataset(inherit=False)
    p = Pendulum(0.1, 1.0)
    window = ((-3 * PI, 3 * PI), (-4.0, 4.0))
    mine = trace(p, *window, method="rk4-trigfree")
    classical = trace(p, *window)
    assert float(sep.attrs["discrepancy"]) == float(mine.attrs["discrepancy"])
    assert float(mine.attrs["discrepancy"]) > 2 * float(classical.attrs["discrepancy"])
    assert "method rk4-trigfree" in sep.attrs["method"]
    assert float(ds["boundary_shift"]) == float(mine.attrs["discrepancy"])


def test_orbit_integrates_with_the_trigfree_method():
    """atlas.commands.orbit_integrate.integrate(method="rk4-trigfree") steps as the method's
    straightforward kernel: the same status and well at random points, t_trap too but at
    rounding ties."""
    from atlas.commands.orbit_integrate import integrate

    rng = np.random.default_rng(8)
    th, v = rng.uniform(-9, 9, 80), rng.uniform(-4, 4, 80)
    ref = atlas.label(th, v, alpha=0.1, omega0=1.0, kernel="straightforward",
                      method="rk4-trigfree")
    orbits = [integrate(a, b, alpha=0.1, omega0=1.0, method="rk4-trigfree")
              for a, b in zip(th, v)]
    np.testing.assert_array_equal([o.status for o in orbits], ref.status)
    np.testing.assert_array_equal([o.k for o in orbits], ref.attractor)
    assert np.mean(np.isclose([o.t_trap for o in orbits], ref.t_trap)) > 0.98
    classical = [integrate(a, b, alpha=0.1, omega0=1.0) for a, b in zip(th[:5], v[:5])]
    # the same steps as classical RK4 would fail this: the methods part by far more than rounding
    assert all(abs(o.theta[n] - c.theta[n]) > 1e-12 for o, c in zip(orbits, classical)
               for n in [min(o.theta.size, c.theta.size, 1000) - 1])
    with pytest.raises(ValueError, match="method"):
        integrate(0.0, 1.0, alpha=0.1, omega0=1.0, method="euler")
    from atlas.commands.orbit import running_barrier_for

    barrier, _ = running_barrier_for(0.05, 1.0, 0.5, 0.01)
    with pytest.raises(ValueError, match="running certificate is established for classical"):
        integrate(0.0, 1.0, alpha=0.05, omega0=1.0, torque=0.5, running=barrier,
                  method="rk4-trigfree")
