"""``atlas bench``, the driven pendulum's rows: the stroboscopic map's kernel against a
NumPy RK4 of the same map, and the three-basin atlas (``configs/driven.yaml``'s drive) end to
end, with the share of it spent outside the kernel.

The kernel row applies P (one drive period, N = 200 RK4 steps; α = 0.1 s⁻¹, ω0 = 1 rad s⁻¹,
A = 1.66 rad s⁻², Ω = 1 rad s⁻¹) to orbits spread over the Wada window with
:func:`atlas.kernels.driven.advance`, and the reference applies the same map with a NumPy
RK4 vectorised over the orbits (the drive evaluated once per stage, as the kernel's table);
both in this process, one after the other, so that their ratio compares like with like on
a loaded machine. The reference's states must agree with the kernel's to 1e-9 (said in the
row's note), so that the two compute the same thing. The end-to-end row is one ``atlas run``
of a 1000² atlas in a fresh interpreter, after a small warm-up run; the next row sets it
against the kernel alone labelling the same grid. Quick: fewer orbits and a 100² atlas.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np

from atlas.commands.bench_e2e import phase_seconds, run_python
from atlas.commands.bench_gpu_driven import DRIVE

__all__ = ["driven_rows", "TITLE", "numpy_periods"]

TITLE = "driven pendulum: the stroboscopic map's kernel against NumPy, the Wada atlas"

#: configs/driven.yaml's drive, as the GPU rows run it (the CPU bench calls the GPU's)
_ALPHA, _OMEGA0, _, _AMPLITUDE, _FREQUENCY, _, _STEPS = DRIVE
#: The phase of ``atlas run -v`` that labels the tiles (the kernel's part of a run).
_MAP_PHASE = "map (label and certify tiles)"


def numpy_periods(theta: np.ndarray, theta_dot: np.ndarray, periods: int) -> None:
    """The reference: P applied ``periods`` times in place by classical RK4 in NumPy (dt =
    T/200), vectorised over the orbits."""
    dt = 2 * math.pi / _FREQUENCY / _STEPS

    def accel(th, v, t):
        return (_AMPLITUDE * math.cos(_FREQUENCY * t) - _OMEGA0 ** 2 * np.sin(th)
                - 2 * _ALPHA * v)

    for p in range(periods):
        for j in range(_STEPS):
            t = (p * _STEPS + j) * dt
            k1t, k1v = theta_dot, accel(theta, theta_dot, t)
            k2t = theta_dot + 0.5 * dt * k1v
            k2v = accel(theta + 0.5 * dt * k1t, k2t, t + 0.5 * dt)
            k3t = theta_dot + 0.5 * dt * k2v
            k3v = accel(theta + 0.5 * dt * k2t, k3t, t + 0.5 * dt)
            k4t = theta_dot + dt * k3v
            k4v = accel(theta + dt * k3t, k4t, t + dt)
            theta += dt / 6 * (k1t + 2 * k2t + 2 * k3t + k4t)
            theta_dot += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)


def _orbits(n: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    return rng.uniform(-math.pi, math.pi, n), rng.uniform(-2.0, 4.0, n)


def _kernel_row(quick: bool) -> dict:
    from atlas.kernels import driven

    table = driven.forcing_table(_AMPLITUDE, _FREQUENCY, 0.0, _STEPS)
    dt = driven.step_size(_FREQUENCY, _STEPS)
    n, periods = (20_000, 2) if quick else (100_000, 5)
    for size in (n, 2_000 if quick else 10_000):  # untimed: the kernels of both batch sizes
        theta, theta_dot = _orbits(size)  # compiled (or loaded from the cache)
        driven.advance(theta, theta_dot, _ALPHA, _OMEGA0, 0.0, table, dt, 1)
    theta, theta_dot = _orbits(n)
    start = time.perf_counter()
    driven.advance(theta, theta_dot, _ALPHA, _OMEGA0, 0.0, table, dt, periods)
    kernel_s = time.perf_counter() - start
    ref_n = 2_000 if quick else 10_000
    ref_theta, ref_dot = _orbits(n)
    ref_theta, ref_dot = ref_theta[:ref_n].copy(), ref_dot[:ref_n].copy()
    start = time.perf_counter()
    numpy_periods(ref_theta, ref_dot, 1)
    numpy_s = time.perf_counter() - start
    check_theta, check_dot = _orbits(n)
    check_theta, check_dot = check_theta[:ref_n].copy(), check_dot[:ref_n].copy()
    driven.advance(check_theta, check_dot, _ALPHA, _OMEGA0, 0.0, table, dt, 1)
    differ = float(max(np.abs(check_theta - ref_theta).max(), np.abs(check_dot - ref_dot).max()))
    kernel_rate = n * periods * _STEPS / kernel_s
    numpy_rate = ref_n * _STEPS / numpy_s
    return {"variant": f"kernel: P on {n:,} orbits x {periods} periods (N = {_STEPS}), "
                       f"{kernel_rate / 1e6:.0f} M RK4 steps/s",
            "wall_s": kernel_s, "ratio": kernel_rate / numpy_rate,
            "against": f"NumPy RK4 of the same map, {numpy_rate / 1e6:.1f} M steps/s",
            "note": f"ratio = speed-up; the NumPy states agree to {differ:.1e} after one "
                    "period (must be < 1e-9)"}


#: A fresh interpreter's rate of :func:`atlas.kernels.driven.advance` (M RK4 steps/s, the
#: best of three calls after a warm-up) and the features Numba compiled for.
_WIDTH_SCRIPT = """
import hashlib, json, math, time
import numpy as np
from atlas.kernels import driven
import numba
n, periods = {n}, {periods}
rng = np.random.default_rng(0)
theta0, theta_dot0 = rng.uniform(-math.pi, math.pi, n), rng.uniform(-2.0, 4.0, n)
table = driven.forcing_table({amplitude}, {frequency}, 0.0, {steps})
dt = driven.step_size({frequency}, {steps})
best = math.inf
for i in range(4):
    theta, theta_dot = theta0.copy(), theta_dot0.copy()
    start = time.perf_counter()
    driven.advance(theta, theta_dot, {alpha}, {omega0}, 0.0, table, dt, periods if i else 1)
    if i:
        best = min(best, time.perf_counter() - start)
