"""Is this checkout slower than another commit? The runs a restructure must not slow down,
timed side by side: the default end-to-end run (``atlas run configs/default.yaml``), the
torque sweep (``configs/swing_torque.yaml``) and the 1,001-point study (``atlas stability
configs/swing_stability.yaml``), each run by the old commit and by this checkout in turn
(old, new, old, new, …), so that the machine's drift and load fall on both alike:

    python -m tools.bench_against 8fc1cfe            # 3 rounds each
    python -m tools.bench_against 8fc1cfe --rounds 5 --only torque

The old commit is checked out into a temporary git worktree and run with this checkout's
interpreter and libraries (``PYTHONPATH`` set to it); each side's Numba cache is warmed by
one untimed run of each job first. Prints each job's median wall time per side and their
ratio (new / old). Wall time of the whole ``atlas`` process, start-up included, as a user
waits for it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: The jobs: name → atlas arguments (a config of this checkout; ``{out}``: an output folder).
JOBS = {
    "default end to end": ["run", "configs/default.yaml", "-o", "{out}/default.h5"],
    "torque sweep (19 points)": ["run", "configs/swing_torque.yaml", "-o",
                                 "{out}/swing_torque.h5"],
    "study (1,001 torques)": ["stability", "configs/swing_stability.yaml", "-o",
                              "{out}/swing_stability.h5"],
}


def _run(tree: Path, args: list[str], out: Path) -> float:
    """Seconds of one ``python -m atlas ARGS`` of the checkout at ``tree`` (run in it)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    argv = [sys.executable, "-m", "atlas", *(a.format(out=out) for a in args), "--force"]
    start = time.perf_counter()
    subprocess.run(argv, cwd=tree, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def compare(old: str, rounds: int = 3, only: str = "") -> dict[str, tuple[float, float]]:
    """{job: (median seconds of the old commit, of this checkout)} of the jobs whose name
    holds ``only``."""
    jobs = {name: args for name, args in JOBS.items() if only in name}
    with tempfile.TemporaryDirectory(prefix="atlas-old-") as tmp:
        tree, out = Path(tmp) / "old", Path(tmp) / "out"
        out.mkdir()
        subprocess.run(["git", "worktree", "add", "--detach", str(tree), old], cwd=REPO,
                       check=True, capture_output=True)
        try:
            sides = {"old": tree, "new": REPO}
            for side in sides:
                (out / side).mkdir()
            times = {job: {side: [] for side in sides} for job in jobs}
            for args in jobs.values():  # warm both Numba caches, untimed
                for side, path in sides.items():
                    _run(path, args, out / side)
            for _ in range(rounds):
                for job, args in jobs.items():
                    for side, path in sides.items():
                        times[job][side].append(_run(path, args, out / side))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=REPO,
                           check=False, capture_output=True)
    return {job: (statistics.median(t["old"]), statistics.median(t["new"]))
            for job, t in times.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", help="the commit to compare with (e.g. 8fc1cfe)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--only", default="", help="the jobs whose name holds this word")
    args = parser.parse_args(argv)
    result = compare(args.old, args.rounds, args.only)
    print(f"{'job':<28}{'old [s]':>10}{'new [s]':>10}{'new/old':>10}")
    for job, (old, new) in result.items():
        print(f"{job:<28}{old:>10.2f}{new:>10.2f}{new / old:>10.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
