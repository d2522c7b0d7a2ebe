"""``atlas bench``, the kernel rows: the default kernel against its peers on the default map.

On the n × n grid of the default problem (:mod:`atlas.defaults`): the basin map with early
exit (the default lanes of method "rk4", the trig-free lanes, the straightforward kernel
tested every step and every ``CHECK_EVERY`` steps, numpy without early exit, scipy's LSODA on a
sample), the trig-free lanes at the step as accurate as the default (:func:`equal_dt`), bulk
RK4 steps without early exit, the swing equation's torque map against the untilted one, and
the JIT's cold and warm start. Every time is the median of ``repeats`` rounds after a warm-up
(:func:`median_times`), the variants in turn within a round. What each row means:
``docs/design/bench.md``.
"""

from __future__ import annotations

import statistics
import tempfile
import time

import numpy as np

from atlas import defaults
from atlas.kernels.lanes import label_lanes, label_trigfree, propagate_lanes, propagate_trigfree
from atlas.kernels.rk4 import label_straightforward, make_rk4_step, propagate_straightforward
from atlas.kernels.trigfree import label_trigfree_straightforward
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for
from atlas.status import TRAPPED

__all__ = ["MAP_N", "median_times", "label_grid", "label_run", "kernel_rows", "torque_rows",
           "jit_times", "label_mismatches"]

MAP_N = defaults.GRID_NUM

# The same RK4 definition evaluated by numpy on whole arrays: make_rk4_step's Python body
# with plain-Python sin/reduce (the Numba wrapper is never compiled).
_numpy_step = make_rk4_step(lambda p, delta: np.sin(p + delta), reduce=lambda x: x).py_func


def median_times(runs: dict, repeats: int, warm_up: bool = True) -> dict:
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


def label_grid(kernel, theta0, theta_dot0, check_every, p):
    n = theta0.size
    out = (np.zeros(n, np.int32), np.zeros(n, np.int8), np.zeros(n, np.int32))
    kernel(theta0, theta_dot0, p["alpha"], p["omega0"], p["dt"],
           n_checks_for(p["t_max"], p["dt"], check_every), check_every,
           energy_cap(p["dt"], p["alpha"], p["omega0"]), *out)
    return out


def label_run(kernel, theta0, theta_dot0, check_every, p):
    return lambda: label_grid(kernel, theta0, theta_dot0, check_every, p)


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

    from atlas.physics.pendulum import Pendulum

    rhs = Pendulum(p["alpha"], p["omega0"]).rhs

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


def jit_times():
    """(cold, warm) dicts of import_s, first_call_s, process_s (wall incl. interpreter)."""
    from atlas.commands.bench_e2e import run_python

    result = []
    with tempfile.TemporaryDirectory() as cache:
        for _ in ("cold", "warm"):
            wall, out = run_python(["-c", _JIT_SCRIPT], NUMBA_CACHE_DIR=cache)
            import_s, call_s = map(float, out.stdout.split()[-2:])
            result.append({"import_s": import_s, "first_call_s": call_s, "process_s": wall})
    return result




def _boundary_shift(p: dict, dt: float, method: str) -> float:
    """The RK4 map's basin-boundary shift from the exact boundaries [rad-ish] over the default
    window (the separatrices' ``discrepancy``, which sets d_cert)."""
    from atlas.boundaries.trace import trace
    from atlas.physics.pendulum import Pendulum

    sep = trace(Pendulum(p["alpha"], p["omega0"]), defaults.THETA0_WINDOW,
                defaults.THETA_DOT0_WINDOW, dt=dt, method=method)
    return float(sep.attrs["discrepancy"])


def equal_dt(p: dict) -> tuple[float, float, float]:
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




def _row(variant, steps_s, orbits_s, map_s, atlas_map_s, note=""):
    return {"variant": variant, "steps_per_s": steps_s, "orbits_per_s": orbits_s,
            "map_s": map_s, "ratio_to_atlas": map_s / atlas_map_s, "note": note}