print(json.dumps({{"rate": n * periods * {steps} / best / 1e6,
                  "features": numba.config.CPU_FEATURES or "",
                  "digest": hashlib.sha256(theta.tobytes() + theta_dot.tobytes()).hexdigest()}}))
"""


def _width_row(quick: bool) -> dict:
    """The driven kernel at 512-bit vectors (:mod:`atlas.kernels.vector_width`, this
    machine's default where the CPU has AVX-512) against LLVM's own choice
    (``ATLAS_VECTOR_BITS=256``), each in fresh interpreters taking turns (three each, the
    fastest counted; one in quick)."""
    import json

    from atlas.kernels.vector_width import TUNING

    n, periods = (20_000, 2) if quick else (100_000, 5)
    script = _WIDTH_SCRIPT.format(n=n, periods=periods,
                                  alpha=_ALPHA, omega0=_OMEGA0, amplitude=_AMPLITUDE,
                                  frequency=_FREQUENCY, steps=_STEPS)
    out = {}
    for _ in range(1 if quick else 3):  # alternated, the best of each: a shared machine's
        for name, env in (("wide", {}), ("llvm", {"ATLAS_VECTOR_BITS": "256"})):  # speed
            _, done = run_python(["-c", script], **env)  # drifts within seconds
            got = json.loads(done.stdout.strip().splitlines()[-1])
            if name not in out or got["rate"] > out[name]["rate"]:
                out[name] = got
    wide = out["wide"]["features"].endswith(f"-{TUNING}")
    return {"variant": f"driven kernel at {'512' if wide else 'the default'}-bit vectors, "
                       f"{out['wide']['rate']:.0f} M RK4 steps/s",
            "wall_s": n * periods * _STEPS / (out["wide"]["rate"] * 1e6),
            "ratio": out["wide"]["rate"] / out["llvm"]["rate"],
            "against": f"LLVM's own width (ATLAS_VECTOR_BITS=256), "
                       f"{out['llvm']['rate']:.0f} M steps/s",
            "note": "ratio = speed-up; " + (
                "the same states: " + str(out["wide"]["digest"] == out["llvm"]["digest"])
                if wide else "this CPU has no AVX-512 or the width was set by the user: "
                             "both ran alike")}


def _atlas_rows(quick: bool) -> list[dict]:
    """The three-basin atlas over [−π, π] × [−4, 4], 1000² (quick: 100²), end to end in a
    fresh interpreter (``atlas run -v``, after a small warm-up run), and the share of that
    time spent outside its map phase (labelling and checking the tiles at dt and dt/2), from
    the run's own phase lines: one run, so the machine's drift from one minute to the next
    does not enter. For reference, the kernel alone labelling the same grid twice in this
    process, from the file's attractors (the map phase adds the tiles' tallies and writes)."""
    import atlas
    from atlas.layout import point_group, points
    from atlas.models.driven.points import stored_point

    num = 100 if quick else 1000
    config = ("name: {name}\npendulum:\n  alpha: 0.1\n  omega0: 1.0\n"
              "  drive: {{amplitude: 1.66, frequency: 1.0}}\n"
              "grid:\n  theta0: {{start: -pi, stop: pi, num: {num}}}\n"
              "  theta_dot0: {{start: -4.0, stop: 4.0, num: {num}}}\n"
              "integrator: {{dt: pi/100, t_max: 1000.0}}\noutput: {output}\n")
    with tempfile.TemporaryDirectory(prefix="atlas-bench-driven-") as tmp:
        folder = Path(tmp)
        for name, n in (("warm", 24), ("driven", num)):
            path = folder / f"{name}.yaml"
            path.write_text(config.format(name=name, num=n, output=folder / f"{name}.h5"))
            wall, done = run_python(["-m", "atlas", "run", str(path), "-v"])
        map_s = phase_seconds(done.stderr)[_MAP_PHASE]
        tree = atlas.open(folder / "driven.h5")
        ds = tree.to_dataset(inherit=False)
        params = points(ds)[0]
        point = stored_point(point_group(tree, "attractors", params), params,
                             float(ds.attrs["t_max"]))
        x0, v0 = ds["theta0"].values[None, :], ds["theta_dot0"].values[:, None]
        point.label(x0[:, :8], v0[:8])  # untimed: compiled or loaded from the cache
        start = time.perf_counter()
        attractor = point.label(x0, v0)[0]
        point.halved().label(x0, v0)
        kernel_s = time.perf_counter() - start
        same = float(np.mean(attractor == ds["attractor"].values))
    return [{"variant": f"three-basin atlas (A = 1.66), {num}² over [-pi, pi] x [-4, 4], "
                        "every label checked at dt/2, end to end",
             "wall_s": wall, "ratio": float("nan"), "against": "-",
             "note": "atlas run in a fresh interpreter; includes start-up and the attractors' "
                     "search; goal 30 s at 1000² on 2 cores"},
            {"variant": "  its share outside the kernel's map phase", "wall_s": wall - map_s,
             "ratio": (wall - map_s) / wall,
             "against": f"its map phase, {map_s:.1f} s (the kernel alone in this process: "
                        f"{kernel_s:.1f} s for both passes)",
             "note": f"ratio = share of the run outside the map phase (goal < 0.2); the "
                     f"kernel alone gives the file's labels at {same:.2%} of the points"}]


def _sweep_rows(quick: bool) -> list[dict]:
    """``atlas stability`` of the amplitude sweep (configs/driven_sweep.yaml's: A from 1 to
    2, 101 points, 10⁴ samples each; quick: 3 points of A in [1, 1.1], where nothing is born
    or dies, 1,000 samples) in a fresh interpreter,
    on this machine's threads and on a local Dask cluster (not in quick), with the same
    arrays."""
    import xarray as xr

    num, samples, stop = (3, 1000, 1.1) if quick else (101, 10_000, 2.0)
    config = ("name: sweep\npendulum:\n  alpha: 0.1\n  omega0: 1.0\n"
              f"  drive: {{amplitude: {{start: 1.0, stop: {stop}, num: {num}}}, "
              "frequency: 1.0}\n"
              "grid:\n  theta0: {start: -pi, stop: pi, num: 2}\n"
              "  theta_dot0: {start: -2.0, stop: 4.0, num: 2}\n"
              "integrator: {dt: pi/100, t_max: 1000.0}\n"
              f"stability: {{samples: {samples}, seed: 0}}\noutput: {{output}}\n")
    rows, arrays = [], {}
    with tempfile.TemporaryDirectory(prefix="atlas-bench-sweep-") as tmp:
        for backend in ("cpu",) if quick else ("cpu", "dask"):
            out = Path(tmp) / f"{backend}.h5"
            path = Path(tmp) / f"{backend}.yaml"
            path.write_text(config.replace("{output}", str(out)))
            wall, _ = run_python(["-m", "atlas", "stability", str(path), "--backend",
                                  backend])
            with xr.open_dataset(out, engine="h5netcdf") as ds:
                arrays[backend] = ds["basin_fraction"].values.copy()
            rows.append({"variant": f"sweep of A in [1, {stop:g}], {num} points x {samples:,} "
                                    f"samples, attractors matched, events bisected "
                                    f"({backend})",
                         "wall_s": wall, "ratio": float("nan"), "against": "-",
                         "note": "atlas stability in a fresh interpreter; goal 300 s for "
                                 "101 x 10,000 on 2 cores"})
    if "dask" in arrays:
        same = np.array_equal(arrays["cpu"], arrays["dask"], equal_nan=True)
        rows[-1]["note"] += f"; the same fractions as on threads: {same}"
    return rows


def driven_rows(quick: bool) -> list[dict]:
    """The rows (``atlas.commands.bench``'s row shape): the kernel against NumPy and at both
    vector widths, the Wada atlas end to end, the amplitude sweep."""
    return [_kernel_row(quick), _width_row(quick), *_atlas_rows(quick), *_sweep_rows(quick)]
