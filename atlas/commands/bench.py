"""CPU benchmark: the default kernel against its peers, side by side in one run.

The default problem of :mod:`atlas.defaults` (the essay's Figure 9: α, ω0, dt, t_max) on an
n × n grid of its θ0 and θ̇0 window (:func:`atlas.defaults.grid`). Every figure is the median of
``repeats`` timed runs after one warm-up run (which also compiles), all in this process; within
each round the variants run in turn, so they see the same machine load and their ratios are
meaningful even where absolute times drift (the best of the repeats is kept in the JSON too).

* basin map (512², early exit): atlas = :func:`~atlas.kernels.lanes.label_lanes`, the default
  method "rk4", with the trap tested every ``CHECK_EVERY`` steps (what :func:`atlas.label` and
  ``atlas run`` run); the trig-free lanes of method "rk4-trigfree"
  (:func:`~atlas.kernels.lanes.label_trigfree`); the straightforward
  Numba kernel with the trap tested every step (one orbit per ``prange`` iteration,
  ``math.sin``) and every ``CHECK_EVERY`` steps; numpy over the whole grid without early exit
  (fixed duration t_max, timed on a short run and extrapolated); scipy ``solve_ivp`` LSODA
  (rtol 1e-8, atol 1e-10, one process) on a random sample of orbits to t_max, extrapolated to
  the grid. "steps/s" there is effective: the RK4 steps the orbits need (Σ n_trap at
  check_every = 1) per second of wall time; the run also reports whether each lane method's
  labels equal those of its straightforward kernel, and how many trig-free labels differ from
  the default's (a different discretisation: boundary cells only). One more row runs the
  trig-free lanes at the step that makes them as accurate as the default (:func:`_equal_dt`:
  its RK4 map's basin boundaries as close to the exact ones, measured by the separatrix
  bisection, :func:`atlas.boundaries.separatrices.trace`).
* bulk (fixed number of steps, no early exit): steps/s of ``propagate_lanes`` (the default),
  ``propagate_trigfree``, ``propagate_straightforward`` and numpy; "512² map" there is the
  time to integrate every orbit to t_max without early exit.
* torque: the swing equation's map (bSTAB's pendulum: α = 0.05, ω0 = 1, τ = 0.5, its window
  θ ∈ [−5π/6, 7π/6], θ̇ ∈ [−10, 10], t_max = 400 s) against the untilted map of the same points
  and α, both through :func:`atlas.label` with the file's method "rk4" (the tilted trap and the
  running barrier against the plain energy trap).
* scaling: the atlas map at 256² … 4096² (the same window, finer grids); and the 1024² map on
  1, 2, 4, … Numba threads up to all of them (:func:`_thread_scaling`: speed-up and parallel
  efficiency against one thread; the labels are the same on every count).
* end to end: ``atlas run`` of the default config, the whole command, against the budget
  imports + 3 × the default map's kernel time + 0.5 s (:mod:`atlas.commands.bench_e2e`).
* JIT: a subprocess with ``NUMBA_CACHE_DIR`` pointed at a fresh directory times import and the
  first call (compilation), then a second subprocess with the same directory (cache hit).
* plotting: ``atlas plot`` of the default config's atlas at 512² and 4096² (1536² in a quick
  run; written first by :func:`atlas.run`, separatrices on): in process
  (:func:`~atlas.views.plotting.plot_atlas` of the file opened lazily, as the CLI opens it; median
  of the repeats), and the whole command in a subprocess (wall: the median of as many runs
  up to 1024², one run above; peak RSS: the largest). The
  maps are read band by band and coarsened to at most ``MAX_PIXELS`` per axis; the row also
  gives the peak memory (tracemalloc) of reading and coarsening them that way against
  loading each whole and coarsening it in memory as float64, as ``atlas plot`` did before.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from atlas import defaults
from atlas.kernels import TRAPPED
from atlas.kernels.lanes import label_lanes, label_trigfree, propagate_lanes, propagate_trigfree
from atlas.kernels.rk4 import label_straightforward, make_rk4_step, propagate_straightforward
from atlas.kernels.trigfree import label_trigfree_straightforward
from atlas.labels.labelling import CHECK_EVERY, energy_cap, n_checks_for

__all__ = ["run_bench", "format_table", "bench_to_json"]

MAP_N = defaults.GRID_NUM
SCALING = (256, 512, 1024, 2048, 4096)
QUICK_SCALING = (256, 512, 1024)
#: Grid side of the torque rows in a quick run.
QUICK_TORQUE = 128
#: Grid sides of the plotting rows (a quick run: the second is smaller).
PLOT_SIDES = (512, 4096)
QUICK_PLOT_SIDES = (512, 1536)
#: Target of the plotting rows: ``atlas plot`` of the default 512² atlas, the whole command.
PLOT_TARGET_S = 1.0
#: Targets on the 2-core development machine.
TARGETS = {"map_speedup": 8.0, "bulk_msteps_s": 350.0, "bulk_speedup": 10.0,
           "bulk_vs_lanes": 1.5, "jit_cold_s": 5.0, "jit_warm_s": 1.0}

# The same RK4 definition evaluated by numpy on whole arrays: make_rk4_step's Python body
# with plain-Python sin/reduce (the Numba wrapper is never compiled).
_numpy_step = make_rk4_step(lambda p, delta: np.sin(p + delta), reduce=lambda x: x).py_func


def _median_times(runs: dict, repeats: int, warm_up: bool = True) -> dict:
    """{name: (median s, best s)} of the callables in ``runs``: one warm-up call each (which
    also compiles; ``warm_up=False``: the caller has just run them), then ``repeats`` rounds
    that call them in turn, so that every variant sees the same machine load."""
    for run in runs.values() if warm_up else ():
        run()
    times = {name: [] for name in runs}
    for _ in range(repeats):
        for name, run in runs.items():
            t0 = time.perf_counter()
            run()
            times[name].append(time.perf_counter() - t0)
    return {name: (statistics.median(t), min(t)) for name, t in times.items()}


def _label(kernel, theta0, theta_dot0, check_every, p):
    n = theta0.size
    out = (np.zeros(n, np.int32), np.zeros(n, np.int8), np.zeros(n, np.int32))
    kernel(theta0, theta_dot0, p["alpha"], p["omega0"], p["dt"],
           n_checks_for(p["t_max"], p["dt"], check_every), check_every,
           energy_cap(p["dt"], p["alpha"], p["omega0"]), *out)
    return out


def _label_run(kernel, theta0, theta_dot0, check_every, p):
    return lambda: _label(kernel, theta0, theta_dot0, check_every, p)


def _propagate_run(propagate, theta0, theta_dot0, n_steps, p):
    """A fixed-steps run of every orbit (on copies: the initial state stays the same)."""
    return lambda: propagate(theta0.copy(), theta_dot0.copy(), p["alpha"], p["omega0"],
                             p["dt"], n_steps)


def _numpy_propagate(theta, theta_dot, alpha, omega0, dt, n_steps):
    for _ in range(n_steps):
        theta, theta_dot = _numpy_step(theta, theta_dot, alpha, omega0, dt)
    return theta, theta_dot


def _lsoda_orbits_per_s(theta0, theta_dot0, p, n_sample, seed=0):
    from scipy.integrate import solve_ivp

    a2, w2 = 2.0 * p["alpha"], p["omega0"] ** 2

    def rhs(_, y):
        return [y[1], -w2 * np.sin(y[0]) - a2 * y[1]]

    idx = np.random.default_rng(seed).choice(theta0.size, n_sample, replace=False)
    t0 = time.perf_counter()
    for i in idx:
        solve_ivp(rhs, (0.0, p["t_max"]), [theta0[i], theta_dot0[i]], method="LSODA",
                  rtol=1e-8, atol=1e-10)
    return n_sample / (time.perf_counter() - t0)


_JIT_SCRIPT = """
import time
t0 = time.perf_counter()
import numpy as np
from atlas.kernels.lanes import label_trigfree
t1 = time.perf_counter()
n = 64
out = (np.zeros(n, np.int32), np.zeros(n, np.int8), np.zeros(n, np.int32))
label_trigfree(np.linspace(-3.0, 3.0, n), np.zeros(n), 0.1, 1.0, 0.01, 10, 16, 1.9, *out)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def _jit_times():
    """(cold, warm) dicts of import_s, first_call_s, process_s (wall incl. interpreter)."""
    from atlas.commands.bench_e2e import run_python

    result = []
    with tempfile.TemporaryDirectory() as cache:
        for _ in ("cold", "warm"):
            wall, out = run_python(["-c", _JIT_SCRIPT], NUMBA_CACHE_DIR=cache)
            import_s, call_s = map(float, out.stdout.split()[-2:])
            result.append({"import_s": import_s, "first_call_s": call_s, "process_s": wall})
    return result


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


