"""GPU benchmark: the CUDA kernels of :mod:`atlas.kernels.cuda` on the default problem.

On an n × n grid of the default window (:mod:`atlas.defaults`), for each kernel variant
("fast": wrapped θ and a reduced-range polynomial sin; "straightforward": libdevice sin): the
basin map (kernel time by CUDA events, the wall time of :func:`label_cuda` host to host, and
effective steps/s), bulk steps/s without early exit, the GPU's labels against the CPU's on
the same grid (the share equal; the largest exact-boundary distance of those that differ),
and :func:`atlas.run` with backend "cuda" end to end (:func:`sweep_rows`; 16384² on request:
``atlas bench --backend cuda --gpu-sweep 16384``); the driven pendulum's three-basin map
labelled on the GPU against the CPU kernel (:func:`atlas.commands.bench_gpu_driven.gpu_row`).
Plus a JAX peer when JAX sees a GPU.
Without a CUDA GPU :func:`run_gpu_bench` returns None. Details: ``docs/design/bench.md``.
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from atlas import defaults
from atlas.commands.bench_gpu_driven import gpu_line, gpu_row
from atlas.kernels.cuda import VARIANTS, cuda_status, kernels
from atlas.kernels.cuda_host import label_cuda
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for
from atlas.status import TRAPPED, UNRESOLVED

__all__ = ["run_gpu_bench", "format_gpu_rows", "TARGETS"]

#: Targets on one H100 at n = 4096 (a straightforward kernel measured ≈ 42 ms, ≈ 110 G steps/s).
TARGETS = {"label_ms": 30.0, "bulk_gsteps_s": 150.0}


def _event_ms(cuda, launch, repeats):
    """Median kernel time [ms] by CUDA events after one warm-up launch."""
    launch()
    cuda.synchronize()
    times = []
    for _ in range(repeats):
        start, end = cuda.event(), cuda.event()
        start.record()
        launch()
        end.record()
        end.synchronize()
        times.append(start.elapsed_time(end))
    return statistics.median(times)


def _wall_ms(run, repeats):
    run()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run()
        times.append(1e3 * (time.perf_counter() - t0))
    return statistics.median(times)


def _bench_variant(cuda, variant, theta0, theta_dot0, p, n_checks, cap, bulk_steps,
                   repeats):
    k = kernels(variant)
    n = theta0.size
    d_th, d_v = cuda.to_device(theta0), cuda.to_device(theta_dot0)
    d_att = cuda.device_array(n, np.int32)
    d_st = cuda.device_array(n, np.int8)
    d_nt = cuda.device_array(n, np.int32)
    grid = -(-n // k.label_block)
    scalars = (p["alpha"], p["omega0"], p["dt"], n_checks, CHECK_EVERY, cap)
    label_ms = _event_ms(cuda, lambda: k.label[grid, k.label_block](
        d_th, d_v, *scalars, d_att, d_st, d_nt), repeats)
    status, n_trap, attractor = d_st.copy_to_host(), d_nt.copy_to_host(), d_att.copy_to_host()
    steps = int(n_trap[status == TRAPPED].sum(dtype=np.int64)
                + np.count_nonzero(status == UNRESOLVED) * n_checks * CHECK_EVERY)

    out = (np.zeros(n, np.int32), np.zeros(n, np.int8), np.zeros(n, np.int32))
    wall_ms = _wall_ms(lambda: label_cuda(theta0, theta_dot0, *scalars, *out, variant=variant),
                       repeats)

    d_pth, d_pv = cuda.to_device(theta0), cuda.to_device(theta_dot0)
    pgrid = -(-n // k.propagate_block)
    bulk_ms = _event_ms(cuda, lambda: k.propagate[pgrid, k.propagate_block](
        d_pth, d_pv, p["alpha"], p["omega0"], p["dt"], bulk_steps), repeats)
    return {
        "label_ms": label_ms,
        "label_with_transfers_ms": wall_ms,
        "steps_taken": steps,
        "effective_gsteps_s": steps / (label_ms * 1e-3) / 1e9 if label_ms > 0 else math.nan,
        "bulk_ms": bulk_ms,
        "bulk_gsteps_s": n * bulk_steps / (bulk_ms * 1e-3) / 1e9 if bulk_ms > 0 else math.nan,
        "blocks": (k.label_block, k.propagate_block),
        "labels": (attractor, status),
    }


def _jax_bulk(theta0, theta_dot0, p, bulk_steps, repeats):
    """JAX peer: what a JAX user writes (vmap of a fori_loop RK4), fixed steps, float64."""
    try:
        import jax

        jax.config.update("jax_enable_x64", True)
        import jax.numpy as jnp
        from jax import lax
    except Exception as exc:  # not installed, or a broken install
        return {"skipped": f"JAX not importable ({type(exc).__name__})"}
    if not any(d.platform == "gpu" for d in jax.devices()):
        return {"skipped": "JAX sees no GPU"}
    a2, w2, dt = 2.0 * p["alpha"], p["omega0"] ** 2, p["dt"]

    def rhs(th, v):
        return v, -w2 * jnp.sin(th) - a2 * v

    def step(_, s):
        th, v = s
        k1 = rhs(th, v)
        k2 = rhs(th + 0.5 * dt * k1[0], v + 0.5 * dt * k1[1])
        k3 = rhs(th + 0.5 * dt * k2[0], v + 0.5 * dt * k2[1])
        k4 = rhs(th + dt * k3[0], v + dt * k3[1])
        return (th + dt / 6.0 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0]),
                v + dt / 6.0 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1]))

    run = jax.jit(jax.vmap(lambda th, v: lax.fori_loop(0, bulk_steps, step, (th, v))))
    th, v = jax.device_put(theta0), jax.device_put(theta_dot0)
    ms = _wall_ms(lambda: jax.block_until_ready(run(th, v)), repeats)
    return {"bulk_ms": ms, "bulk_gsteps_s": theta0.size * bulk_steps / (ms * 1e-3) / 1e9,
            "version": jax.__version__}


def _sweep_row(n: int, t_max: float) -> dict:
    """One end-to-end :func:`atlas.run` of the n × n default atlas on the GPU (module doc)."""
    from atlas.pipeline.config import Config
    from atlas.pipeline.sweep import layout_of, run

    with tempfile.TemporaryDirectory(prefix="atlas-bench-gpu-") as tmp:
        cfg = Config.model_validate({
            "name": f"bench-gpu-{n}",
            "grid": {"theta0": {"start": defaults.THETA0_WINDOW[0],
                                "stop": defaults.THETA0_WINDOW[1], "num": n},
                     "theta_dot0": {"start": defaults.THETA_DOT0_WINDOW[0],
                                    "stop": defaults.THETA_DOT0_WINDOW[1], "num": n}},
            "integrator": {"t_max": t_max},
            "output": Path(tmp) / "sweep.h5"})
        tiles = layout_of(cfg, "cuda").n_tiles
        t0 = time.perf_counter()
        run(cfg, backend="cuda", quiet=True).close()
        seconds = time.perf_counter() - t0
    return {"n": n, "tiles": tiles, "sweep_s": seconds,
            "orbits_per_s": n * n / seconds}


def _cpu_agreement(theta0, theta_dot0, p, attractor, status) -> dict:
    """The GPU's labels (fast variant) against the CPU's on the same orbits (module doc)."""
    from atlas.labels.labelling import label
    from atlas.physics.pendulum import Pendulum

    cpu = label(theta0, theta_dot0, alpha=p["alpha"], omega0=p["omega0"], dt=p["dt"],
                t_max=p["t_max"])
    gpu_k = np.where(status == TRAPPED, attractor, 0)
    cpu_k = np.where(cpu.status == TRAPPED, cpu.attractor, 0)
    differ = np.flatnonzero((cpu.status != status) | (cpu_k != gpu_k))
    nearest = math.nan
    if differ.size:
        from atlas.boundaries.exact import exact_boundaries

        window = (defaults.THETA0_WINDOW, defaults.THETA_DOT0_WINDOW)
        exact = exact_boundaries(Pendulum(p["alpha"], p["omega0"]), window)
        nearest = float(exact.distance(theta0[differ], theta_dot0[differ])[0].max())
    return {"agree_fraction": 1.0 - differ.size / theta0.size, "differ": int(differ.size),
            "differ_max_boundary_distance": nearest}


def sweep_rows(sides, t_max: float = defaults.T_MAX) -> list[dict]:
    """One end-to-end GPU sweep of the default atlas per grid side (:func:`_sweep_row`)."""
    return [_sweep_row(side, t_max) for side in sides]


def run_gpu_bench(n: int = 4096, repeats: int = 5, *, t_max: float = defaults.T_MAX,
                  bulk_steps: int = 1000, allow_simulator: bool = False) -> dict | None:
    """Benchmark the CUDA kernels, and one sweep, on an n × n default-parameter grid (module
    doc).

    Returns None when no CUDA GPU can be used (:func:`atlas.kernels.cuda.cuda_status` says
    why) and, unless ``allow_simulator`` (tests), under the CUDA simulator, whose timings are
    meaningless. Times in ms, throughputs in 10⁹ RK4 steps per second.
    """
    ok, device = cuda_status()
    if not ok or (device == "CUDA simulator" and not allow_simulator):
        return None
    from numba import cuda

    p = dict(defaults.problem(), t_max=t_max)
    theta0, theta_dot0 = defaults.grid(n)
    n_checks = n_checks_for(t_max, p["dt"], CHECK_EVERY)
    cap = energy_cap(p["dt"], p["alpha"], p["omega0"])
    variants = {v: _bench_variant(cuda, v, theta0, theta_dot0, p, n_checks, cap,
                                  bulk_steps, repeats) for v in VARIANTS}
    (att_f, st_f), (att_s, st_s) = (variants[v].pop("labels") for v in VARIANTS)
    same = (st_f == st_s) & ((st_f != TRAPPED) | (att_f == att_s))
    cpu = _cpu_agreement(theta0, theta_dot0, p, att_f, st_f)
    return {
        "device": device,
        "n": n,
        "orbits": n * n,
        "repeats": repeats,
        "params": p,
        "check_every": CHECK_EVERY,
        "bulk_steps": bulk_steps,
        "variants": variants,
        "labels_agree_fraction": float(np.mean(same)),
        "cpu_labels": cpu,
        "jax": _jax_bulk(theta0, theta_dot0, p, bulk_steps, repeats),
        "sweep": _sweep_row(n, t_max),
        "driven": gpu_row(n, repeats),
        "targets": TARGETS,
    }


def format_gpu_rows(result: dict | None) -> str:
    """A small text table of :func:`run_gpu_bench`'s result (or why it was skipped)."""
    if result is None:
        ok, why = cuda_status()
        return f"GPU benchmark skipped: {'CUDA simulator (timings meaningless)' if ok else why}"
    n = result["n"]
    lines = [f"GPU: {result['device']}, {n}x{n} orbits, default parameters, "
             f"median of {result['repeats']}",
             f"{'variant':<16}{'basin map ms':>14}{'+transfers ms':>15}"
             f"{'eff. G steps/s':>16}{'bulk G steps/s':>16}"]
    for name, r in result["variants"].items():
        lines.append(f"{name:<16}{r['label_ms']:>14.2f}{r['label_with_transfers_ms']:>15.2f}"
                     f"{r['effective_gsteps_s']:>16.1f}{r['bulk_gsteps_s']:>16.1f}")
    jax = result["jax"]
    jax_cell = (f"{jax['bulk_gsteps_s']:>16.1f}" if "bulk_gsteps_s" in jax
                else f"  skipped: {jax['skipped']}")
    lines.append(f"{'JAX vmap+fori':<16}{'—':>14}{'—':>15}{'—':>16}{jax_cell}")
    for sweep in [result["sweep"], *result.get("sweeps", [])]:
        side = sweep["n"]
        lines.append(f"sweep: atlas run --backend cuda of the {side}x{side} default atlas "
                     f"({sweep['tiles']} tiles), end to end {sweep['sweep_s']:.2f} s, "
                     f"{sweep['orbits_per_s'] / 1e6:.1f} M orbits/s")
    if "driven" in result:
        lines.append(gpu_line(result["driven"]))
    cpu = result.get("cpu_labels")
    if cpu is not None:
        differ = (f"{cpu['differ']} differ, all within "
                  f"{cpu['differ_max_boundary_distance']:.1e} of an exact boundary"
                  if cpu["differ"] else "none differs")
        lines.append(f"GPU (fast) against CPU labels (default method): the same on "
                     f"{100 * cpu['agree_fraction']:.4f} % of orbits; {differ}")
    t = result["targets"]
    lines.append(f"targets (H100, 4096²): basin map ≤ {t['label_ms']:.0f} ms, bulk ≥ "
                 f"{t['bulk_gsteps_s']:.0f} G steps/s; labels agree between variants on "
                 f"{100 * result['labels_agree_fraction']:.4f} % of orbits")
    return "\n".join(lines)
