"""Fault soak (``make faults`` = ``python -m tools.faults``): interrupt real runs, resume
them, and check the result against an uninterrupted run, array for array.

Faults injected, each on a small grid (48 × 48 orbits in 48 tiles) so that hundreds fit in a
few minutes on two cores:

* ``kill -9`` at uniformly random instants of a run (start-up, tile computation, tile
  writes, assembly of the file), some followed by a second ``kill -9`` during the resume;
  the same for a Zarr output (``NAME.zarr``);
* SIGTERM at random instants (the run must stop with exit status 143 and one line);
* a real full disk: the run writes into a small tmpfs (a private mount namespace made with
  ``unshare``; where that is not permitted, a file-size limit, RLIMIT_FSIZE, instead), which
  is enlarged before the second run;
* the disk taken by another process mid-run: a small tmpfs that a second writer (``dd``)
  fills at a chosen phase of the run (while tiles are written, while the file's map is
  assembled, while its summary and while its groups are written); the space is then freed;
* hostile input: Hypothesis-generated configs (from the schema's keys, and mutations of a
  valid one) and byte-level damage to a valid atlas file, fed to ``atlas run``, ``info``,
  ``plot`` and ``view``; the same for studies (``stability.*`` keys and parameter ranges)
  and study files, fed to ``atlas stability``, ``info`` (``--check`` too) and ``plot``
  (``tests/commands/test_fuzz.py`` with ``ATLAS_FUZZ_SCALE=10``: ten times the examples of
  ``make test``);
* one bit flipped in a stored chunk of a finished atlas: ``atlas info --check`` must name
  its variable in one line, exit status 2, the file untouched;
* racing takeovers of a lock whose holder was SIGKILLed (8 processes; no two may hold it
  at once, every one must get it);
* two runs of different physics on one Dask scheduler at once;
* a Dask worker killed with SIGKILL mid-run.

Each row of the table: how many faults were injected, after how many the run was recovered
(the next plain ``atlas run`` completed), and after how many the result was identical to the
clean run (computed by separate ``atlas`` processes). Runs are forked from this process, its
kernels already loaded (Numba's fork-safe 'workqueue' threading layer), to avoid an
interpreter start per trial; random instants are scaled by the median time of such a run.
SIGTERM instants start after 2 % of a run: a signal during interpreter start-up, before any
of atlas runs, ends any Python program by the signal (nothing is written by then). The Dask
rows come last, as subprocesses.
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CONFIG = """\
pendulum: {{alpha: {alpha}}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 48}}
  theta_dot0: {{start: -4, stop: 4, num: 48}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 48{extra}}}
