"""End to end: what a user waits for in ``atlas run`` of the default config, against a budget.

The budget: the time Python needs to import atlas's dependencies (numba, xarray, h5netcdf),
plus 3 × the default method's own kernel time on the 512² map (the same ``atlas bench`` run),
plus 0.5 s. Measured each in a fresh interpreter (:func:`run_python`), the median of
``repeats`` warm runs: ``atlas run`` of the default problem, the whole command, with the phases
it logs; the imports alone; the imports plus one call of a cached kernel (Numba's first-call
set-up). "Warm" includes atlas's own bytecode cache (:func:`warm_bytecode`). Why each part is
measured so: ``docs/design/bench.md``.
"""

from __future__ import annotations

import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from atlas import defaults

__all__ = ["end_to_end", "format_end_to_end", "OVERHEAD_S", "KERNEL_FACTOR"]

#: The budget: imports + KERNEL_FACTOR × the 512² map's kernel time + OVERHEAD_S.
KERNEL_FACTOR, OVERHEAD_S = 3.0, 0.5

#: The default problem's config: every key at its default (atlas.defaults).
_CONFIG = "name: bench-end-to-end\n"
_IMPORTS = "import numba, xarray, h5netcdf"
_FIRST_CALL = (_IMPORTS + "; import numpy as np; from atlas import label; "
               "label(np.zeros(64), np.linspace(-3, 3, 64), alpha=0.1, omega0=1.0)")
_PHASE = re.compile(r"^atlas: (.+?)\s+([0-9.]+) s$")


def phase_seconds(stderr: str) -> dict[str, float]:
    """{phase: seconds} of the phase lines ``atlas run -v`` writes to ``stderr``."""
    return {m.group(1).strip(): float(m.group(2))
            for m in map(_PHASE.match, stderr.splitlines()) if m}


#: atlas's package folder (its sources), whatever subpackage this module sits in.
_PACKAGE = Path(__file__).resolve().parents[1]


def warm_bytecode() -> bool:
    """Write the bytecode cache (``__pycache__``, next to atlas's sources) of every atlas
    module, as the first import does where Python may write it (this writes it even where
    ``PYTHONDONTWRITEBYTECODE`` is set). Returns whether every module's could be written (a
    read-only install: no, and the timed runs compile atlas's sources)."""
    import compileall

    return bool(compileall.compile_dir(str(_PACKAGE), quiet=2))


def run_python(argv: list[str], **env) -> tuple[float, subprocess.CompletedProcess]:
    """(wall s, the finished process) of a fresh interpreter running ``argv`` with this atlas
    first on its path and ``env`` added to the environment (output captured)."""
    root = str(_PACKAGE.parent)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [
        root, os.environ.get("PYTHONPATH")])), **env)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, *argv], env=env, check=True, capture_output=True,
                         text=True, timeout=600)
    return time.perf_counter() - t0, out


def end_to_end(map_kernel_s: float, repeats: int = 3) -> dict:
    """Time the whole ``atlas run`` of the default problem against the budget (module
    docstring); ``map_kernel_s`` [s]: the default method's 512² map kernel, from the same
    bench run."""
    bytecode = warm_bytecode()
    runs, phases = [], []
    with tempfile.TemporaryDirectory(prefix="atlas-bench-e2e-") as tmp:
        config = Path(tmp) / "default.yaml"
        config.write_text(_CONFIG)
        for i in range(repeats + 1):  # the first is the warm-up
            wall, out = run_python(["-m", "atlas", "run", str(config), "-v",
                                    "-o", str(Path(tmp) / f"run{i}.h5")])
            if i:
                runs.append(wall)
                phases.append(phase_seconds(out.stderr))
        imports = [run_python(["-c", _IMPORTS])[0] for _ in range(repeats)]
        first_call = [run_python(["-c", _FIRST_CALL])[0] for _ in range(repeats)]
    import_s = statistics.median(imports)
    budget = import_s + KERNEL_FACTOR * map_kernel_s + OVERHEAD_S
    run_s = statistics.median(runs)
    names = list(phases[0]) if phases else []
    return {"run_s": run_s, "run_best_s": min(runs), "import_s": import_s,
            "imports_and_first_call_s": statistics.median(first_call), "map_kernel_s": map_kernel_s,
            "budget_s": budget, "ratio_to_budget": run_s / budget,
            "bytecode_cached": bytecode,
            "phases_s": {name: statistics.median([ph.get(name, float("nan")) for ph in phases])
                         for name in names}}


def format_end_to_end(e: dict) -> list[str]:
    """The end-to-end rows of the bench table."""
    phases = ", ".join(f"{name} {s:.2f} s" for name, s in e["phases_s"].items()
                       if not name.startswith("wrote"))
    return [
        f"End to end: atlas run of the default config ({defaults.GRID_NUM}², separatrices on), "
        f"the whole command, warm caches: {e['run_s']:.2f} s (best {e['run_best_s']:.2f} s) "
        f"against a budget of {e['budget_s']:.2f} s = imports {e['import_s']:.2f} s + "
        f"{KERNEL_FACTOR:g} × map kernel {e['map_kernel_s'] * 1e3:.0f} ms + {OVERHEAD_S:g} s: "
        f"{e['ratio_to_budget']:.2f}× the budget",
        f"  phases (-v, medians): {phases}",
        f"  imports alone {e['import_s']:.2f} s; imports and Numba's first call of a cached "
        f"kernel {e['imports_and_first_call_s']:.2f} s"
        + ("" if e.get("bytecode_cached", True) else
           "; atlas's bytecode cache could not be written: every run compiled its sources"),
    ]
