"""``--backend dask``: parameter points as Dask tasks, each worker computing whole points; a
worker killed in the middle of the study changes nothing in the result (its points are
computed again elsewhere, and a point depends only on its numbers)."""

from __future__ import annotations

import math
import os
import signal

import numpy as np
import pytest

from atlas.stability.study import StudySettings, compute_points

pytestmark = pytest.mark.slow  # a local Dask cluster


def _same(a, b) -> None:
    assert (a.status, a.message) == (b.status, b.message)
    for name in ("k", "fraction", "error"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert (a.running, a.running_error) == (b.running, b.running_error)
    np.testing.assert_array_equal(np.array(a.shock), np.array(b.shock))
    np.testing.assert_array_equal(np.array(a.gaussian), np.array(b.gaussian))


def test_a_killed_worker_changes_nothing():
    from distributed import Client, LocalCluster

    points = [(a, 1.0, 0.0) for a in (0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)]
    settings = StudySettings(window=((-math.pi, math.pi), (-3.0, 3.0)), sigma=(0.5, 0.5))
    here = compute_points(points, settings)
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    client = Client(cluster)
    killed = []

    def kill_a_busy_worker(i, result):
        if killed:
            return
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    try:
        there = compute_points(points, settings, backend="dask",
                               scheduler=cluster.scheduler_address,
                               on_result=kill_a_busy_worker)
    finally:
        client.close()
        cluster.close()
    assert killed, "no worker was busy when the first point came back"
    for a, b in zip(here, there):
        _same(a, b)


def test_threads_give_the_same_points():
    """``--backend cpu`` on several threads (in order) = one thread, also after this process
    ran Numba's parallel kernels."""
    import atlas

    atlas.label(np.linspace(-3, 3, 64)[None, :], np.linspace(-2, 2, 64)[:, None], alpha=0.3,
                omega0=1.0, t_max=50.0)
    points = [(a, 1.0, 0.0) for a in (0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)]
    settings = StudySettings(window=((-math.pi, math.pi), (-3.0, 3.0)))
    order = []
    threaded = compute_points(points, settings, workers=2,
                              on_result=lambda i, _: order.append(i))
    assert order == list(range(len(points)))
    for a, b in zip(compute_points(points, settings, workers=1), threaded):
        _same(a, b)


def test_a_script_without_a_main_guard_runs_two_studies(tmp_path):
    """A study run twice from a plain script (no ``if __name__ == "__main__"``, as in a
    notebook) finishes, with the same numbers: the points' workers never import the
    caller's ``__main__`` again."""
    import subprocess
    import sys

    script = tmp_path / "two_studies.py"
    script.write_text(
        "import math\n"
        "from atlas.stability.study import StudySettings, compute_points\n"
        "points = [(a, 1.0, 0.0) for a in (0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)]\n"
        "s = StudySettings(window=((-math.pi, math.pi), (-3.0, 3.0)))\n"
        "a = compute_points(points, s, workers=2)\n"
        "b = compute_points(points, s, workers=2)\n"
        "print(all((x.fraction == y.fraction).all() for x, y in zip(a, b)))\n")
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == "True"


def test_the_command_on_its_own_local_cluster_writes_the_same_study(tmp_path, monkeypatch):
    """``atlas stability --backend dask`` without a scheduler starts a local cluster of its
    own (and closes it): the study it writes holds the same numbers as on this machine's
    CPU."""
    import distributed

    from atlas.cli import main
    from atlas.store.study import open_study
    from tests.helpers import STUDY_BODY, write_config

    clusters = []

    class Counted(distributed.LocalCluster):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            clusters.append(self)

    monkeypatch.setattr(distributed, "LocalCluster", Counted)
    files = {}
    for backend in ("cpu", "dask"):
        cfg = write_config(tmp_path / f"{backend}.yaml", STUDY_BODY.format(
            torque="{start: 0.0, stop: 0.9, num: 6}", output=tmp_path / f"{backend}.h5"))
        assert main(["stability", str(cfg), "--backend", backend]) == 0
        files[backend] = open_study(tmp_path / f"{backend}.h5")
    assert len(clusters) == 1 and clusters[0].status.name == "closed"
    cpu, dask = files["cpu"], files["dask"]
    assert set(cpu.data_vars) == set(dask.data_vars)
    for name in cpu.data_vars:
        np.testing.assert_array_equal(cpu[name].values, dask[name].values, err_msg=name)