output: {output}
"""
COMPARED = ("attractor", "status", "t_trap", "basin_fraction", "k")


def _arrays(path: Path) -> dict[str, np.ndarray] | None:
    import h5py

    try:
        with h5py.File(path, "r") as f:
            if not f.attrs.get("complete", 0):
                return None
            return {name: f[name][...] for name in COMPARED}
    except OSError:
        return None


def _same(a, b) -> bool:
    return a is not None and b is not None and all(
        np.array_equal(a[n], b[n], equal_nan=True) for n in COMPARED)


def _fork_cli(argv: list[str], stderr: Path, fsize: int | None = None) -> int:
    """Start ``atlas <argv>`` in a forked child; return its pid."""
    pid = os.fork()
    if pid:
        return pid
    code = 99
    try:
        fd = os.open(stderr, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        os.dup2(fd, 2)
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        if fsize is not None:
            import resource

            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit: EFBIG
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
        from atlas.cli import main

        code = main(argv)
        sys.stderr.flush()
    finally:
        os._exit(code)


def _wait(pid: int) -> int:
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status)


def _run(argv, stderr, fsize=None) -> int:
    return _wait(_fork_cli(argv, stderr, fsize))


def _in_write(out: Path) -> bool:
    """Evidence that a kill landed inside a write: a tile or manifest mid-write, a
    half-built partial folder, or a file mid-assembly."""
    partial = out.with_name(out.name + ".partial")
    return (any(partial.glob("tiles/.*.tmp")) or any(partial.glob(".*.tmp"))
            or (partial / "assembly.h5").exists()
            or any(partial.glob("atlas.zarr/**/*.partial"))  # a Zarr chunk mid-write
            or any(out.parent.glob(out.name + ".partial.*.new")))


class Soak:
    def __init__(self, work: Path, seed: int):
        self.work = work
        self.rng = random.Random(seed)
        self.rows: list[tuple] = []
        self.n = 0

    def config(self, name: str, alpha=0.1, extra="", suffix=".h5") -> tuple[Path, Path]:
        out = self.work / f"{name}{suffix}"
        cfg = self.work / f"{name}.yaml"
        cfg.write_text(CONFIG.format(alpha=alpha, extra=extra, output=out))
        return cfg, out

    def err(self) -> Path:
        self.n += 1
        return self.work / f"stderr-{self.n}.txt"

    def reference(self) -> None:
        """The clean results, from fresh ``atlas`` processes (independent of this harness);
        then the harness's own run time, the scale of the random instants."""
        self.ref, self.ref_b = (self._clean(name, alpha) for name, alpha in
                                (("reference", 0.1), ("reference_b", 0.3)))
        cfg, out = self.config("timing")
        times = []
        for _ in range(3):
            start = time.perf_counter()
            assert _run(["run", str(cfg), "--quiet"], self.err()) == 0, "a clean run failed"
            times.append(time.perf_counter() - start)
            assert _same(_arrays(out), self.ref), "the harness's run differs from the CLI's"
        self.t_run = sorted(times)[1]

    def _clean(self, name, alpha):
        cfg, out = self.config(name, alpha)
        proc = subprocess.run([sys.executable, "-m", "atlas.cli", "run", str(cfg), "--quiet"],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        return _arrays(out)

    def _kill_at_random(self, argv, out, sig, lo=0.0, hi=1.0) -> tuple[int, bool, Path]:
        err = self.err()
        pid = _fork_cli(argv, err)
        time.sleep(self.rng.uniform(lo, hi) * self.t_run)
        os.kill(pid, sig)
        code = _wait(pid)
        return code, _in_write(out), err

    def _finish(self, cfg, out) -> tuple[bool, bool]:
        """Run again to completion: (recovered, identical to the clean run)."""
        err = self.err()
        ok = _run(["run", str(cfg), "--quiet"], err) == 0
        if not ok:
            print(f"not recovered: {err.read_text().strip()}", file=sys.stderr)
        if out.suffix == ".zarr":
            same = ok and _same_zarr_in_child(out, self.ref)
            shutil.rmtree(out, ignore_errors=True)
        else:
            same = ok and _same(_arrays(out), self.ref)
            out.unlink(missing_ok=True)
        shutil.rmtree(out.with_name(out.name + ".partial"), ignore_errors=True)
        return ok, same

    def kills(self, n: int, suffix: str = ".h5") -> None:
        cfg, out = self.config("kill", suffix=suffix)
        landed = in_write = second = recovered = identical = 0
        for _ in range(n):
            code, inside, _ = self._kill_at_random(["run", str(cfg), "--quiet"], out,
                                                   signal.SIGKILL)
            landed += code == -signal.SIGKILL
            in_write += inside
            if self.rng.random() < 0.3:  # a second kill during the resume
                code, inside, _ = self._kill_at_random(["run", str(cfg), "--quiet"], out,
                                                       signal.SIGKILL)
                second += code == -signal.SIGKILL
                in_write += inside
            ok, same = self._finish(cfg, out)
            recovered += ok
            identical += same
        what = "Zarr output, " if suffix == ".zarr" else ""
        self.rows.append((f"kill -9 at a random instant ({what}{landed} mid-run, {second} "
                          f"second kills in the resume, {in_write} inside a write)",
                          n, recovered, identical))

    def sigterms(self, n: int) -> None:
        cfg, out = self.config("term")
        clean = recovered = identical = 0
        for _ in range(n):
            code, _, err = self._kill_at_random(["run", str(cfg), "--quiet"], out,
                                                signal.SIGTERM, 0.02, 0.95)
            lines = err.read_text().strip().splitlines()
            ok = (code == 143 and len(lines) == 1 and "SIGTERM" in lines[0]) or code == 0
            clean += ok
            if not ok:
                print(f"SIGTERM: exit {code}, stderr {lines}", file=sys.stderr)
            ok, same = self._finish(cfg, out)
            recovered += ok
            identical += same
        self.rows.append((f"SIGTERM at a random instant ({clean} clean stops: exit 143, "
                          "one line)", n, min(recovered, clean), identical))

    def disk_full(self, sizes_kib: list[int]) -> None:
        cfg, out = self.config("full")
        how = "tmpfs" if _unshare_works(self.work) else "RLIMIT_FSIZE"
        recovered = identical = failed_cleanly = 0
        for size in sizes_kib:
            if how == "tmpfs":
                code, line, ok = _tmpfs_trial(cfg, self.work, size)
                got = _arrays(self.work / "full-copy.h5")
            else:
                err = self.err()
                code = _run(["run", str(cfg), "--quiet"], err, fsize=size * 1024)
                line = err.read_text().strip()
                ok = _run(["run", str(cfg), "--quiet"], self.err()) == 0
                got = _arrays(out)
            failed_cleanly += code == 1 and len(line.splitlines()) == 1 and (
                "No space left" in line or "too large" in line)
            recovered += ok
            identical += ok and _same(got, self.ref)
            shutil.rmtree(out.with_name(out.name + ".partial"), ignore_errors=True)
            out.unlink(missing_ok=True)
        self.rows.append((f"disk full mid-write ({how}; {failed_cleanly} stopped with exit 1 "
                          "and one line)", len(sizes_kib), min(recovered, failed_cleanly),
                          identical))

    def disk_taken(self, phases: list[str]) -> None:
        """Another process fills the disk at each phase of ``phases`` (:data:`PHASES`)."""
        if not _unshare_works(self.work):
            self.rows.append(("disk taken by another process (skipped: no mount namespaces)",
                              1, 1, 1))
            return
        cfg, _ = self.config("taken")
        clean = recovered = identical = 0
        for phase in phases:
            code, line, ok = _taken_trial(cfg, self.work, phase)
            got = _arrays(self.work / "taken-copy.h5")
            stopped = code == 1 and len(line.splitlines()) == 1 and "No space left" in line
            if not stopped:
                print(f"disk taken at {phase}: exit {code}, stderr {line!r}", file=sys.stderr)
            clean += stopped
            recovered += ok
            identical += ok and _same(got, self.ref)
        self.rows.append((f"disk taken by another process mid-run (tmpfs filled by dd at "
                          f"{', '.join(phases)}; {clean} stopped with exit 1 and one line)",
                          len(phases), min(recovered, clean), identical))

    def hostile_input(self, scale: int) -> None:
        """The property tests of hostile input, ``scale`` times their ``make test`` size: each
        example exits 0 with a sound file, or 2 with one line and nothing created or
        overwritten. The row fails (nothing recovered) where the tests cannot be found or
        ran none: a harness row must not read as passed while it runs nothing."""
        self.rows.append(hostile_input_row(Path(_package_root()), scale))

    def damaged_chunks(self, n: int) -> None:
        """A finished atlas with one bit flipped in a random compressed chunk (one h5py cannot
        read past: a few bits of a deflate stream change nothing read), ``n`` times:
        ``atlas info --check`` must exit 2 with one line naming that variable (recovered)
        and leave the file as it was (identical)."""
        import h5py

        cfg, out = self.config("chunks")
        assert _run(["run", str(cfg), "--quiet"], self.err()) == 0, "a clean run failed"
        chunks = []
        with h5py.File(out, "r") as f:
            for name, dset in f.items():
                if isinstance(dset, h5py.Dataset) and dset.chunks and dset.compression:
                    chunks += [(name, dset.id.get_chunk_info(i))
                               for i in range(dset.id.get_num_chunks())]
        clean = out.read_bytes()
        named = untouched = 0
        for _ in range(n):
            name, chunk = self.rng.choice(chunks)
            while True:  # a flip that h5py itself cannot read past
                damaged = bytearray(clean)
                damaged[chunk.byte_offset + self.rng.randrange(chunk.size)] ^= (
                    1 << self.rng.randrange(8))
                out.write_bytes(bytes(damaged))
                try:
                    with h5py.File(out, "r") as f:
                        f[name][...]
                except OSError:
                    break
            err = self.err()
            code = _run(["info", "--check", str(out)], err)
            lines = err.read_text().strip().splitlines()
            ok = code == 2 and len(lines) == 1 and f"variable {name}:" in lines[0]
            if not ok:
                print(f"info --check: exit {code}, stderr {lines}", file=sys.stderr)
            named += ok
            untouched += out.read_bytes() == bytes(damaged)
        out.unlink()
        self.rows.append(("one bit flipped in a stored chunk (atlas info --check: exit 2, "
                          "one line naming the variable; identical = file untouched)", n,
                          named, untouched))

    def lock_races(self, n: int, racers: int = 8) -> None:
        out = self.work / "race.h5"
        recovered = clean = 0
        for trial in range(n):
            records = self.work / f"race-{trial}"
            records.mkdir()
            holder = os.fork()
            if holder == 0:
                _hold_forever(out)
            time.sleep(0.3)
            pids = []
            for _ in range(racers):
                pid = os.fork()
                if pid == 0:
                    _race(out, records)  # never returns
                pids.append(pid)
            time.sleep(self.rng.uniform(0.0, 0.3))
            os.kill(holder, signal.SIGKILL)
            _wait(holder)
            codes = [_wait(p) for p in pids]
            spans = sorted(tuple(map(float, f.read_text().split()))
                           for f in records.iterdir())
            recovered += codes == [0] * racers and len(spans) == racers
            clean += all(a[1] <= b[0] for a, b in zip(spans, spans[1:]))
        self.rows.append((f"racing takeovers of a SIGKILLed holder's lock ({racers} racers; "
                          "identical = no two holders at once)", n, recovered, clean))

    def dask(self, n_pairs: int, n_kills: int) -> None:
        import logging

        from distributed import Client, LocalCluster

        for name in ("distributed", "dask"):  # a killed worker is expected here
            logging.getLogger(name).setLevel(logging.CRITICAL)

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            extra = f', backend: dask, scheduler: "{cluster.scheduler_address}"'
            recovered = identical = 0
            for _ in range(n_pairs):
                runs = [self.config(name, alpha, extra) for name, alpha in (("da", 0.1),
                                                                            ("db", 0.3))]
                procs = [_cli_subprocess(cfg) for cfg, _ in runs]
                codes = [p.wait() for p in procs]
                recovered += codes == [0, 0]
                identical += (_same(_arrays(runs[0][1]), self.ref)
                              and _same(_arrays(runs[1][1]), self.ref_b))
                for _, out in runs:
                    out.unlink(missing_ok=True)
            self.rows.append(("two runs of different physics on one Dask scheduler",
                              n_pairs, recovered, identical))
            recovered = identical = 0
            for _ in range(n_kills):
                cfg, out = self.config("dk", 0.1, extra)
                proc = _cli_subprocess(cfg, "-vv")
                written = 0
                for line in proc.stderr:
                    written += " written" in line
                    if written == 20:
                        break
                pids = client.run(os.getpid)
                os.kill(self.rng.choice(list(pids.values())), signal.SIGKILL)
                proc.stderr.read()
                recovered += proc.wait() == 0
                identical += _same(_arrays(out), self.ref)
                out.unlink(missing_ok=True)
                client.wait_for_workers(2, timeout=60)
            self.rows.append(("a Dask worker SIGKILLed mid-run", n_kills, recovered,
                              identical))


def _same_zarr_in_child(path: Path, ref: dict) -> bool:
    """Compare a Zarr atlas with ``ref`` in a forked child: zarr's I/O thread is never started
    in this process, which keeps forking safe."""
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            from atlas.store.reader import open_atlas

            root = open_atlas(path).to_dataset(inherit=False)
            code = 0 if _same({n: root[n].values for n in COMPARED}, ref) else 1
        finally:
            os._exit(code)
    return _wait(pid) == 0


def _cli_subprocess(cfg: Path, *flags) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "atlas.cli", "run", str(cfg), "--quiet",
                             *flags], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)


