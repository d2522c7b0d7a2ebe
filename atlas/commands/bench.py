"""``atlas bench``: the CPU benchmark, its JSON file and its table (and the GPU rows where a
GPU is present).

:func:`run_bench` runs the rows of :mod:`atlas.commands.bench_kernels` (the default map
against its peers, bulk steps, torque, JIT), :mod:`atlas.commands.bench_scaling` (grid sizes,
threads), :mod:`atlas.commands.bench_plot` (``atlas plot``) and
:mod:`atlas.commands.bench_e2e` (the whole ``atlas run`` against its budget), all in this
process on the default problem of :mod:`atlas.defaults`; :func:`bench_to_json` writes the
result and prints it (:mod:`atlas.commands.bench_table`), with the GPU rows of
:mod:`atlas.commands.bench_gpu`. What each row measures and why: ``docs/design/bench.md``.

``atlas bench --quick`` (about 15 s on the idle 2-core development machine, against a minute
and more for the full run) keeps every comparison a comparison of the same problem on both
sides, on fewer orbits: the kernel rows on the :data:`QUICK_MAP_N`² map, the torque rows on
:data:`QUICK_TORQUE`², the scaling rows at 128² and 256², the threads at 128², the plotting
row of one 256² atlas (the whole ``atlas plot`` command, once). It leaves out what cannot be
made small without changing what it measures: the trig-free row at equal accuracy (its step
is found by tracing the default window's separatrices), the end-to-end row (the default
config's whole run against its budget), the JIT's cold start (a compilation in a fresh
process), and the plotting row's in-process time and memory. The table says so.

Rows from other modules (:data:`MORE_ROWS`): ``atlas.commands.<module>`` with a function
``<name>(quick: bool) -> list[dict]``, imported only when the bench runs (absent: the table
says it is skipped). Each dict is one row, of this shape::

    {"variant": str,         # what is timed, in a few words
     "wall_s": float,        # its wall time [s] (a median of repeats, the module says which)
     "ratio": float,         # wall_s / the wall time of the same problem done the reference way
     "against": str,         # that reference way, e.g. "untilted", "grid count"
     "orbits_per_s": float,  # optional: orbits labelled per second
     "note": str}            # optional: anything the reader needs to trust the number

(the shape of the torque rows of :func:`atlas.commands.bench_kernels.torque_rows`, plus
``against`` and ``note``). A module may set ``TITLE`` (a line that heads its rows).
"""

from __future__ import annotations

import datetime as _dt
import importlib
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

__all__ = ["run_bench", "bench_to_json", "machine_info", "more_rows", "MORE_ROWS"]

#: Grid side of the torque rows in a quick run.
QUICK_TORQUE = 128
#: Grid side of the kernel rows (the map and bulk rows) in a quick run.
QUICK_MAP_N = 128
#: Rows from other modules (module docstring): JSON key → (module, function).
MORE_ROWS = {"torque_sweep": ("atlas.commands.bench_torque", "torque_rows"),
             "stability": ("atlas.commands.bench_stability", "stability_rows"),
             "driven": ("atlas.commands.bench_driven", "driven_rows")}
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



def more_rows(quick: bool) -> dict:
    """{key: {"title", "rows"} or {"title", "skipped": why}} of :data:`MORE_ROWS`, each
    module imported here, and skipped with a note where it is absent. They run whole sweeps
    and studies end to end (minutes), so ``--quick`` skips them with a note."""
    out = {}
    for key, (module, function) in MORE_ROWS.items():
        if quick:
            out[key] = {"title": key, "skipped": "not in --quick (whole sweeps and studies, "
                                                 "minutes): run `atlas bench`"}
            continue
        try:
            found = importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                raise  # the module is there but something it imports is not: a real error
            out[key] = {"title": key, "skipped": f"{module} is not installed"}
            continue
        out[key] = {"title": getattr(found, "TITLE", key),
                    "rows": getattr(found, function)(quick)}
    return out


def run_bench(sizes=None, repeats: int = 5, quick: bool = False, jit: bool = True,
              lsoda_sample: int | None = None, plots: bool = True,
              end_to_end: bool = True) -> dict:
    """Run the CPU benchmark (module docstring) and return a JSON-ready dict.

    ``sizes``: grid sides of the scaling rows (default 256…4096). ``quick``: the small
    variant of the module docstring (at most 2 repeats, shorter numpy/straightforward runs, a
    smaller LSODA sample; no JIT or end-to-end rows whatever ``jit`` and ``end_to_end`` say).
    ``plots``: the plotting rows (``atlas plot``; they compute their atlases first).
    ``end_to_end``: the whole ``atlas run`` of the default config against its budget
    (:mod:`atlas.commands.bench_e2e`).
    """
    p = defaults.problem()
    if quick:
        repeats = min(repeats, 2)
        jit = end_to_end = False
    side = QUICK_MAP_N if quick else MAP_N
    sizes = tuple(sizes or (QUICK_SCALING if quick else SCALING))
    kernels = kernel_rows(p, repeats, quick, lsoda_sample or (8 if quick else 32), side)
    atlas_s = kernels.pop("atlas_s")
    thread_side = QUICK_SCALING[0] if quick else 1024
    result = {
        "machine": machine_info(), "problem": {**p, "grid": side, "check_every": CHECK_EVERY},
        "torque": torque_rows(QUICK_TORQUE if quick else MAP_N, repeats),
        "repeats": repeats, "quick": quick, "targets": TARGETS,
        **kernels,
        "scaling": size_rows(sizes, repeats, p),
        "threads": {"side": thread_side, "rows": thread_rows(thread_side, repeats, p)},
    }
    result["more"] = more_rows(quick)
    if plots:
        result["plot"] = plot_rows(QUICK_PLOT_SIDES if quick else PLOT_SIDES,
                                   1 if quick else repeats, quick)
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