def _boundary_shift(p: dict, dt: float, method: str) -> float:
    """The RK4 map's basin-boundary shift from the exact boundaries [rad-ish] over the default
    window (the separatrices' ``discrepancy``, which sets d_cert)."""
    from atlas.boundaries.separatrices import trace
    from atlas.physics.pendulum import Pendulum

    sep = trace(Pendulum(p["alpha"], p["omega0"]), defaults.THETA0_WINDOW,
                defaults.THETA_DOT0_WINDOW, dt=dt, method=method)
    return float(sep.attrs["discrepancy"])


def _equal_dt(p: dict) -> tuple[float, float, float]:
    """The trig-free step as accurate as the default method at ``p["dt"]``: (dt [s], its
    boundary shift, the default's). Both are of order 4, so dt·(shift ratio)^(−1/4), to two
    digits, lowered by 5 % while its measured shift is larger (at most 8 times: the order
    estimate is close; a shift that will not come down raises RuntimeError)."""
    target = _boundary_shift(p, p["dt"], "rk4")
    ratio = _boundary_shift(p, p["dt"], "rk4-trigfree") / target
    dt = float(f"{p['dt'] * ratio ** -0.25:.2g}")
    for _ in range(8):
        shift = _boundary_shift(p, dt, "rk4-trigfree")
        if shift <= target:
            return dt, shift, target
        dt = float(f"{0.95 * dt:.2g}")
    raise RuntimeError(f"the trig-free boundary shift stays above {target:.2g} down to "
                       f"dt = {dt:g} s")