def _hold_forever(out: Path) -> None:
    from atlas.pipeline.lock import output_lock

    with output_lock(out):
        time.sleep(3600)
    os._exit(0)


def _race(out: Path, records: Path) -> None:
    code = 1
    try:
        from atlas.pipeline.lock import OutputLocked, output_lock

        while True:
            try:
                with output_lock(out):
                    entered = time.monotonic()
                    time.sleep(0.02)
                    left = time.monotonic()
                break
            except OutputLocked:
                time.sleep(0.001)
        (records / str(os.getpid())).write_text(f"{entered} {left}")
        code = 0
    finally:
        os._exit(code)


def _unshare_works(work: Path) -> bool:
    if not shutil.which("unshare"):
        return False
    probe = work / "probe"
    probe.mkdir(exist_ok=True)
    return subprocess.run(["unshare", "--user", "--map-root-user", "--mount", "sh", "-c",
                           f"mount -t tmpfs -o size=64k none {probe}"],
                          capture_output=True).returncode == 0


def _tmpfs_trial(cfg: Path, work: Path, size_kib: int) -> tuple[int, str, bool]:
    """In a private mount namespace: a tmpfs of ``size_kib`` KiB at the output folder; run
    (expecting a full disk), enlarge the tmpfs, run again, copy the result out."""
    disk = work / "disk"
    disk.mkdir(exist_ok=True)
    out = disk / "out.h5"
    run = f"{sys.executable} -m atlas.cli run {cfg} --quiet -o {out}"
    script = (f"mount -t tmpfs -o size={size_kib}k none {disk} || exit 90; "
              f"{run} 2> {work}/full-err.txt; echo $? > {work}/full-code.txt; "
              f"mount -o remount,size=64m {disk} || exit 91; "
              f"{run} 2> {work}/full-err2.txt && cp {out} {work}/full-copy.h5")
    (work / "full-copy.h5").unlink(missing_ok=True)
    recovered = _in_mount_namespace(script)
    code = int((work / "full-code.txt").read_text())
    return code, (work / "full-err.txt").read_text().strip(), recovered


