"""Shared by the zoom tests (test_zoom_windows.py, test_zoom_windows_torque.py): zooms
into a basin boundary and into a saddle, with and without torque (issue 26).

Windows 1 down to 1e-9 wide (the narrowest the default tol allows) around a boundary point
and a saddle each finish (a hang would time the suite out), trace the boundary inside
themselves and measure there the shift that d_cert is built on; the certified labels of the
grid points closest to the boundary (the CLOSEST nearest that are certified: some at every
width, unless nothing is certified, which is then asserted with its reason) are an
independent DOP853 integration's (rtol = atol = 1e-13); and the boundary count and shift
reported agree with the labels of the window: where both sides' labels occur, a boundary is
traced and a shift measured, or nothing is certified. Windows narrower than 1000 tol are
refused by the config, with one line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import atlas
from atlas.boundaries.certificate import cert_distance, labelled
from atlas.status import RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED

#: (torque, θ0, θ̇0) of the zoom centres: the k = 0 | 1 boundary on θ0 = 0 and the saddle
#: (π, 0) at α = 0.1, ω0 = 1; with τ = 0.3 (bistable: tongues in a running basin) the
#: exact boundary's crossing of θ0 = 0 (atlas.boundaries.tilted, to its chord error 1e-8)
#: and the tilted saddle (π − arcsin 0.3, 0).
CENTRES = {"boundary": (0.0, 0.0, 2.4149382176), "saddle": (0.0, math.pi, 0.0),
           "tilted boundary": (0.3, 0.0, 1.888028823945676),
           "tilted saddle": (0.3, math.pi - math.asin(0.3), 0.0)}
ALPHA, OMEGA0 = 0.1, 1.0
FAST = {("boundary", 1e-4), ("saddle", 1e-8)}
WIDTHS = (1.0, 1e-2, 1e-4, 1e-6, 1e-8, 1e-9)
CLOSEST = 6  # grid points nearest the boundary checked against DOP853


def _reference(theta0: float, theta_dot0: float, torque: float):
    """The exact equation's attractor from (θ0, θ̇0) by scipy's DOP853 (rtol = atol = 1e-13):
    well k once the energy is below the lower saddle beside the well the orbit is in (it
    can never leave: the energy only falls), "running" once it has turned for 100 s with
    θ̇ > 0 throughout after 200 s; None if neither by 3000 s."""
    from scipy.integrate import solve_ivp

    w2 = OMEGA0**2
    star = math.asin(torque / w2)

    def rhs(_, y):
        return [y[1], -w2 * math.sin(y[0]) - 2 * ALPHA * y[1] + torque]

    def trapped(y):
        k = round((y[0] - star) / (2 * math.pi))
        left, right = -math.pi - star + 2 * math.pi * k, math.pi - star + 2 * math.pi * k
        energy = 0.5 * y[1] ** 2 - w2 * math.cos(y[0]) - torque * y[0]
        barrier = min(-w2 * math.cos(s) - torque * s for s in (left, right))
        return k if left < y[0] < right and energy < barrier else None

    y, t = np.array([theta0, theta_dot0], float), 0.0
    while t < 3000.0:
        sol = solve_ivp(rhs, (t, t + 50.0), y, method="DOP853", rtol=1e-13, atol=1e-13)
        y, t = sol.y[:, -1], t + 50.0
        if (k := trapped(y)) is not None:
            return k
        if torque and t >= 200.0:
            later = solve_ivp(rhs, (t, t + 100.0), y, method="DOP853", rtol=1e-13,
                              atol=1e-13)
            if later.y[1].min() > 0.0:
                return "running"
    return None


def _zoom(tmp_path, name: str, width: float):
    torque, theta, speed = CENTRES[name]
    h = 0.5 * width
    cfg = tmp_path / "zoom.yaml"
    cfg.write_text(f"""\
pendulum: {{alpha: {ALPHA}, omega0: {OMEGA0}, torque: {torque!r}}}
grid:
  theta0: {{start: {theta - h!r}, stop: {theta + h!r}, num: 9}}
  theta_dot0: {{start: {speed - h!r}, stop: {speed + h!r}, num: 9}}
integrator: {{dt: 0.01, t_max: 1000.0}}
output: {tmp_path / 'zoom.h5'}
""")
    ds = atlas.run(atlas.load_config(cfg), quiet=True).to_dataset(inherit=False)
    sep = atlas.open(tmp_path / "zoom.h5")["separatrices"]
    return ds, sep


#: Zooms that cannot be made: the tilted boundary's centre is known to its chord error
#: (1e-8) and the RK4 map's boundary lies ≈ 1e-9 from the exact one, so a window 1e-9 wide
#: around it need not hold the boundary at all.
UNRESOLVED = {("tilted boundary", 1e-9)}


def cases(names):
    """The zooms of ``names`` at every width (but :data:`UNRESOLVED`), the FAST ones
    unmarked, the others slow."""
    return [pytest.param(name, width, id=f"{name}-{width:g}",
                         marks=() if (name, width) in FAST else pytest.mark.slow)
            for name in names for width in WIDTHS if (name, width) not in UNRESOLVED]


def check_zoom(tmp_path, name: str, width: float) -> None:
    """The checks of the module docstring for one zoom: ``name`` a key of CENTRES."""
    ds, sep = _zoom(tmp_path, name, width)
    torque = CENTRES[name][0]
    status = ds["status"].values
    attractor = ds["attractor"].values.astype(np.int64)
    theta0, theta_dot0 = ds["theta0"].values, ds["theta_dot0"].values
    dist = ds["boundary_distance"].values
    d_cert = float(ds["d_cert"])
    certified = (status == TRAPPED) | (status == RUNNING)

    # the boundary crosses the window: both sides' labels occur, and it was traced inside it
    running = (status == RUNNING) | (status == RUNNING_NEAR_BOUNDARY)
    basins = set(np.where(running, -1, attractor)[labelled(status) | running].tolist())
    assert len(basins) >= 2
    inside = ((sep["theta"].values >= theta0[0]) & (sep["theta"].values <= theta0[-1])
              & (sep["theta_dot"].values >= theta_dot0[0])
              & (sep["theta_dot"].values <= theta_dot0[-1]))
    shift = float(sep.attrs["discrepancy"])
    if certified.any():
        # a certificate stands on a shift measured in this window, on a boundary traced here
        assert inside.any() and int(sep.attrs["n_boundaries"]) >= 1
        assert math.isfinite(shift) and float(ds["boundary_shift"]) == shift
        assert d_cert == cert_distance(shift, float(sep.attrs["tol"]),
                                       float(ds["boundary_reference_error"]))
        np.testing.assert_array_equal(certified, certified & (dist > d_cert))
    else:
        assert not math.isfinite(d_cert) or not (dist > d_cert).any()

    # the certified labels nearest the boundary are the exact equation's: at every width
    # some are compared, unless none can be (nothing certified: asserted above, with why)
    order = np.array([i for i in np.argsort(dist, axis=None) if certified.flat[i]][:CLOSEST],
                     np.intp)
    assert len(order) == min(CLOSEST, int(certified.sum()))
    assert order.size or not certified.any()
    for row, col in zip(*np.unravel_index(order, dist.shape)):
        want = _reference(float(theta0[col]), float(theta_dot0[row]), torque)
        got = "running" if status[row, col] == RUNNING else int(attractor[row, col])
        assert want == got, (theta0[col], theta_dot0[row], want, got, dist[row, col])