def kernel_rows(p: dict, repeats: int, quick: bool, lsoda_sample: int,
                side: int = MAP_N) -> dict:
    """The basin-map and bulk rows of problem ``p`` on the ``side``² grid of the default
    window (module docstring): {"map", "bulk", "best_of_repeats_s", "summary", "atlas_s": the
    default map's time}. Every row's ratio compares the same orbits. ``quick``: fewer bulk
    and numpy steps, and no trig-free row at equal accuracy (finding its step traces the
    default window's separatrices five times or more: tens of seconds)."""
    full_steps = n_checks_for(p["t_max"], p["dt"], 1)  # steps to t_max
    theta0, theta_dot0 = defaults.grid(side)
    n = theta0.size

    # basin map, early exit
    ref = label_grid(label_straightforward, theta0, theta_dot0, 1, p)
    ref16 = label_grid(label_straightforward, theta0, theta_dot0, CHECK_EVERY, p)
    ref_tf = label_grid(label_trigfree_straightforward, theta0, theta_dot0, CHECK_EVERY, p)
    atl = label_grid(label_lanes, theta0, theta_dot0, CHECK_EVERY, p)
    atl_tf = label_grid(label_trigfree, theta0, theta_dot0, CHECK_EVERY, p)
    trapped = ref[1] == TRAPPED
    useful = float(np.where(trapped, ref[2], full_steps).sum())  # steps the orbits need
    np_steps = 5 if quick else 20
    bulk_steps = {"atlas rk4 lanes propagate (default)": 50 if quick else 200,
                  "trig-free lanes propagate": 50 if quick else 200,
                  "straightforward numba propagate": 5 if quick else 20,
                  "numpy whole grid": np_steps}
    default_bulk, trigfree_bulk = list(bulk_steps)[:2]
    equal = None if quick else equal_dt(p)  # (dt, its boundary shift, the default's)
    runs = {
        "lanes": label_run(label_lanes, theta0, theta_dot0, CHECK_EVERY, p),
        "trigfree": label_run(label_trigfree, theta0, theta_dot0, CHECK_EVERY, p),
        "sf1": label_run(label_straightforward, theta0, theta_dot0, 1, p),
        "sf16": label_run(label_straightforward, theta0, theta_dot0, CHECK_EVERY, p),
        default_bulk: _propagate_run(propagate_lanes, theta0, theta_dot0,
                                     bulk_steps[default_bulk], p),
        trigfree_bulk: _propagate_run(propagate_trigfree, theta0, theta_dot0,
                                      bulk_steps[trigfree_bulk], p),
        "straightforward numba propagate": _propagate_run(
            propagate_straightforward, theta0, theta_dot0,
            bulk_steps["straightforward numba propagate"], p),
        "numpy whole grid": _propagate_run(_numpy_propagate, theta0, theta_dot0, np_steps, p),
    }
    if equal is not None:
        runs["trigfree_equal"] = label_run(label_trigfree, theta0, theta_dot0, CHECK_EVERY,
                                           {**p, "dt": equal[0]})
    t = median_times(runs, repeats)
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
        *([] if equal is None else [_row(
            f"trig-free lanes at dt = {equal[0]:g} s, as accurate as the default",
            useful * p["dt"] / equal[0] / t["trigfree_equal"][0], n / t["trigfree_equal"][0],
            t["trigfree_equal"][0], atlas_s,
            f"boundary shift {equal[1]:.2g} vs the default's {equal[2]:.2g}; "
            "steps/s counts its steps")]),
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

    mismatches = label_mismatches(atl, ref16)
    summary = {"map_speedup": sf1_s / atlas_s,
               "trigfree_map_speedup": atlas_s / trigfree_s,
               "default_bulk_msteps_s": rates[default_bulk] / 1e6,
               "bulk_msteps_s": rates[trigfree_bulk] / 1e6,
               "bulk_msteps_s_best": n * bulk_steps[trigfree_bulk] / t[trigfree_bulk][1] / 1e6,
               "bulk_speedup": rates[trigfree_bulk] / rates["straightforward numba propagate"],
               "bulk_vs_lanes": rates[trigfree_bulk] / rates[default_bulk]}
    if equal is not None:
        summary["trigfree_equal_accuracy"] = {
            "dt": equal[0], "boundary_shift": equal[1], "default_boundary_shift": equal[2],
            "map_speedup": atlas_s / t["trigfree_equal"][0]}
    return {
        "map": {"rows": map_rows, "side": side,
                "labels_equal_straightforward": mismatches == 0,
                "trigfree_labels_equal_straightforward": label_mismatches(atl_tf, ref_tf) == 0,
                "label_mismatches": mismatches,
                "trigfree_vs_rk4_label_mismatches": label_mismatches(atl_tf, atl),
                "trigfree_vs_rk4_status_mismatches": int(np.sum(atl_tf[1] != atl[1])),
                "useful_steps": useful},
        "bulk": {"rows": bulk_rows},
        "best_of_repeats_s": {name: best for name, (_, best) in t.items()},
        "summary": summary,
        "atlas_s": atlas_s,
    }


def torque_rows(side: int, repeats: int) -> dict:
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
    t = median_times(runs, repeats)
    n = theta0.size * theta_dot0.size
    return {"side": side, "orbits": n,
            "rows": [{"variant": "untilted (tau = 0), energy trap", "wall_s": t["untilted"][0],
                      "orbits_per_s": n / t["untilted"][0], "ratio": 1.0},
                     {"variant": "torque tau = 0.5, tilted trap + running barrier",
                      "wall_s": t["torque"][0], "orbits_per_s": n / t["torque"][0],
                      "ratio": t["torque"][0] / t["untilted"][0]}]}




def label_mismatches(a, b) -> int:
    """Orbits whose status or (where trapped) attractor differ."""
    return int(np.sum((a[1] != b[1]) | ((a[1] == TRAPPED) & (a[0] != b[0]))))