#: Where :func:`_taken_trial` lets another process fill the disk: the function of atlas that
#: is about to write when the space goes.
PHASES = {"tiles": ("atlas.store.partial", "TileStore", "record", 3),
          "assembly": ("atlas.store.hdf5", None, "_copy_tiles", 1),
          "summary": ("atlas.store.hdf5", None, "_write_summary", 1),
          "groups": ("h5netcdf", "Group", "create_group", 1)}
_TAKER = """\
import importlib, subprocess, sys
from pathlib import Path
module, owner, name, call = {hook!r}
target = importlib.import_module(module)
target = getattr(target, owner) if owner else target
real, calls = getattr(target, name), []
def taken(*args, **kwargs):
    calls.append(1)
    if len(calls) == call:  # another process takes every free byte, now
        subprocess.run(["dd", "if=/dev/zero", "of={hog}", "bs=4096"], capture_output=True)
    return real(*args, **kwargs)
setattr(target, name, taken)
from atlas.cli import main
sys.exit(main(["run", {cfg!r}, "--quiet", "-o", {out!r}]))
"""


def _taken_trial(cfg: Path, work: Path, phase: str) -> tuple[int, str, bool]:
    """In a private mount namespace: a 4 MiB tmpfs at the output folder; run, another process
    (dd) filling the disk at ``phase``; free the space, run again, copy the result out."""
    disk = work / "taken"
    disk.mkdir(exist_ok=True)
    out, hog = disk / "out.h5", disk / "hog"
    script = work / "taken.py"
    script.write_text(_TAKER.format(hook=PHASES[phase], hog=hog, cfg=str(cfg), out=str(out)))
    run = f"{sys.executable} -m atlas.cli run {cfg} --quiet -o {out}"
    shell = (f"mount -t tmpfs -o size=4m none {disk} || exit 90; "
             f"{sys.executable} {script} 2> {work}/taken-err.txt; "
             f"echo $? > {work}/taken-code.txt; rm -f {hog}; "
             f"{run} 2> {work}/taken-err2.txt && cp {out} {work}/taken-copy.h5")
    (work / "taken-copy.h5").unlink(missing_ok=True)
    recovered = _in_mount_namespace(shell)
    code = int((work / "taken-code.txt").read_text())
    return code, (work / "taken-err.txt").read_text().strip(), recovered


