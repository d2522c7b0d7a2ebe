"""``atlas bench``: the CPU benchmark, its JSON file and its table (and the GPU rows where a
GPU is present).

:func:`run_bench` runs the rows of :mod:`atlas.commands.bench_kernels` (the default map
against its peers, bulk steps, torque, JIT), :mod:`atlas.commands.bench_scaling` (grid sizes,
threads), :mod:`atlas.commands.bench_plot` (``atlas plot``) and
:mod:`atlas.commands.bench_e2e` (the whole ``atlas run`` against its budget), all in this
process on the default problem of :mod:`atlas.defaults`; :func:`bench_to_json` writes the
result and prints it (:mod:`atlas.commands.bench_table`), with the GPU rows of
:mod:`atlas.commands.bench_gpu`. What each row measures and why: ``docs/design/bench.md``.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import sys
from pathlib import Path

import numpy as np

from atlas import defaults
from atlas.commands.bench_kernels import MAP_N, jit_times, kernel_rows, torque_rows
from atlas.commands.bench_plot import PLOT_SIDES, QUICK_PLOT_SIDES, plot_rows
from atlas.commands.bench_scaling import QUICK_SCALING, SCALING, size_rows, thread_rows
from atlas.commands.bench_table import format_table
from atlas.labels.trap import CHECK_EVERY

__all__ = ["run_bench", "bench_to_json", "machine_info"]

#: Grid side of the torque rows in a quick run.
QUICK_TORQUE = 128
#: Targets on the 2-core development machine.
TARGETS = {"map_speedup": 8.0, "bulk_msteps_s": 350.0, "bulk_speedup": 10.0,
           "bulk_vs_lanes": 1.5, "jit_cold_s": 5.0, "jit_warm_s": 1.0}


def machine_info() -> dict:
    import llvmlite
    import numba

    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        cpu = platform.processor() or cpu
    return {
        "cpu": cpu, "cores": os.cpu_count(), "numba_threads": numba.get_num_threads(),
        "python": platform.python_version(), "numpy": np.__version__,
        "numba": numba.__version__, "llvmlite": llvmlite.__version__,
        "platform": platform.platform(),
        "timestamp": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }



def run_bench(sizes=None, repeats: int = 5, quick: bool = False, jit: bool = True,
              lsoda_sample: int | None = None, plots: bool = True,
              end_to_end: bool = True) -> dict:
    """Run the CPU benchmark (module docstring) and return a JSON-ready dict.

    ``sizes``: grid sides of the scaling rows (default 256…4096; ``quick`` stops at 1024 and
    uses at most 2 repeats, shorter numpy/straightforward runs and a smaller LSODA sample).
    ``plots``: the plotting rows (``atlas plot``; they compute their atlases first).
    ``end_to_end``: the whole ``atlas run`` of the default config against its budget
    (:mod:`atlas.commands.bench_e2e`).
    """
    p = defaults.problem()
    if quick:
        repeats = min(repeats, 2)
    sizes = tuple(sizes or (QUICK_SCALING if quick else SCALING))
    kernels = kernel_rows(p, repeats, quick, lsoda_sample or (8 if quick else 32))
    atlas_s = kernels.pop("atlas_s")
    thread_side = QUICK_SCALING[0] if quick else 1024
    result = {
        "machine": machine_info(), "problem": {**p, "grid": MAP_N, "check_every": CHECK_EVERY},
        "torque": torque_rows(QUICK_TORQUE if quick else MAP_N, repeats),
        "repeats": repeats, "quick": quick, "targets": TARGETS,
        **kernels,
        "scaling": size_rows(sizes, repeats, p),
        "threads": {"side": thread_side, "rows": thread_rows(thread_side, repeats, p)},
    }
    if plots:
        result["plot"] = plot_rows(QUICK_PLOT_SIDES if quick else PLOT_SIDES, repeats)
    if end_to_end:
        from atlas.commands.bench_e2e import end_to_end as whole_run

        result["end_to_end"] = whole_run(atlas_s, repeats=1 if quick else 5)
    if jit:
        cold, warm = jit_times()
        result["jit"] = {"cold": cold, "warm_cache": warm}
        # "starts computing": import atlas and load (or compile) the kernel, in the process
        result["summary"].update(jit_cold_s=cold["import_s"] + cold["first_call_s"],
                                 jit_warm_s=warm["import_s"] + warm["first_call_s"])
    return result


def bench_to_json(path="outputs/bench.json", *, backend: str = "cpu",
                  gpu_sweeps: tuple[int, ...] = (), **kwargs) -> dict:
    """Run the benchmark, write its result to ``path`` as JSON, print the table.

    ``backend="cpu"``: the CPU table, plus the GPU rows when a CUDA GPU is present;
    ``backend="cuda"``: the GPU rows only (BackendUnavailable without a GPU).
    ``gpu_sweeps``: grid sides of further end-to-end GPU sweeps (``--gpu-sweep``; they take
    minutes at 16384²: the other rows are written first).
    """
    from atlas.commands.bench_gpu import format_gpu_rows, run_gpu_bench
    from atlas.kernels.cuda import cuda_status

    result = {} if backend == "cuda" else run_bench(**kwargs)
    gpu_ok, _ = cuda_status()
    if backend == "cuda" and not gpu_ok:
        from atlas.kernels.cuda import require_cuda

        require_cuda()  # raises with the one-line reason
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if gpu_ok:
        result["gpu"] = run_gpu_bench(repeats=3 if kwargs.get("quick") else 5)
        if gpu_sweeps and result["gpu"] is not None:
            from atlas.commands.bench_gpu import sweep_rows

            path.write_text(json.dumps(result, indent=2))  # kept if the big sweeps overrun
            result["gpu"]["sweeps"] = sweep_rows(gpu_sweeps)
    path.write_text(json.dumps(result, indent=2))
    if backend != "cuda":
        print(format_table(result))
    if "gpu" in result:
        print(format_gpu_rows(result["gpu"]))
    print(f"wrote {path}")
    return result


if __name__ == "__main__":
    _paths = [a for a in sys.argv[1:] if not a.startswith("--")]
    bench_to_json(*_paths[:1], quick="--quick" in sys.argv)
