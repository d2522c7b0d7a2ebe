"""The Dask backend on a shared scheduler: runs never receive each other's tiles, a killed
worker's tiles are computed again with the same result, each task gets its host's share of
cores."""

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import atlas
from tests.helpers import REPO, write_config

pytestmark = pytest.mark.slow  # local Dask clusters

distributed = pytest.importorskip("distributed")

#: one row per tile, 60 tiles: enough to overlap two runs and to kill a worker with many
#: tiles still to do (each tile is a task and a durable write, so not more of them)
CONFIG = """\
pendulum: {{alpha: {alpha}}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 48}}
  theta_dot0: {{start: -4, stop: 4, num: 60}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 48, backend: dask, scheduler: "{scheduler}"}}
output: {output}
"""


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as c, distributed.Client(c) as client:
        yield c, client


def _labels(path):
    ds = atlas.open(path).to_dataset(inherit=False)
    return [ds[n].values for n in ("attractor", "status", "t_trap", "basin_fraction")]


def _assert_same(a, b):
    for x, y in zip(_labels(a), _labels(b)):
        np.testing.assert_array_equal(x, y)


def _local(cfg_path, output):
    """The same config computed here with the CPU backend."""
    cfg = atlas.load_config(cfg_path, output=output)
    atlas.run(cfg, quiet=True, backend="cpu")
    return output


def _config(tmp_path, name, alpha, cluster):
    return write_config(tmp_path / f"{name}.yaml", CONFIG.format(
        alpha=alpha, scheduler=cluster[0].scheduler_address, output=tmp_path / f"{name}.h5"))


def test_two_runs_on_one_scheduler_get_their_own_tiles(tmp_path, cluster):
    """Two runs of different physics at once on one scheduler, same tiling (so the same tile
    indices): each equals its own local run."""
    cfgs = [_config(tmp_path, name, alpha, cluster) for name, alpha in (("a", 0.1), ("b", 0.3))]
    procs = [subprocess.Popen([sys.executable, "-m", "atlas.cli", "run", str(c), "--quiet"],
                              cwd=REPO, stderr=subprocess.PIPE, text=True) for c in cfgs]
    for p in procs:
        assert p.wait(timeout=300) == 0, p.stderr.read()
    for c, name in zip(cfgs, "ab"):
        _assert_same(tmp_path / f"{name}.h5", _local(c, tmp_path / f"{name}0.h5"))


def test_a_worker_killed_mid_run_changes_nothing(tmp_path, cluster):
    cfg = _config(tmp_path, "k", 0.1, cluster)
    proc = subprocess.Popen([sys.executable, "-m", "atlas.cli", "run", "-vv", str(cfg),
                             "--quiet"], cwd=REPO, stderr=subprocess.PIPE, text=True)
    for line in proc.stderr:
        if "tile 10 of 60 written" in line:
            break
    else:
        raise AssertionError("the run ended before writing 10 tiles")
    pids = cluster[1].run(os.getpid)
    os.kill(next(iter(pids.values())), signal.SIGKILL)
    rest = proc.stderr.read()
    assert proc.wait(timeout=300) == 0, rest
    assert rest.count(" written") >= 20  # the kill came with many tiles still to do
    _assert_same(tmp_path / "k.h5", _local(cfg, tmp_path / "k0.h5"))


def test_each_task_gets_its_hosts_share_of_cores(cluster):
    from atlas.kernels.threads import cores
    from atlas.pipeline.distributed import numba_threads_here

    client = cluster[1]
    host = "127.0.0.1"
    assert numba_threads_here({host: 2}) is None  # not on a worker

    def on_each_worker(slots):
        return {client.gather(client.submit(numba_threads_here, slots, pure=False,
                                            workers=[address]))
                for address in client.scheduler_info()["workers"]}

    assert on_each_worker({host: 2}) == {max(1, cores() // 2)}
    # a host the run did not list: the worker's own task slots (1 here) share the cores
    assert on_each_worker({}) == {cores()}