def _in_mount_namespace(shell: str) -> bool:
    """Run ``shell`` (sh) in a private user and mount namespace, with this atlas importable;
    True if it exited 0."""
    done = subprocess.run(["unshare", "--user", "--map-root-user", "--mount", "sh", "-c",
                           shell], capture_output=True,
                          env={**os.environ, "PYTHONPATH": _package_root()})
    return done.returncode == 0


#: The fuzz tests the soak runs at scale (``make faults``), from the checkout's root.
FUZZ_TESTS = Path("tests") / "commands" / "test_fuzz.py"


def hostile_input_row(root: Path, scale: int) -> tuple[str, int, int, int]:
    """The table row of the fuzz tests at ``root`` / :data:`FUZZ_TESTS` run with
    ``ATLAS_FUZZ_SCALE=scale``: (what, injected, recovered, identical). Not found, failed
    or no test run (pytest's exit 5): recovered and identical 0."""
    tests = root / FUZZ_TESTS
    # each property test (@FUZZ) draws 40 examples at scale 1
    n = 40 * scale * max(1, tests.read_text().count("\n@FUZZ\n") if tests.exists() else 0)
    what = (f"hostile input: fuzzed configs and studies, damaged atlas and study files (up "
            f"to {n} examples; recovered = exit 0 or one line, identical = nothing created "
            "or overwritten)")
    if not tests.exists():
        return (f"hostile input: FAILED, {FUZZ_TESTS} not found", n, 0, 0)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           str(tests)], capture_output=True, text=True, cwd=root,
                          env={**os.environ, "ATLAS_FUZZ_SCALE": str(scale)})
    if proc.returncode != 0:
        print(proc.stdout[-3000:], file=sys.stderr)
        why = "no test ran" if proc.returncode == 5 else f"pytest exit {proc.returncode}"
        return (f"hostile input: FAILED ({why}); {what}", n, 0, 0)
    return (what, n, n, n)