def _thread_scaling(side: int, repeats: int, p: dict) -> list[dict]:
    """The default map of ``side``² orbits on 1, 2, 4, … threads and on all of Numba's:
    median wall time, speed-up and efficiency against one thread, and whether the labels
    equal one thread's."""
    import numba

    th, v = defaults.grid(side)
    counts = sorted({*(1 << k for k in range(numba.config.NUMBA_NUM_THREADS.bit_length())),
                     numba.config.NUMBA_NUM_THREADS})
    saved, rows, first = numba.get_num_threads(), [], None
    try:
        for count in counts:
            numba.set_num_threads(count)
            labels = _label(label_lanes, th, v, CHECK_EVERY, p)
            first = first or labels
            s = _median_times({"map": _label_run(label_lanes, th, v, CHECK_EVERY, p)},
                              repeats, warm_up=False)["map"][0]  # warmed by the labels above
            rows.append({"threads": count, "wall_s": s, "same_labels": all(
                np.array_equal(a, b) for a, b in zip(labels, first))})
    finally:
        numba.set_num_threads(saved)
    for row in rows:
        row["speedup"] = rows[0]["wall_s"] / row["wall_s"]
        row["efficiency"] = row["speedup"] / row["threads"]
    return rows


def _row(variant, steps_s, orbits_s, map_s, atlas_map_s, note=""):
    return {"variant": variant, "steps_per_s": steps_s, "orbits_per_s": orbits_s,
            "map_512_s": map_s, "ratio_to_atlas": map_s / atlas_map_s, "note": note}


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
    lsoda_sample = lsoda_sample or (8 if quick else 32)
    full_steps = n_checks_for(p["t_max"], p["dt"], 1)  # steps to t_max
    theta0, theta_dot0 = defaults.grid(MAP_N)
    n = theta0.size

    # basin map, early exit
    ref = _label(label_straightforward, theta0, theta_dot0, 1, p)
    ref16 = _label(label_straightforward, theta0, theta_dot0, CHECK_EVERY, p)
    ref_tf = _label(label_trigfree_straightforward, theta0, theta_dot0, CHECK_EVERY, p)
    atl = _label(label_lanes, theta0, theta_dot0, CHECK_EVERY, p)
    atl_tf = _label(label_trigfree, theta0, theta_dot0, CHECK_EVERY, p)
    trapped = ref[1] == TRAPPED
    useful = float(np.where(trapped, ref[2], full_steps).sum())  # steps the orbits need
    np_steps = 5 if quick else 20
    bulk_steps = {"atlas rk4 lanes propagate (default)": 50 if quick else 200,
                  "trig-free lanes propagate": 50 if quick else 200,
                  "straightforward numba propagate": 5 if quick else 20,
                  "numpy whole grid": np_steps}
    default_bulk, trigfree_bulk = list(bulk_steps)[:2]
    equal_dt, equal_shift, default_shift = _equal_dt(p)
    p_equal = {**p, "dt": equal_dt}
    t = _median_times({
        "lanes": _label_run(label_lanes, theta0, theta_dot0, CHECK_EVERY, p),
        "trigfree": _label_run(label_trigfree, theta0, theta_dot0, CHECK_EVERY, p),
        "trigfree_equal": _label_run(label_trigfree, theta0, theta_dot0, CHECK_EVERY, p_equal),
        "sf1": _label_run(label_straightforward, theta0, theta_dot0, 1, p),
        "sf16": _label_run(label_straightforward, theta0, theta_dot0, CHECK_EVERY, p),
        default_bulk: _propagate_run(propagate_lanes, theta0, theta_dot0,
                                     bulk_steps[default_bulk], p),
        trigfree_bulk: _propagate_run(propagate_trigfree, theta0, theta_dot0,
                                      bulk_steps[trigfree_bulk], p),
        "straightforward numba propagate": _propagate_run(
            propagate_straightforward, theta0, theta_dot0,
            bulk_steps["straightforward numba propagate"], p),
        "numpy whole grid": _propagate_run(_numpy_propagate, theta0, theta_dot0, np_steps, p),
    }, repeats)
    atlas_s, trigfree_s, sf1_s, sf16_s = (t[k][0] for k in ("lanes", "trigfree", "sf1", "sf16"))
    rates = {name: n * steps / t[name][0] for name, steps in bulk_steps.items()}
    np_map_s = n * full_steps / rates["numpy whole grid"]
    lsoda_rate = _lsoda_orbits_per_s(theta0, theta_dot0, p, lsoda_sample)
    lsoda_map_s = n / lsoda_rate
    map_rows = [
        _row(f"atlas default: rk4 lanes (check every {CHECK_EVERY})", useful / atlas_s,
             n / atlas_s, atlas_s, atlas_s),
        _row(f"trig-free lanes, method rk4-trigfree (check every {CHECK_EVERY})",
             useful / trigfree_s, n / trigfree_s, trigfree_s, atlas_s),
        _row(f"trig-free lanes at dt = {equal_dt:g} s, as accurate as the default",
             useful * p["dt"] / equal_dt / t["trigfree_equal"][0], n / t["trigfree_equal"][0],
             t["trigfree_equal"][0], atlas_s,
             f"boundary shift {equal_shift:.2g} vs the default's {default_shift:.2g}; "
             "steps/s counts its steps"),
        _row("straightforward numba (check every step)", useful / sf1_s, n / sf1_s, sf1_s,
             atlas_s),
        _row(f"straightforward numba (check every {CHECK_EVERY})", useful / sf16_s,
             n / sf16_s, sf16_s, atlas_s),
        _row("numpy whole grid, fixed duration", useful / np_map_s, n / np_map_s, np_map_s,
             atlas_s, f"extrapolated from {np_steps} steps"),
        _row("scipy LSODA rtol 1e-8, 1 process", useful / lsoda_map_s, lsoda_rate, lsoda_map_s,
             atlas_s, f"extrapolated from {lsoda_sample} random orbits"),
    ]
    atlas_bulk_map = n * full_steps / rates[default_bulk]
    bulk_rows = [
        _row(name, rate, rate / full_steps, n * full_steps / rate, atlas_bulk_map,
             f"{bulk_steps[name]} steps timed, map time extrapolated to {full_steps} steps")
        for name, rate in rates.items()
    ]

    scaling = []
    for side in sizes:
        th, v = defaults.grid(side)
        s = _median_times({"atlas": _label_run(label_lanes, th, v, CHECK_EVERY, p)},
                          repeats if side <= 1024 else 1)["atlas"][0]
        scaling.append({"n": side, "orbits": th.size, "wall_s": s, "orbits_per_s": th.size / s,
                        "ns_per_orbit": s / th.size * 1e9})

    thread_side = QUICK_SCALING[0] if quick else 1024
    threads = {"side": thread_side, "rows": _thread_scaling(thread_side, repeats, p)}
    torque = _torque_rows(QUICK_TORQUE if quick else MAP_N, repeats)
    plot = _plot_rows(QUICK_PLOT_SIDES if quick else PLOT_SIDES, repeats) if plots else None

    mismatches = _label_mismatches(atl, ref16)
    result = {
        "machine": machine_info(), "problem": {**p, "grid": MAP_N, "check_every": CHECK_EVERY},
        "torque": torque,
        "repeats": repeats, "quick": quick, "targets": TARGETS,
        "map": {"rows": map_rows,
                "labels_equal_straightforward": mismatches == 0,
                "trigfree_labels_equal_straightforward": _label_mismatches(atl_tf, ref_tf) == 0,
                "label_mismatches": mismatches,
                "trigfree_vs_rk4_label_mismatches": _label_mismatches(atl_tf, atl),
                "trigfree_vs_rk4_status_mismatches": int(np.sum(atl_tf[1] != atl[1])),
                "useful_steps": useful},
        "bulk": {"rows": bulk_rows},
        "scaling": scaling,
        "threads": threads,
        "best_of_repeats_s": {name: best for name, (_, best) in t.items()},
        "summary": {"map_speedup": sf1_s / atlas_s,
                    "trigfree_map_speedup": atlas_s / trigfree_s,
                    "trigfree_equal_accuracy": {
                        "dt": equal_dt, "boundary_shift": equal_shift,
                        "default_boundary_shift": default_shift,
                        "map_speedup": atlas_s / t["trigfree_equal"][0]},
                    "default_bulk_msteps_s": rates[default_bulk] / 1e6,
                    "bulk_msteps_s": rates[trigfree_bulk] / 1e6,
                    "bulk_msteps_s_best": n * bulk_steps[trigfree_bulk]
                    / t[trigfree_bulk][1] / 1e6,
                    "bulk_speedup": rates[trigfree_bulk]
                    / rates["straightforward numba propagate"],
                    "bulk_vs_lanes": rates[trigfree_bulk] / rates[default_bulk]},
    }
    if plot is not None:
        result["plot"] = plot
    if end_to_end:
        from atlas.commands.bench_e2e import end_to_end as whole_run

        result["end_to_end"] = whole_run(atlas_s, repeats=1 if quick else 5)
    if jit:
        cold, warm = _jit_times()
        result["jit"] = {"cold": cold, "warm_cache": warm}
        # "starts computing": import atlas and load (or compile) the kernel, in the process
        result["summary"].update(jit_cold_s=cold["import_s"] + cold["first_call_s"],
                                 jit_warm_s=warm["import_s"] + warm["first_call_s"])
    return result


