"""The Dask backend: tiles as tasks on a dask.distributed cluster, one writer on the client.

Workers compute tiles (:func:`atlas.sweep.compute_tile`) and send the label arrays back; the
client writes each as it arrives, so HDF5 needs no parallel driver and the file's crash and
resume guarantees are those of the local backend. At most ``2 × workers`` tiles are in
flight, which bounds the client's memory by a few tiles.

``execution.scheduler`` names an existing scheduler (``tcp://host:8786``, started with
``dask scheduler`` and ``dask worker`` on other hosts, or by dask-jobqueue on a batch
system); otherwise a LocalCluster of ``execution.workers`` processes is started. Each worker
runs Numba with ``cores // workers`` threads so the workers of one machine do not
oversubscribe its cores.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterator

from .errors import BackendUnavailable

log = logging.getLogger(__name__)


def _client(scheduler: str | None, workers: int | None):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise BackendUnavailable("backend 'dask': dask.distributed is not installed; "
                                 "pip install 'atlas[dask]'") from None
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
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster), cluster


def dask_results(cfg, todo, args_of: Callable[[int], tuple], compute_tile,
                 ) -> Iterator[tuple[int, tuple]]:
    """Yield (tile index, (attractor, status, t_trap)) as tiles finish on the cluster."""
    from distributed import as_completed

    client, cluster = _client(cfg.execution.scheduler, cfg.execution.workers)
    try:
        info = client.scheduler_info()["workers"].values()
        n_workers = max(1, len(info))
        threads = max(1, (os.cpu_count() or 1) // n_workers) if cluster is not None else None
        log.info("dask: %d workers, %s numba threads each", n_workers, threads or "default")
        pending = iter(todo)
        window = as_completed()

        def submit(count: int) -> None:
            for index in (next(pending, None) for _ in range(count)):
                if index is None:
                    return
                future = client.submit(compute_tile, *args_of(int(index)),
                                       numba_threads=threads, key=f"atlas-tile-{index}",
                                       pure=False)
                future.tile_index = int(index)
                window.add(future)

        submit(2 * n_workers)
        for future in window:
            yield future.tile_index, future.result()
            del future
            submit(1)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
