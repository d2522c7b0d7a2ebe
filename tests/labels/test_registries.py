"""The method and backend registries: every entry complete and consistent with the names of
atlas.defaults, the lookups :func:`atlas.label` and the pipeline use, and the methods' scalar
forms against their kernels."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest

import atlas
from atlas import defaults, kernels
from atlas.errors import BackendUnavailable
from atlas.kernels import TRAPPED, UNRESOLVED
from atlas.kernels.rk4 import record_straightforward, record_torque
from atlas.kernels.trigfree import SYNC_EVERY, record_trigfree, record_trigfree_torque
from atlas.labels import backends, methods
from atlas.labels.backends import BACKENDS, resolve_method
from atlas.labels.methods import METHODS
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for
from atlas.physics.pendulum import tilt


# ----------------------------------------------------------------------- methods
def test_the_registry_names_are_the_method_tuple():
    assert tuple(METHODS) == defaults.METHODS == kernels.METHODS
    assert all(name == m.name for name, m in METHODS.items())
    assert defaults.METHOD in METHODS


@pytest.mark.parametrize("name", defaults.METHODS)
def test_every_method_has_every_field(name):
    m = METHODS[name]
    for f in dataclasses.fields(m):
        value = getattr(m, f.name)
        assert value is not None, f.name
        if f.type in ("str",) and f.name != "resync":
            assert value, f.name
    assert m.order == 4 and isinstance(m.cuda, bool) and isinstance(m.running, bool)
    fast, plain = m.kernel(), m.kernel(straightforward=True)
    assert callable(fast) and callable(plain) and fast is not plain
    scalar = m.scalar_form()
    assert callable(scalar.step) and callable(scalar.sync)
    assert m.scalar_form() is scalar  # built once


def test_the_registry_points_at_the_kernels():
    from atlas.kernels.lanes import label_lanes, label_trigfree
    from atlas.kernels.rk4 import label_straightforward
    from atlas.kernels.trigfree import label_trigfree_straightforward

    assert METHODS["rk4"].kernel() is label_lanes
    assert METHODS["rk4"].kernel(straightforward=True) is label_straightforward
    assert METHODS["rk4-trigfree"].kernel() is label_trigfree
    assert METHODS["rk4-trigfree"].kernel(straightforward=True) is label_trigfree_straightforward
    # the flags that used to be written as `method != "rk4"` in several places
    assert [m.name for m in METHODS.values() if m.cuda] == ["rk4"]
    assert [m.name for m in METHODS.values() if m.running] == ["rk4"]
    assert METHODS["rk4-trigfree"].resync and not METHODS["rk4"].resync


def test_a_method_checks_its_own_entry():
    with pytest.raises(ValueError, match="not one of"):
        dataclasses.replace(METHODS["rk4"], name="euler")
    with pytest.raises(ValueError, match="Method.lanes"):
        dataclasses.replace(METHODS["rk4"], lanes="label_lanes")
    with pytest.raises(ValueError, match="method must be one of"):
        methods.lookup("euler")
    assert methods.lookup("rk4") is METHODS["rk4"]


def _record(method, theta, theta_dot, alpha, omega0, torque, dt, every, samples):
    """The kernels' trajectories (libm, re-synchronised every SYNC_EVERY steps)."""
    out = np.empty((2, samples, theta.size))
    th, v = theta.copy(), theta_dot.copy()
    if method == "rk4":
        if torque == 0.0:
            record_straightforward(th, v, alpha, omega0, dt, every, out)
        else:
            record_torque(th, v, alpha, omega0, torque, dt, every, out)
    elif torque == 0.0:
        record_trigfree(th, v, alpha, omega0, dt, every, out)
    else:
        record_trigfree_torque(th, v, alpha, omega0, torque, dt, every, out)
    return out


def _scalar_record(method, theta, theta_dot, alpha, omega0, torque, dt, every, samples):
    """The same with the method's scalar form, synchronised every SYNC_EVERY steps."""
    form = METHODS[method].scalar_form()
    shift = tilt(omega0, torque)
    vers = 2.0 * math.sin(0.5 * shift) ** 2
    out = np.empty((2, samples, theta.size))
    for j, (th, v) in enumerate(zip(theta.tolist(), theta_dot.tolist())):
        c, s, _, _ = form.sync(th, v, omega0, torque, shift, vers)
        out[:, 0, j] = th, v
        n = 0
        for i in range(1, samples):
            for _ in range(every):
                th, v, c, s = form.step(th, v, c, s, alpha, omega0, dt, torque)
                n += 1
                if n % SYNC_EVERY == 0:
                    c, s, _, _ = form.sync(th, v, omega0, torque, shift, vers)
            out[:, i, j] = th, v
    return out


@pytest.mark.parametrize("method", defaults.METHODS)
@pytest.mark.parametrize("torque", [0.0, 0.5])
def test_the_scalar_step_is_the_kernels_step(method, torque):
    """The scalar form steps the kernels' discretisation: trajectories of 800 steps from
    states away from the separatrices agree with the kernels' to rounding (the kernels may
    fuse multiply-adds), while the two methods differ by far more."""
    theta = np.array([0.3, -1.2, 2.0, 4.0])
    theta_dot = np.array([0.0, 1.0, -0.5, 3.5])
    args = (theta, theta_dot, 0.1, 1.0, torque, 0.01, 100, 9)
    kernel = _record(method, *args)
    scalar = _scalar_record(method, *args)
    np.testing.assert_allclose(scalar, kernel, rtol=0, atol=1e-12)
    other = [m for m in defaults.METHODS if m != method][0]
    assert np.max(np.abs(_scalar_record(other, *args) - kernel)) > 1e-9