def _torque_rows(side: int, repeats: int) -> dict:
    """The torque map against the untilted map of the same points (module docstring)."""
    from atlas.labels.labelling import label
    from atlas.physics.running import running_barrier

    alpha, omega0, torque, dt, t_max = 0.05, 1.0, 0.5, 0.01, 400.0
    theta0 = np.linspace(-5 * np.pi / 6, 7 * np.pi / 6, side)[None, :]
    theta_dot0 = np.linspace(-10.0, 10.0, side)[:, None]
    barrier = running_barrier(alpha, omega0, torque, dt=dt)
    runs = {
        "untilted": lambda: label(theta0, theta_dot0, alpha=alpha, omega0=omega0, dt=dt,
                                  t_max=t_max, method="rk4"),
        "torque": lambda: label(theta0, theta_dot0, alpha=alpha, omega0=omega0, torque=torque,
                                dt=dt, t_max=t_max, method="rk4", running=barrier),
    }
    t = _median_times(runs, repeats)
    n = theta0.size * theta_dot0.size
    return {"side": side, "orbits": n,
            "rows": [{"variant": "untilted (tau = 0), energy trap", "wall_s": t["untilted"][0],
                      "orbits_per_s": n / t["untilted"][0], "ratio": 1.0},
                     {"variant": "torque tau = 0.5, tilted trap + running barrier",
                      "wall_s": t["torque"][0], "orbits_per_s": n / t["torque"][0],
                      "ratio": t["torque"][0] / t["untilted"][0]}]}


