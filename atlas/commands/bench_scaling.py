"""``atlas bench``, the scaling rows: the default map on finer grids and on more threads.

The atlas map (the default lanes, :func:`atlas.kernels.lanes.label_lanes`) of the default
window at 256² … 4096² (wall time, orbits/s, ns per orbit; 128² and 256² in a quick run), and
the 1024² map (128² in a quick run) on 1, 2, 4, …
Numba threads up to all of them: speed-up and parallel efficiency against one thread, and
whether the labels equal one thread's (they must: orbits never interact).
"""

from __future__ import annotations

import numpy as np

from atlas import defaults
from atlas.commands.bench_kernels import label_grid, label_run, median_times
from atlas.kernels.lanes import label_lanes
from atlas.labels.trap import CHECK_EVERY

__all__ = ["SCALING", "QUICK_SCALING", "size_rows", "thread_rows"]

SCALING = (256, 512, 1024, 2048, 4096)
#: A quick run's sides: a few tenths of a second each (the per-orbit cost is the same).
QUICK_SCALING = (128, 256)


def size_rows(sizes, repeats: int, p: dict) -> list[dict]:
    """The atlas map of problem ``p`` at each grid side in ``sizes`` (one repeat above
    1024²)."""
    rows = []
    for side in sizes:
        th, v = defaults.grid(side)
        s = median_times({"atlas": label_run(label_lanes, th, v, CHECK_EVERY, p)},
                         repeats if side <= 1024 else 1)["atlas"][0]
        rows.append({"n": side, "orbits": th.size, "wall_s": s, "orbits_per_s": th.size / s,
                     "ns_per_orbit": s / th.size * 1e9})
    return rows


def thread_rows(side: int, repeats: int, p: dict) -> list[dict]:
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
            labels = label_grid(label_lanes, th, v, CHECK_EVERY, p)
            first = first or labels
            s = median_times({"map": label_run(label_lanes, th, v, CHECK_EVERY, p)},
                              repeats, warm_up=False)["map"][0]  # warmed by the labels above
            rows.append({"threads": count, "wall_s": s, "same_labels": all(
                np.array_equal(a, b) for a, b in zip(labels, first))})
    finally:
        numba.set_num_threads(saved)
    for row in rows:
        row["speedup"] = rows[0]["wall_s"] / row["wall_s"]
        row["efficiency"] = row["speedup"] / row["threads"]
    return rows