def _scalar_labels(method, theta0, theta_dot0, alpha, omega0, torque, dt, t_max):
    """Label orbits with the scalar form, as the kernels' scalar labeller does (energy trap
    every CHECK_EVERY steps): (status, k, n_trap) arrays."""
    form = METHODS[method].scalar_form()
    cap = energy_cap(dt, alpha, omega0, torque)
    shift = tilt(omega0, torque)
    vers = 2.0 * math.sin(0.5 * shift) ** 2
    n_checks = n_checks_for(t_max, dt, CHECK_EVERY)
    result = []
    for th, v in zip(theta0, theta_dot0):
        got = (UNRESOLVED, 0, -1)
        for j in range(n_checks + 1):
            c, s, k, energy = form.sync(th, v, omega0, torque, shift, vers)
            if energy < cap:
                got = (TRAPPED, k, j * CHECK_EVERY)
                break
            for _ in range(CHECK_EVERY):
                th, v, c, s = form.step(th, v, c, s, alpha, omega0, dt, torque)
        result.append(got)
    return np.array(result).T


@pytest.mark.parametrize("method", defaults.METHODS)
@pytest.mark.parametrize("torque", [0.0, -0.4])
def test_the_scalar_form_labels_as_the_straightforward_kernel(method, torque):
    rng = np.random.default_rng(11)
    theta0, theta_dot0 = rng.uniform(-6.0, 6.0, 16), rng.uniform(-2.5, 2.5, 16)
    alpha, omega0, dt, t_max = 0.3, 1.0, 0.02, 40.0
    status, k, n_trap = _scalar_labels(method, theta0, theta_dot0, alpha, omega0, torque, dt,
                                       t_max)
    ref = atlas.label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=torque, dt=dt,
                      t_max=t_max, method=method, kernel="straightforward")
    assert (status == TRAPPED).sum() >= 12
    np.testing.assert_array_equal(status, ref.status)
    trapped = status == TRAPPED
    np.testing.assert_array_equal(k[trapped], ref.attractor[trapped])
    np.testing.assert_allclose(n_trap[trapped] * dt, ref.t_trap[trapped], rtol=1e-6)


# ----------------------------------------------------------------------- backends
def test_every_backend_has_every_field():
    assert tuple(BACKENDS) == ("cpu", "cuda")
    assert BACKENDS["cpu"].tile_orbits == defaults.TILE_ORBITS
    assert BACKENDS["cuda"].tile_orbits == defaults.TILE_ORBITS_CUDA
    assert BACKENDS["cpu"].methods == defaults.METHODS
    assert BACKENDS["cuda"].methods == tuple(m.name for m in METHODS.values() if m.cuda)
    for name, b in BACKENDS.items():
        assert b.name == name and b.summary and set(b.methods) <= set(defaults.METHODS)
        assert b.default_method == defaults.METHOD
        assert backends.lookup(name) is b
    with pytest.raises(ValueError, match="backend must be one of"):
        backends.lookup("tpu")


def test_availability_is_reported_in_one_line():
    from atlas.kernels.cuda import cuda_status

    assert BACKENDS["cpu"].available() == (True, BACKENDS["cpu"].summary)
    BACKENDS["cpu"].require()
    ok, why = BACKENDS["cuda"].available()
    assert (ok, why) == cuda_status()
    assert isinstance(ok, bool) and why and "\n" not in why
    if not ok:
        with pytest.raises(BackendUnavailable) as err:
            BACKENDS["cuda"].require()
        message = str(err.value)
        assert message.startswith("backend 'cuda': ") and "\n" not in message
        assert "pendulum-atlas[cuda]" in message


def test_a_backend_hands_out_the_kernel_of_a_method():
    from atlas.kernels.cuda_host import label_cuda

    cpu, cuda = BACKENDS["cpu"], BACKENDS["cuda"]
    for name, m in METHODS.items():
        assert cpu.kernel(name) is m.kernel()
        assert cpu.kernel(name, "straightforward") is m.kernel(straightforward=True)
    for variant, expected in ((None, "fast"), ("straightforward", "straightforward")):
        k = cuda.kernel("rk4", variant)
        assert isinstance(k, functools.partial) and k.func is label_cuda
        assert k.keywords == {"variant": expected}
    with pytest.raises(ValueError, match="method: 'rk4-trigfree' has no CUDA kernel"):
        cuda.kernel("rk4-trigfree")
    with pytest.raises(ValueError, match="kernel must be one of"):
        cpu.kernel("rk4", "lanes")
    with pytest.raises(ValueError, match="method must be one of"):
        cpu.kernel("euler")


def test_resolve_method_is_what_label_runs():
    assert resolve_method("cpu", None, None) == defaults.METHOD
    assert resolve_method("cuda", "straightforward", None) == "rk4"
    assert resolve_method("cpu", "straightforward", "rk4-trigfree") == "rk4-trigfree"
    with pytest.raises(ValueError, match="no CUDA kernel"):
        resolve_method("cuda", None, "rk4-trigfree")
    with pytest.raises(ValueError, match="backend must be one of"):
        atlas.label([0.1], [0.0], alpha=0.1, omega0=1.0, backend="dask")