_PLOT_CONFIG = """\
name: plot{side}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: {side}}}
  theta_dot0: {{start: -4.0, stop: 4.0, num: {side}}}
output: {output}
"""


def _whole_array_maps(path) -> None:
    """The maps of the atlas at ``path`` as ``atlas plot`` read them before streaming: every
    map loaded whole, then each converted to float64 and coarsened in memory."""
    from atlas.kernels import NEAR_BOUNDARY
    from atlas.store.atlasfile import open_atlas
    from atlas.views.plotting import _coarsen

    tree = open_atlas(path)
    try:
        ds = tree.to_dataset(inherit=False).load()
    finally:
        tree.close()
    k = ds["attractor"].values.astype(float)
    k[~np.isin(ds["status"].values, (TRAPPED, NEAR_BOUNDARY))] = np.nan
    _coarsen(k, "mode")
    del k
    t = ds["t_trap"].values.astype(float)
    _coarsen(np.where(t > 0, t, 1.0), "max")
    del t
    _coarsen(ds["boundary_distance"].values.astype(float), "min")


def _streamed_maps(path) -> None:
    """The maps of the atlas at ``path`` as ``atlas plot`` reads them: band by band."""
    from atlas.store.atlasfile import open_atlas
    from atlas.views.plotting import read_maps

    tree = open_atlas(path)
    try:
        read_maps(tree)
    finally:
        tree.close()


