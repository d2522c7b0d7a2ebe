"""Helpers shared by the test modules: small configs, the CLI in a subprocess, a crash
injected mid-run, and an independent reference integrator (scipy's DOP853).

Import them with ``from tests.helpers import ...``; fixtures live in ``conftest.py``."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


def dop853_attractor(theta0, theta_dot0, alpha, omega0, t_end=200.0):
    """Independent reference label: integrate eq. (1) with scipy's DOP853 (rtol 1e-11) until
    the orbit is deep inside a well (E_k below half the saddle energy, far from any trap
    margin question) or t_end; None if it has not got there."""
    from scipy.integrate import solve_ivp

    def rhs(_, y):
        return [y[1], -omega0**2 * np.sin(y[0]) - 2 * alpha * y[1]]

    def low_energy(_, y):  # E_k < ω0² for the nearest well k
        k = np.round(y[0] / (2 * np.pi))
        return 0.5 * y[1] ** 2 + omega0**2 * (1 - np.cos(y[0] - 2 * np.pi * k)) - omega0**2

    low_energy.terminal = True
    if low_energy(0.0, (theta0, theta_dot0)) < 0:
        return round(theta0 / (2 * np.pi))
    sol = solve_ivp(rhs, (0.0, t_end), [theta0, theta_dot0], method="DOP853", rtol=1e-11,
                    atol=1e-12, events=low_energy)
    theta, theta_dot = sol.y[:, -1]
    if sol.status != 1:
        return None
    return round(theta / (2 * np.pi))


def boundary_adjacent(labels: np.ndarray) -> np.ndarray:
    """Cells with a 4-neighbour of a different label (or a neighbour without a label)."""
    adj = np.zeros(labels.shape, bool)
    for axis in (0, 1):
        diff = np.diff(labels, axis=axis) != 0
        lo = [slice(None)] * 2
        hi = [slice(None)] * 2
        lo[axis] = slice(None, -1)
        hi[axis] = slice(1, None)
        adj[tuple(lo)] |= diff
        adj[tuple(hi)] |= diff
    return adj


def write_config(path: Path, body: str) -> Path:
    path.write_text(textwrap.dedent(body))
    return path


SMALL = """\
name: small
pendulum: {{alpha: 0.1, omega0: 1.0}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 24}}
  theta_dot0: {{start: -4, stop: 4, num: 16}}
integrator: {{dt: 0.01, t_max: 200}}
separatrices: {{enabled: {sep}}}
execution: {{tile_orbits: 100}}
output: {output}
"""


def study_config(path: Path, pendulum: str, output, extra: str = "") -> Path:
    """A small study's config at ``path``: ``pendulum`` the body of its flow mapping (e.g.
    ``"alpha: 0.1, omega0: {start: 0.5, stop: 1.5, num: 5}, torque: 0.3"``), STUDY_BODY's
    2π × 6 window, the lines ``extra`` (``"stability: {tipping: true}\\n"``) and ``output``."""
    return write_config(path, (f"pendulum: {{{pendulum}}}\n"
                               "grid:\n  theta0: {start: -pi, stop: pi, num: 2}\n"
                               "  theta_dot0: {start: -3, stop: 3, num: 2}\n"
                               f"{extra}output: {output}\n"))


def run_cli(*args, cwd=None, env=None, timeout=300):
    """Run the real ``atlas`` CLI in a subprocess."""
    return subprocess.run([sys.executable, "-m", "atlas.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=timeout)


def crash_on_tile(monkeypatch, call: int, error: BaseException) -> None:
    """Make the sweep's ``call``-th tile computation raise ``error`` (a crash mid-run): its
    labelling, the part of a tile that the local scheduler starts ahead (and that
    ``compute_tile`` calls)."""
    from atlas.pipeline import schedule

    real, calls = schedule.label_tile, []

    def crashing(*args, **kwargs):
        calls.append(1)
        if len(calls) == call:
            raise error
        return real(*args, **kwargs)

    monkeypatch.setattr(schedule, "label_tile", crashing)


def lock_is_free(output: Path) -> bool:
    """True if no process holds ``output``'s lock (taking it to see: it is removed again)."""
    from atlas.pipeline.lock import OutputLocked, output_lock

    try:
        with output_lock(Path(output)):
            return True
    except OutputLocked:
        return False


#: The bistable swing pendulum of bSTAB's pendulum case (tilted wells and a running cycle).
SWING = {"alpha": 0.05, "omega0": 1.0, "torque": 0.5}


def small_atlas(directory: Path, name: str, pendulum: dict, *, theta=("-5pi/6", "7pi/6"),
                speed=(-6.0, 6.0), num=(36, 30), t_max: float = 400.0,
                separatrices: bool = True):
    """``atlas.run`` of a small atlas into ``directory/NAME.h5`` (θ0 and θ̇0 windows,
    ``num`` = (columns, rows), dt = 0.01); the DataTree. Defaults: the swing window."""
    import atlas

    cfg = atlas.Config.model_validate({
        "name": name, "pendulum": pendulum,
        "grid": {"theta0": {"start": theta[0], "stop": theta[1], "num": num[0]},
                 "theta_dot0": {"start": speed[0], "stop": speed[1], "num": num[1]}},
        "integrator": {"dt": 0.01, "t_max": t_max},
        "separatrices": {"enabled": separatrices},
        "output": str(Path(directory) / f"{name}.h5")})
    return atlas.run(cfg, quiet=True)


#: A small stability study's config (``atlas stability``): α = 0.2, ω0 = 1, a 2π × 6 window;
#: ``{torque}`` (a number, a list or a range) and ``{output}`` filled by the test.
STUDY_BODY = """\
name: study
pendulum: {{alpha: 0.2, omega0: 1.0, torque: {torque}}}
grid:
  theta0: {{start: -pi, stop: pi, num: 2}}
  theta_dot0: {{start: -3, stop: 3, num: 2}}
output: {output}
"""


def host_has_fma() -> bool:
    """Whether this host's CPU has fused multiply-add, as Numba's compiler (LLVM) sees it:
    the pinned bytes of atlas's kernels (tests/kernels/test_torque_kernels.py,
    tests/tools/test_identity.py) were made on such a host, where LLVM contracts a·b + c into
    one rounding; a host without it rounds twice and gives other last bits."""
    from llvmlite import binding

    return bool(binding.get_host_cpu_features().get("fma"))


#: Skip a test of pinned bytes on a host whose arithmetic rounds differently (no FMA).
needs_fma = pytest.mark.skipif(not host_has_fma(), reason="the pinned bytes were made on a "
                               "host with FMA; this CPU rounds a·b + c twice")
