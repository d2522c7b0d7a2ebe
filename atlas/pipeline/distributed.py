"""The Dask scheduler: tiles as tasks on a dask.distributed cluster.

Workers compute tiles (:func:`atlas.pipeline.schedule.compute_tile`); for HDF5 they send the
arrays back and the client writes each as it arrives (no parallel driver needed), for Zarr
they write their tile into the store themselves and send its tally; either way the crash
and resume guarantees are those of the local scheduler. At most ``2 × workers`` tiles are in
flight. ``execution.scheduler`` names an existing scheduler (``tcp://host:8786``), otherwise a
LocalCluster of ``execution.workers`` processes starts. A task runs Numba with (its host's
cores) ÷ (the task slots on that host) threads (:func:`numba_threads_here`). Task keys
``atlas-tile-<run identity>-<run token>-<tile>`` are unique per run, so runs sharing a
scheduler never receive each other's tiles; a tile lost with a dead worker is computed again
elsewhere with the same result (a tile depends only on its inputs).
"""

from __future__ import annotations

import logging
import os
import secrets
from collections.abc import Callable, Iterator
from urllib.parse import urlparse

from atlas.errors import BackendUnavailable
from atlas.kernels.threads import cores

log = logging.getLogger(__name__)


def client_for(scheduler: str | None, workers: int | None):
    """(a Dask client, the LocalCluster it started or None): on ``scheduler``'s address where
    given, else on a new local cluster of ``workers`` processes (default: up to 4, one per
    core). BackendUnavailable in one line without dask.distributed or a scheduler to reach."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise BackendUnavailable("backend 'dask': dask.distributed is not installed; "
                                 "pip install 'pendulum-atlas[dask]'") from None
    if scheduler:
        try:
            return Client(scheduler, timeout="10s"), None
        except (OSError, TimeoutError) as exc:
            raise BackendUnavailable(f"backend 'dask': cannot reach the scheduler at "
                                     f"{scheduler} ({exc.__class__.__name__})") from None
    if not log.isEnabledFor(logging.INFO):  # dask's own INFO chatter only with --verbose
        for name in ("distributed", "dask"):
            logging.getLogger(name).setLevel(logging.WARNING)
    n = workers or max(1, min(4, os.cpu_count() or 1))
    # the dashboard on a free port (None still binds its server to 8787, and warns where
    # another cluster holds it); its address with --verbose
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    log.info("local Dask cluster of %d workers, dashboard %s", n, cluster.dashboard_link)
    return Client(cluster), cluster


def _host(address: str) -> str:
    return urlparse(address).hostname or address


def numba_threads_here(slots_by_host: dict[str, int]) -> int | None:
    """Numba threads for a task on this Dask worker: this host's cores shared among the task
    slots (``nthreads``) of every worker on the host, as the scheduler listed them when the
    run started (a worker that joined later counts its own slots). None outside a worker."""
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        return None
    slots = slots_by_host.get(_host(worker.address)) or worker.state.nthreads
    return max(1, cores() // max(1, slots))


def dask_map(scheduler: str | None, workers: int | None, task: Callable, args_of: Callable,
             todo, prefix: str) -> Iterator[tuple[int, object]]:
    """Yield (index, ``task(*args_of(index), numba_threads=…)``) for every index of ``todo``
    as the tasks finish on the cluster (:func:`client_for`), at most 2 × workers in flight,
    each with its host's share of the cores as Numba threads (:func:`numba_threads_here`).
    Task keys ``<prefix>-<token>-<index>`` are unique per call."""
    from distributed import as_completed

    client, cluster = client_for(scheduler, workers)
    try:
        info = client.scheduler_info(n_workers=-1)["workers"]
        n_workers = max(1, len(info))
        slots_by_host: dict[str, int] = {}
        for address, worker in info.items():
            host = _host(address)
            slots_by_host[host] = slots_by_host.get(host, 0) + int(worker["nthreads"])
        prefix = f"{prefix}-{secrets.token_hex(6)}"
        log.info("dask: %d workers, task slots per host %s", n_workers, slots_by_host)
        pending = iter(todo)
        window = as_completed()

        def submit(count: int) -> None:
            for index in (next(pending, None) for _ in range(count)):
                if index is None:
                    return
                future = client.submit(_task, task, slots_by_host, *args_of(int(index)),
                                       key=f"{prefix}-{index}", pure=False)
                future.task_index = int(index)
                window.add(future)

        submit(2 * n_workers)
        for future in window:
            yield future.task_index, future.result()
            future.release()
            del future
            submit(1)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def dask_results(cfg, todo, args_of: Callable[[int], tuple], compute_tile, run_identity: str,
                 ) -> Iterator[tuple[int, tuple]]:
    """Yield (tile index, what ``compute_tile`` returned: (arrays, tally), or a tally for a
    tile its worker wrote) as tiles finish on the cluster (:func:`dask_map`, keys
    ``atlas-tile-<run identity>-<token>-<tile>``)."""
    yield from dask_map(cfg.execution.scheduler, cfg.execution.workers, compute_tile, args_of,
                        todo, f"atlas-tile-{run_identity}")


def _task(function, slots_by_host, *args):
    """One task on a worker, with the worker's share of its host's cores."""
    return function(*args, numba_threads=numba_threads_here(slots_by_host))