def _peak_bytes(run, *args) -> int:
    """Peak memory traced (tracemalloc: Python and numpy allocations) while ``run(*args)``
    runs."""
    import tracemalloc

    tracemalloc.start()
    try:
        run(*args)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


_CLI_PLOT = """
import sys
from atlas.cli import main
code = main(["plot", sys.argv[1]])
try:  # the high-water mark of this process's own memory (ru_maxrss would count its parent's)
    with open("/proc/self/status") as status:
        hwm = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
except (OSError, StopIteration):
    hwm = "nan"
try:  # the largest of its drawing processes (forks: they all ended, and were waited for)
    import resource
    drawing = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
except ImportError:
    drawing = "nan"
print(code, hwm, drawing)
from atlas.cli import leave
leave(0)  # as the atlas command ends (atlas.cli.entry)
"""


def _cli_plot(path) -> tuple[float, float | None, float | None]:
    """(wall s, peak RSS in bytes, peak RSS of its largest drawing process in bytes; None
    where unknown) of ``atlas plot path`` in a subprocess (the CLI's main in a fresh
    interpreter; the figures are drawn by forks of it, :func:`atlas.views.plotting.plot_file`)."""
    from atlas.commands.bench_e2e import run_python

    wall, out = run_python(["-c", _CLI_PLOT, str(path)])
    code, hwm, drawing = out.stdout.split()[-3:]
    if code != "0":
        raise RuntimeError(f"atlas plot {path}: {out.stderr.strip()}")
    return wall, *(None if kb == "nan" else float(kb) * 1024 for kb in (hwm, drawing))


