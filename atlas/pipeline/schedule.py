"""The tile scheduler: which tiles are computed where, and in what order they come back.

A tile (grid rows of one parameter point) is labelled and certified by :func:`compute_tile`,
a plain function of picklable arguments: the point's plan (its model's
:class:`~atlas.models.base.PointPlan`), the grid's columns and the tile's rows. The local
scheduler labels one tile ahead in a background thread while it certifies the previous one
and the caller writes it (:func:`local_results`); the Dask
scheduler (:mod:`atlas.pipeline.distributed`) sends tiles to workers, which for a format that
takes parallel writes (Zarr) write them themselves (:func:`compute_tile_into_store`). Which
device labels a tile (CPU or CUDA kernels) is the ``backend`` argument, independent of the
scheduler.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent import futures
from concurrent.futures import Future
from typing import NamedTuple

import numpy as np

from atlas.defaults import BACKEND_WORDS
from atlas.kernels.threads import concurrent_points
from atlas.labels.backends import Backend
from atlas.labels.backends import lookup as lookup_backend
from atlas.layout import Layout
from atlas.models.base import PointPlan
from atlas.pipeline.config import Config
from atlas.store.partial import TileStore

__all__ = ["Scheduler", "SCHEDULERS", "resolve", "compute_tile", "label_tile", "certify_tile",
           "point_results",
           "tile_args", "local_results", "each_in_background", "waited",
           "compute_tile_into_store", "dask_tile_results"]


def compute_tile(point: PointPlan, x0: np.ndarray, v0: np.ndarray, rows: slice,
                 backend: str = "cpu", numba_threads: int | None = None):
    """Label and certify the orbits of one tile: the grid rows ``rows`` (initial velocities
    ``v0``) × the columns ``x0`` (initial positions) of the parameter point ``point``, on
    ``backend``'s kernels with ``numba_threads`` threads where given.

    Returns ({variable: array shaped (rows, columns)} for every per-orbit variable of the
    file, the tile's tally). A plain function of picklable arguments, so it can run as a Dask
    task on another machine.
    """
    res = label_tile(point, x0, v0, rows, backend, numba_threads)
    return certify_tile(point, rows, res, numba_threads)


def label_tile(point: PointPlan, x0: np.ndarray, v0: np.ndarray, rows: slice,
               backend: str = "cpu", numba_threads: int | None = None):
    """The first half of :func:`compute_tile`: the tile's labels (``point.label``)."""
    return point.label(x0[None, :], v0[:, None], rows, backend, numba_threads)


def certify_tile(point: PointPlan, rows: slice, res, numba_threads: int | None = None):
    """The second half of :func:`compute_tile`: the labels ``res`` of :func:`label_tile`
    certified (``point.certify``), as the tile's arrays and tally."""
    return point.certify(rows, res, numba_threads)


def tile_args(cfg: Config, layout: Layout, points: list, index: int) -> tuple:
    """The arguments of :func:`compute_tile` for tile ``index``: its point's plan, the
    grid's columns, the tile's rows and their slice."""
    _, rows = layout.tile(index)
    return points[index // layout.bands], layout.x0, layout.v0[rows], rows


#: Held by the thread computing (or labelling) a tile ahead: a sweep's tile waits for one that
#: an interrupted sweep left computing, so two tiles are never labelled at once (Numba's
#: workqueue threading layer aborts the process on concurrent parallel launches). A tile's
#: certification overlaps the next tile's labelling only under a thread-safe layer
#: (:func:`local_results`).
_AHEAD = threading.Lock()


#: Seconds between the looks of a waiting thread at its signals (:func:`waited`).
WAKE_S = 0.1


def waited(future: Future):
    """``future.result()``, waited for in slices of :data:`WAKE_S`: a blocked wait wakes for
    a signal only where the kernel delivers it to this thread, and a process-directed SIGINT
    may go to any thread that does not block it (a worker's, Numba's); between the slices
    the interpreter runs the handler that another thread's delivery only flagged, so that
    Ctrl-C and SIGTERM take effect whichever thread received them."""
    while True:
        try:
            return future.result(timeout=WAKE_S)
        except futures.TimeoutError:  # the builtin from Python 3.11, its own class before
            continue


def _in_background(fn, *args, lock=_AHEAD, **kwargs) -> Future:
    """``fn(*args, **kwargs)`` started in a daemon thread, holding ``lock`` (None: none); its
    result, or whatever it raised (Ctrl-C included), comes back through the Future. A daemon
    rather than a ThreadPoolExecutor worker: those are joined at interpreter exit, so a run
    stopped by Ctrl-C or SIGTERM would wait for its tile in flight before the process could
    end."""
    future = Future()

    def work():
        with lock if lock is not None else contextlib.nullcontext():
            try:
                future.set_result(fn(*args, **kwargs))
            except BaseException as exc:  # re-raised in the caller by future.result()
                future.set_exception(exc)

    threading.Thread(target=work, name="atlas-background", daemon=True).start()
    return future


def each_in_background(fn: Callable, items: Iterable, workers: int) -> Iterator:
    """``fn(item)`` of each of ``items``, in order, computed ``workers`` at a time in daemon
    threads: a ThreadPoolExecutor's ``map``, except that Ctrl-C and SIGTERM, which come to
    this thread while it waits, leave at once. A pool's ``with`` block waits for the calls in
    flight (a parameter point's separatrices, or the kernels' first compilation: half a
    minute and more on a busy machine) and the interpreter joins its threads at exit; here
    the calls in flight are abandoned, their results dropped. As in a pool, a call starts as
    soon as a worker is free, whatever results this thread has yet to take (waiting for the
    results in order before starting the next call left a worker idle behind a slow point:
    a 1,001-torque study ran 6 % longer), by ``workers`` threads that take the calls in
    turn. A call that raises re-raises here, in its turn; once this generator is closed no
    further call starts."""
    jobs = [(item, Future()) for item in items]
    pending, taking, stop = iter(jobs), threading.Lock(), threading.Event()

    def work():  # one of ``workers`` threads, reused: a thread per call would start Numba's
        while not stop.is_set():  # threading layer's own team anew each time (~1 ms a call)
            with taking:
                item, future = next(pending, (None, None))
            if future is None:
                return
            try:
                future.set_result(fn(item))
            except BaseException as exc:  # re-raised in the caller by future.result()
                future.set_exception(exc)

    for _ in range(min(max(workers, 1), len(jobs))):
        threading.Thread(target=work, name="atlas-background", daemon=True).start()
    try:
        for _, future in jobs:
            yield waited(future)
    finally:
        stop.set()


def local_results(cfg, tiles: TileStore, points, todo, device: str
                  ) -> Iterator[tuple[int, tuple]]:
    """(index, (arrays, tally)) of the tiles ``todo`` in order, each labelled one tile ahead
    in a background thread: tile i+1 is labelled while tile i is certified, in a second
    background thread, and the caller writes it (the Numba kernels run without the GIL, and
    so do zlib and fsync in the write; the certificate's serial parts would otherwise leave a
    core idle). This thread only waits for the tiles and yields them, as without the
    overlap: Ctrl-C and SIGTERM come while it waits. Where Numba's threading layer cannot
    run two parallel kernels at once (``workqueue``,
    :func:`atlas.kernels.threads.threadsafe_layer`), the background thread labels and
    certifies tile i+1 while the caller writes tile i. At most one tile is ahead: memory
    holds two tiles' arrays. A tile whose computation failed raises its own exception here,
    after every tile before it has been yielded; a tile still computing when the caller stops
    (a failed write, Ctrl-C, SIGTERM, or the certification of the tile before it failing) is
    abandoned, its result dropped. The arrays do not depend on which way: each tile is
    labelled, then certified, on its own."""
    import numba

    from atlas.kernels.threads import threadsafe_layer

    threads = numba.get_num_threads()  # the caller's setting: Numba's is per thread
    layout = tiles.layout
    staged = threadsafe_layer()

    def start(index):
        return _in_background(label_tile if staged else compute_tile,
                              *tile_args(cfg, layout, points, index), backend=device,
                              numba_threads=threads)

    ahead = start(todo[0]) if len(todo) else None
    for position, index in enumerate(todo):
        result = waited(ahead)
        if position + 1 < len(todo):
            ahead = start(todo[position + 1])
        if staged:
            point, _, _, rows = tile_args(cfg, layout, points, index)
            result = waited(_in_background(certify_tile, point, rows, result, lock=None,
                                           numba_threads=threads))
        yield index, result


def compute_tile_into_store(tile_run, folder, layout, index, *args, numba_threads=None
                            ) -> dict:
    """Label and certify tile ``index`` and write it with the output format's ``tile_run``
    into the partial run at ``folder`` (on the Dask worker itself: a format with
    ``parallel_tile_writes``, Zarr); return its tally for the client's record."""
    values, tally = compute_tile(*args, numba_threads=numba_threads)
    tile_run.write_tile(folder, layout, index, values)
    return tally


def dask_tile_results(cfg, tiles: TileStore, points, todo, device: str = "cpu"
                      ) -> Iterator[tuple[int, tuple]]:
    """(index, (arrays, tally)), or for a format that takes parallel writes (Zarr)
    (index, tally) of a tile the worker has written itself. The workers run the CPU kernels
    (``device`` "cpu": the only device of the Dask scheduler)."""
    from atlas.pipeline.distributed import dask_results

    layout = tiles.layout
    if tiles.tile_run.parallel_tile_writes:
        def args_of(i):
            return (tiles.tile_run, tiles.path, layout, i,
                    *tile_args(cfg, layout, points, i))

        task = compute_tile_into_store
    else:
        def args_of(i):
            return tile_args(cfg, layout, points, i)

        task = compute_tile
    yield from dask_results(cfg, todo, args_of, task, tiles.manifest["attrs"]["run_identity"])


def point_results(task: Callable, points: list[tuple], *, backend: str = "cpu",
                  scheduler: str | None = None, workers: int | None = None,
                  per_thread: int = 4) -> Iterator[tuple[int, object]]:
    """(i, ``task(*points[i], numba_threads=…)``) of every parameter point: on this machine
    (``backend`` "cpu": in their order, by up to ``workers`` threads where there are at
    least ``per_thread`` points per thread, else here; threads, not processes: the compiled
    kernels release the GIL, and a process pool would fork Numba's running OpenMP pool or
    import the caller's ``__main__`` again) or as Dask tasks, one per point ("dask": on
    ``scheduler`` if given, else a local cluster of ``workers`` processes; in the order
    they finish). Each point is computed alone, so its result does not depend on where.
    Ctrl-C leaves the threads' points in flight (:func:`each_in_background`)."""
    if backend == "dask":
        from atlas.pipeline.distributed import dask_map

        yield from dask_map(scheduler, workers, task, lambda i: points[i], range(len(points)),
                            "atlas-points")
        return
    n = concurrent_points(len(points) // per_thread, most=workers or 1)
    if n < 2:
        yield from ((i, task(*point)) for i, point in enumerate(points))
        return
    yield from enumerate(each_in_background(lambda point: task(*point), points, n))


class Scheduler(NamedTuple):
    """A way to run a sweep's tiles: ``results(cfg, tiles, points, todo, device)`` yields
    (index, (arrays, tally)) for the caller to write, or (index, tally) for a tile that its
    worker wrote itself, which is the case where ``worker_writes(tiles)``."""

    results: Callable[..., Iterator[tuple[int, tuple]]]
    worker_writes: Callable[[TileStore], bool]


#: Every tile scheduler by name: this process, one tile ahead; or a Dask cluster.
SCHEDULERS: dict[str, Scheduler] = {
    "local": Scheduler(local_results, lambda tiles: False),
    "dask": Scheduler(dask_tile_results, lambda tiles: tiles.tile_run.parallel_tile_writes),
}


def resolve(word: str) -> tuple[Backend, Scheduler]:
    """(device, scheduler) of a config's or the command line's backend word
    (:data:`atlas.defaults.BACKEND_WORDS`): "cpu" and "cuda" run their device's
    kernels here, "dask" the CPU kernels on a Dask cluster. ValueError (one line) for
    another word."""
    try:
        device, scheduler = BACKEND_WORDS[word]
    except (KeyError, TypeError):
        raise ValueError(f"backend must be one of {tuple(BACKEND_WORDS)}, got {word!r}"
                         ) from None
    return lookup_backend(device), SCHEDULERS[scheduler]
