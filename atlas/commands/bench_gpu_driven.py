"""GPU benchmark, the driven pendulum's row: the three-basin atlas (``configs/driven.yaml``'s
drive) labelled by :func:`atlas.kernels.driven_cuda.label_driven_cuda` against this
machine's CPU kernel (:func:`atlas.kernels.driven.label_driven`) on a sample of the same
orbits, for ``atlas bench --backend cuda`` (:func:`atlas.commands.bench_gpu.run_gpu_bench`).
A GPU module: it imports no module of the CPU bench.
"""

from __future__ import annotations

import math
import time

import numpy as np

__all__ = ["gpu_row", "gpu_line", "DRIVE"]

#: (α [s⁻¹], ω0 [rad s⁻¹], τ [rad s⁻²], A [rad s⁻²], Ω [rad s⁻¹], φ [rad], N): the drive of
#: configs/driven.yaml (Wagemakers, Daza & Sanjuán 2021's three Wada basins), T/200.
DRIVE = (0.1, 1.0, 0.0, 1.66, 1.0, 0.0, 200)


def gpu_row(n: int, repeats: int, sample: int = 20_000) -> dict:
    """The three-basin atlas's labelling (A = 1.66, n × n over [−π, π] × [−4, 4], N = 200,
    t_max = 1000 s; its attractors found on the CPU first, untimed) by
    :func:`atlas.kernels.driven_cuda.label_driven_cuda`, host to host, the median of
    ``repeats`` calls after one that compiles; and :func:`atlas.kernels.driven.label_driven`
    (this machine's CPU kernel) on a seeded sample of ``sample`` of the same orbits, whose
    labels and statuses the GPU's must give (the share that does is reported: the GPU's
    fused multiply-adds and the CPU's may differ in the last bit, which a fractal boundary
    can grow into another label). The CPU's rate comes from the sample, the GPU's from the
    whole grid: orbits drawn at random from it cost the same on average. For ``atlas bench
    --backend cuda`` (:func:`atlas.commands.bench_gpu.run_gpu_bench`)."""
    from atlas.kernels import driven
    from atlas.kernels.driven_cuda import label_driven_cuda
    from atlas.models.driven.attractors import Drive
    from atlas.models.driven.description import MAX_PERIOD
    from atlas.models.driven.points import prepared

    drive = Drive(*DRIVE)
    point = prepared(drive, ((-math.pi, math.pi), (-4.0, 4.0)), MAX_PERIOD, 1000.0)[0]
    theta, theta_dot = np.meshgrid(np.linspace(-math.pi, math.pi, n), np.linspace(-4, 4, n))
    theta, theta_dot = theta.ravel(), theta_dot.ravel()
    args = (drive.alpha, drive.omega0, drive.torque, drive.table, drive.dt, point.targets,
            point.target_attractor, point.radius, point.confirm, point.max_periods)
    label_driven_cuda(theta[:64], theta_dot[:64], *args)  # untimed: compiles
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        attractor, periods, status = label_driven_cuda(theta, theta_dot, *args)
        times.append(time.perf_counter() - start)
    gpu_s = float(np.median(times))
    pick = np.random.default_rng(0).choice(theta.size, min(sample, theta.size), replace=False)
    driven.label_driven(theta[pick][:8], theta_dot[pick][:8], *args)  # untimed: loads
    start = time.perf_counter()
    cpu = driven.label_driven(theta[pick], theta_dot[pick], *args)
    cpu_s = time.perf_counter() - start
    same = (cpu[0] == attractor[pick]) & (cpu[2] == status[pick])
    gpu_rate, cpu_rate = theta.size / gpu_s, pick.size / max(cpu_s, 1e-9)
    return {"n": n, "orbits": int(theta.size), "gpu_s": gpu_s, "gpu_orbits_per_s": gpu_rate,
            "gpu_gsteps_s": float(periods.sum()) * DRIVE[-1] / gpu_s / 1e9,
            "cpu_sample": int(pick.size), "cpu_orbits_per_s": cpu_rate,
            "speedup": gpu_rate / cpu_rate, "agree_fraction": float(np.mean(same))}


def gpu_line(row: dict) -> str:
    """:func:`gpu_row` as one line of ``atlas bench --backend cuda``'s table."""
    n = row["n"]
    return (f"driven: the three-basin map (A = 1.66) {n}x{n} labelled on the GPU in "
            f"{row['gpu_s']:.2f} s ({row['gpu_orbits_per_s'] / 1e6:.1f} M orbits/s, "
            f"{row['gpu_gsteps_s']:.1f} G RK4 steps/s), {row['speedup']:.0f}x this machine's "
            f"CPU kernel (on {row['cpu_sample']:,} of the orbits, of which "
            f"{row['agree_fraction']:.2%} get the same label and status)")
