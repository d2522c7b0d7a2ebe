"""``atlas bench``, the plotting rows: ``atlas plot`` of generated atlases, time and memory.

For each grid side (512² and 4096²; 256² only in a quick run) the default config's atlas is
written first (:func:`atlas.run`, separatrices on), then timed: in process
(:func:`atlas.views.plotting.plot_atlas` of the file opened lazily, as the CLI opens it;
median of the repeats) and the whole command in a fresh interpreter (wall, and peak RSS of
it and of its largest drawing process). The maps are read band by band and coarsened to at
most ``MAX_PIXELS`` per axis; the row also gives the peak memory (tracemalloc) of reading
them that way against loading each whole as float64 and coarsening it in memory.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from atlas.commands.bench_kernels import median_times
from atlas.status import NEAR_BOUNDARY, TRAPPED

__all__ = ["PLOT_SIDES", "QUICK_PLOT_SIDES", "PLOT_TARGET_S", "plot_rows"]

#: Grid sides of the plotting rows (a quick run: one small atlas, one repeat).
PLOT_SIDES = (512, 4096)
QUICK_PLOT_SIDES = (256,)
#: Target of the plotting rows: ``atlas plot`` of the default 512² atlas, the whole command.
PLOT_TARGET_S = 1.0


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
    from atlas.store.reader import open_atlas
    from atlas.views.coarsen import coarsen_blocks

    tree = open_atlas(path)
    try:
        ds = tree.to_dataset(inherit=False).load()
    finally:
        tree.close()
    k = ds["attractor"].values.astype(float)
    k[~np.isin(ds["status"].values, (TRAPPED, NEAR_BOUNDARY))] = np.nan
    coarsen_blocks(k, "mode")
    del k
    t = ds["t_trap"].values.astype(float)
    coarsen_blocks(np.where(t > 0, t, 1.0), "max")
    del t
    coarsen_blocks(ds["boundary_distance"].values.astype(float), "min")


def _streamed_maps(path) -> None:
    """The maps of the atlas at ``path`` as ``atlas plot`` reads them: band by band."""
    from atlas.store.reader import open_atlas
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


def plot_rows(sides, repeats: int, quick: bool = False) -> dict:
    """``atlas plot`` of generated atlases (module docstring), warm: atlas's bytecode cache
    written first (:func:`atlas.commands.bench_e2e.warm_bytecode`). ``quick``: the whole
    command only, once (the in-process time and the memory rows are None)."""
    from atlas.commands.bench_e2e import warm_bytecode
    from atlas.pipeline.config import load_config
    from atlas.pipeline.sweep import run
    from atlas.store.reader import open_atlas
    from atlas.views.coarsen import MAX_PIXELS
    from atlas.views.plotting import plot_atlas

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

            t = ({"plot": (None, None)} if quick else
                 median_times({"plot": plot}, repeats if side <= 1024 else min(repeats, 3)))
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
                         "streamed_peak_bytes": None if quick else _peak_bytes(_streamed_maps,
                                                                               path),
                         "whole_peak_bytes": None if quick else _peak_bytes(_whole_array_maps,
                                                                            path),
                         "image": [-(-side // -(-side // MAX_PIXELS))] * 2})
    return {"rows": rows, "max_pixels": MAX_PIXELS, "target_cli_512_s": PLOT_TARGET_S}