def _package_root() -> str:
    return str(Path(__file__).resolve().parents[1])


def _warm_kernels() -> None:
    """Compile (load) the kernels here once, so forked runs skip it. Numba's 'workqueue'
    threading layer survives fork; GNU OpenMP's does not."""
    import numba

    from atlas.labels.labelling import label

    numba.config.THREADING_LAYER = "workqueue"
    label(np.array([1.0]), np.array([0.5]), alpha=0.1, omega0=1.0)


def _table(rows) -> str:
    width = max(len(r[0]) for r in rows)
    lines = [f"{'fault':<{width}}  injected  recovered  identical",
             f"{'-' * width}  --------  ---------  ---------"]
    for what, n, recovered, identical in rows:
        lines.append(f"{what:<{width}}  {n:>8}  {recovered:>5} ({100 * recovered // n:>3} %)"
                     f"  {identical:>5} ({100 * identical // n:>3} %)".replace(" ( ", " ("))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.faults", description=__doc__
                                     .splitlines()[0])
    parser.add_argument("--kills", type=int, default=100, help="kill -9 trials (100)")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--quick", action="store_true", help="a few of each, for a smoke test")
    args = parser.parse_args(argv)
    kills, zarr_kills, terms, races, pairs, dask_kills, flips = (
        (6, 2, 2, 1, 1, 1, 3) if args.quick else (args.kills, 20, 10, 5, 2, 2, 30))
    start = time.perf_counter()
    _warm_kernels()
    with tempfile.TemporaryDirectory(prefix="atlas-faults-") as tmp:
        soak = Soak(Path(tmp), args.seed)
        soak.reference()
        print(f"a run: {soak.t_run:.2f} s (48 x 48 orbits, 48 tiles)", file=sys.stderr)
        soak.kills(kills)
        soak.kills(zarr_kills, ".zarr")
        soak.sigterms(terms)
        soak.disk_full([16, 64, 128, 200] if not args.quick else [96])
        soak.disk_taken(list(PHASES) if not args.quick else ["assembly"])
        soak.hostile_input(1 if args.quick else 10)
        soak.damaged_chunks(flips)
        soak.lock_races(races)
        soak.dask(pairs, dask_kills)
    print(_table(soak.rows))
    print(f"({time.perf_counter() - start:.0f} s)")
    perfect = all(r[1] == r[2] == r[3] for r in soak.rows)
    return 0 if perfect else 1


if __name__ == "__main__":
    sys.exit(main())
