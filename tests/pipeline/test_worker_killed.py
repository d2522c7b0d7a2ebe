"""Faults at scale: a Dask worker process killed (SIGKILL) in the middle of a grid run and of a
study, by its own task, once (a marker file), at a chosen tile or point: no finished tile or
point is lost — the client writes every tile exactly once and hears of every point exactly
once — and the result equals an undisturbed run's, array for array."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import atlas
from tests.helpers import REPO, study_config, write_config

pytestmark = pytest.mark.slow  # a local Dask cluster

distributed = pytest.importorskip("distributed")

#: 30 tiles of one grid row each: the kill lands at tile KILL_TILE with most still to do.
GRID = """\
pendulum: {{alpha: 0.1}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 48}}
  theta_dot0: {{start: -4, stop: 4, num: 30}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 48, backend: dask, scheduler: "{scheduler}"}}
output: {output}
"""
KILL_TILE = 12


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as c:
        yield c


def _worker_pids(cluster) -> set[int]:
    """The pids of the cluster's worker processes (asked with a client of its own, closed
    again: the run under test opens its own client in this process)."""
    with distributed.Client(cluster) as client:
        client.wait_for_workers(2, timeout=60)
        return set(client.run(os.getpid).values())


def _kill_once_in(cluster, module: str, name: str, marker, when) -> None:
    """On every worker, replace ``module.name`` (the task the client submits: looked up by
    name where the worker unpickles it) by a wrapper that SIGKILLs its own worker process at
    the first call whose arguments satisfy ``when`` (the marker file, created exclusively,
    records the pid: once in all)."""

    def install():
        import importlib

        target = importlib.import_module(module)
        real = getattr(target, name)

        def killing(*args, **kwargs):
            if when(*args):
                try:
                    fd = os.open(marker, os.O_WRONLY | os.O_CREAT | os.O_EXCL)
                except FileExistsError:
                    return real(*args, **kwargs)
                os.write(fd, str(os.getpid()).encode())
                os.close(fd)
                os.kill(os.getpid(), 9)
            return real(*args, **kwargs)

        setattr(target, name, killing)

    with distributed.Client(cluster) as client:
        client.wait_for_workers(2, timeout=60)
        client.run(install)


def test_a_worker_killed_by_its_tile_loses_no_finished_tile(tmp_path, cluster):
    c = cluster
    marker = tmp_path / "killed"
    cfg = write_config(tmp_path / "k.yaml", GRID.format(scheduler=c.scheduler_address,
                                                        output=tmp_path / "k.h5"))
    _kill_once_in(c, "atlas.pipeline.schedule", "compute_tile", str(marker),
                  lambda point, x0, v0, rows, *rest: rows.start == KILL_TILE)
    pids = _worker_pids(c)
    proc = subprocess.run([sys.executable, "-m", "atlas.cli", "run", "-vv", str(cfg),
                           "--quiet"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    killed = int(marker.read_text())
    assert killed in pids and killed not in _worker_pids(c)
    written = [int(m) for m in re.findall(r"tile (\d+) of 30 written", proc.stderr)]
    assert sorted(written) == list(range(1, 31))  # each tile written once, none lost
    # the kill came with tiles finished before it and many still to do
    assert 0 < written.index(KILL_TILE + 1) < 25
    local = atlas.load_config(cfg, output=tmp_path / "k0.h5")
    atlas.run(local, quiet=True, backend="cpu").close()
    a, b = (atlas.open(p).to_dataset(inherit=False) for p in (tmp_path / "k.h5",
                                                             tmp_path / "k0.h5"))
    for name in ("attractor", "status", "t_trap", "basin_fraction", "boundary_distance"):
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_a_worker_killed_by_its_point_loses_no_finished_point(tmp_path, cluster):
    """``atlas stability`` on the cluster, a worker killed by the task of its 4th point of 8:
    every point heard of once, the study file equal to the one computed here."""
    from atlas.commands.stability import run_study

    c = cluster
    marker = tmp_path / "killed"
    alphas = [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45]
    body = f"alpha: {alphas}, omega0: 1.0, torque: 0.3"
    extra = ("stability: {sigma_theta: 0.3, sigma_theta_dot: 0.5}\n"
             f"execution: {{backend: dask, scheduler: \"{c.scheduler_address}\"}}\n")
    cfg = study_config(tmp_path / "s.yaml", body, tmp_path / "s.h5", extra)
    here = study_config(tmp_path / "h.yaml", body, tmp_path / "h.h5",
                        "stability: {sigma_theta: 0.3, sigma_theta_dot: 0.5}\n")
    _kill_once_in(c, "atlas.stability.study", "_point_task", str(marker),
                  lambda alpha, *rest: math.isclose(alpha, alphas[3]))
    pids = _worker_pids(c)
    heard = []
    there, _, _ = run_study(cfg, on_result=lambda i, result: heard.append(i))
    killed = int(marker.read_text())
    assert killed in pids and killed not in _worker_pids(c)
    assert sorted(heard) == list(range(len(alphas)))  # each point once, none lost
    ours, _, _ = run_study(here)
    assert set(there.data_vars) == set(ours.data_vars)
    for name in ours.data_vars:
        np.testing.assert_array_equal(there[name].values, ours[name].values, err_msg=name)