def _plot_rows(sides, repeats: int) -> dict:
    """``atlas plot`` of generated atlases (module docstring), warm: atlas's bytecode cache
    written first (:func:`atlas.commands.bench_e2e.warm_bytecode`)."""
    from atlas.commands.bench_e2e import warm_bytecode
    from atlas.pipeline.config import load_config
    from atlas.pipeline.sweep import run
    from atlas.store.atlasfile import open_atlas
    from atlas.views.plotting import MAX_PIXELS, plot_atlas

    warm_bytecode()
    rows = []
    with tempfile.TemporaryDirectory(prefix="atlas-bench-plot-") as tmp:
        for side in sides:
            path = Path(tmp) / f"plot{side}.h5"
            cfg = Path(tmp) / f"plot{side}.yaml"
            cfg.write_text(_PLOT_CONFIG.format(side=side, output=path))
            t0 = time.perf_counter()
            run(load_config(cfg), quiet=True)
            run_s = time.perf_counter() - t0

            def plot(path=path):
                tree = open_atlas(path)
                try:
                    plot_atlas(tree, path)
                finally:
                    tree.close()

            t = _median_times({"plot": plot}, repeats if side <= 1024 else min(repeats, 3))
            # the whole command: the median of as many runs as the in-process row (a fresh
            # interpreter each; the first also warms the file cache), peak RSS the largest
            cli = [_cli_plot(path) for _ in range(repeats if side <= 1024 else 1)]
            cli_s = statistics.median(c[0] for c in cli)
            cli_rss, drawing_rss = (max((c[i] for c in cli if c[i] is not None), default=None)
                                    for i in (1, 2))
            rows.append({"n": side, "orbits": side * side, "run_s": run_s,
                         "plot_s": t["plot"][0], "plot_best_s": t["plot"][1],
                         "cli_s": cli_s, "cli_best_s": min(c[0] for c in cli),
                         "cli_peak_rss_bytes": cli_rss,
                         "cli_drawing_peak_rss_bytes": drawing_rss,
                         "streamed_peak_bytes": _peak_bytes(_streamed_maps, path),
                         "whole_peak_bytes": _peak_bytes(_whole_array_maps, path),
                         "image": [-(-side // -(-side // MAX_PIXELS))] * 2})
    return {"rows": rows, "max_pixels": MAX_PIXELS, "target_cli_512_s": PLOT_TARGET_S}


def _fmt_bytes(b) -> str:
    return "n/a" if b is None else f"{b / 2**20:.0f} MB" if b < 2**30 else f"{b / 2**30:.2f} GB"


def _label_mismatches(a, b) -> int:
    """Orbits whose status or (where trapped) attractor differ."""
    return int(np.sum((a[1] != b[1]) | ((a[1] == TRAPPED) & (a[0] != b[0]))))


def _fmt_rows(rows):
    lines = [f"  {'variant':62s} {'steps/s':>10s} {'orbits/s':>10s} {'512² map':>10s} "
             f"{'× atlas':>8s}"]
    for r in rows:
        lines.append(f"  {r['variant']:62s} {r['steps_per_s']:10.3g} {r['orbits_per_s']:10.3g} "
                     f"{_fmt_s(r['map_512_s']):>10s} {r['ratio_to_atlas']:8.3g}"
                     + (f"  ({r['note']})" if r["note"] else ""))
    return lines


def _fmt_s(s):
    return f"{s * 1e3:.0f} ms" if s < 1 else f"{s:.3g} s" if s < 600 else f"{s / 60:.3g} min"


def format_table(result: dict) -> str:
    """The benchmark as a plain-text table."""
    m, s = result["machine"], result["summary"]
    lines = [f"CPU: {m['cpu']}, {m['cores']} cores ({m['numba_threads']} numba threads); "
             f"python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, "
             f"llvmlite {m['llvmlite']}; {m['timestamp']}",
             f"Basin map {MAP_N}² (early exit; steps/s = needed RK4 steps / wall; × atlas = "
             f"time / the default method's; its labels equal the straightforward kernel's "
             f"(same check interval): {result['map']['labels_equal_straightforward']} "
             f"({result['map']['label_mismatches']} differ); trig-free lanes against theirs: "
             f"{result['map']['trigfree_labels_equal_straightforward']}, against the default's "
             f"{result['map']['trigfree_vs_rk4_label_mismatches']} orbits differ (a different "
             f"discretisation: boundary cells only))"]
    lines += _fmt_rows(result["map"]["rows"])
    lines.append("Bulk RK4, fixed steps, no early exit")
    lines += _fmt_rows(result["bulk"]["rows"])
    if "torque" in result:
        tq = result["torque"]
        lines.append(f"Torque: the swing equation's {tq['side']}² map (alpha 0.05, omega0 1, "
                     "bSTAB's window, t_max 400 s) against the same points untilted")
        for r in tq["rows"]:
            lines.append(f"  {r['variant']:48s} {_fmt_s(r['wall_s']):>9s} "
                         f"{r['orbits_per_s']:10.3g} orbits/s {r['ratio']:6.2f}× untilted")
    lines.append("Scaling, atlas map")
    for r in result["scaling"]:
        lines.append(f"  {r['n']:5d}² {r['orbits']:9d} orbits {_fmt_s(r['wall_s']):>9s} "
                     f"{r['orbits_per_s']:10.3g} orbits/s {r['ns_per_orbit']:8.1f} ns/orbit")
    if "threads" in result:
        lines.append(f"Threads, atlas map {result['threads']['side']}² (speed-up and "
                     "efficiency against one thread; labels equal one thread's)")
        for r in result["threads"]["rows"]:
            lines.append(f"  {r['threads']:3d} threads {_fmt_s(r['wall_s']):>9s} "
                         f"{r['speedup']:6.2f}× {100 * r['efficiency']:5.0f} %  "
                         f"same labels: {r['same_labels']}")
    if "plot" in result:
        pl = result["plot"]
        lines.append(f"Plotting: atlas plot of the default atlas at n² (3 PNGs; maps read band by "
                     f"band, coarsened to ≤ {pl['max_pixels']} px; in process: plot_atlas of the "
                     f"file opened lazily; CLI: the whole command, median, target ≤ "
                     f"{pl['target_cli_512_s']:g} s at 512²; memory of the maps: tracemalloc "
                     f"peak, streamed against whole float64 arrays as before)")
        for r in pl["rows"]:
            lines.append(f"  {r['n']:5d}² {r['orbits']:9d} orbits  in process "
                         f"{_fmt_s(r['plot_s']):>7s}  CLI {_fmt_s(r['cli_s']):>7s}, peak RSS "
                         f"{_fmt_bytes(r['cli_peak_rss_bytes']):>7s}  maps "
                         f"{_fmt_bytes(r['streamed_peak_bytes']):>7s} streamed vs "
                         f"{_fmt_bytes(r['whole_peak_bytes']):>7s} whole "
                         f"({r['image'][0]}² image; atlas run {_fmt_s(r['run_s'])})")
    if "jit" in result:
        for k, j in result["jit"].items():
            lines.append(f"JIT {k:10s}: import {j['import_s']:.2f} s, first call "
                         f"{j['first_call_s']:.2f} s, process {j['process_s']:.2f} s")
    t = result["targets"]
    jit = (f"; JIT cold {s['jit_cold_s']:.2f} s (< {t['jit_cold_s']:g}), warm cache "
           f"{s['jit_warm_s']:.2f} s (< {t['jit_warm_s']:g})" if "jit_cold_s" in s else "")
    lines.append(f"Summary: default map {s['map_speedup']:.1f}× straightforward (target ≥ "
                 f"{t['map_speedup']:g}×); trig-free map {s['trigfree_map_speedup']:.2f}× the "
                 f"default, {s['trigfree_equal_accuracy']['map_speedup']:.2f}× at equal accuracy "
                 f"(dt {s['trigfree_equal_accuracy']['dt']:g} s); bulk: default "
                 f"{s['default_bulk_msteps_s']:.0f} M steps/s, trig-free "
                 f"{s['bulk_msteps_s']:.0f} (target ≥ {t['bulk_msteps_s']:g}; best of repeats "
                 f"{s['bulk_msteps_s_best']:.0f}), {s['bulk_speedup']:.1f}× straightforward "
                 f"(target ≥ {t['bulk_speedup']:g}×) and {s['bulk_vs_lanes']:.2f}× the default "
                 f"lanes (target ≥ {t['bulk_vs_lanes']:g}×){jit}")
    if "end_to_end" in result:
        from atlas.commands.bench_e2e import format_end_to_end

        lines += format_end_to_end(result["end_to_end"])
    return "\n".join(lines)


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
