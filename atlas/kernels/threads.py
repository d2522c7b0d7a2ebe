"""How many parameter points may run their compiled kernels at once, from Python threads,
and with how many of Numba's threads each; the cores this process may use.

Independent parameter points (their exact boundaries, separatrices, study values) are
computed two at a time on threads: the compiled code releases the GIL, so the points'
serial parts overlap. Numba's parallel kernels may be called from several threads at once
only under a thread-safe threading layer (OpenMP or TBB); its ``workqueue`` layer, the one
left where neither library is installed, aborts the process on a concurrent call (Numba
documentation, "The Threading Layers"). :func:`concurrent_points` gives 1 there. The
results never depend on it: each point is computed alone.
"""

from __future__ import annotations

__all__ = ["concurrent_points", "threadsafe_layer", "cores", "use_threads"]


def cores() -> int:
    """The cores this process may run on (its CPU affinity on Linux, else every core)."""
    import os

    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def use_threads(numba_threads: int | None) -> None:
    """Numba's thread count for this thread's parallel kernels (a per-thread setting):
    ``numba_threads`` where given (at most Numba's pool), else left as it is."""
    if numba_threads is not None:
        import numba

        numba.set_num_threads(min(numba_threads, numba.config.NUMBA_NUM_THREADS))


def threadsafe_layer() -> bool:
    """Whether Numba's threading layer, as it will be chosen, allows concurrent calls of
    parallel kernels from several threads (OpenMP or TBB, not ``workqueue``)."""
    import numba

    wanted = str(numba.config.THREADING_LAYER).lower()
    # the layers Numba may pick for each setting that are thread-safe (GNU OpenMP, the one
    # built here, is not fork-safe, so "forksafe" may only mean TBB)
    safe = {"default": ("tbbpool", "omppool"), "safe": ("tbbpool",),
            "threadsafe": ("tbbpool", "omppool"), "forksafe": ("tbbpool",),
            "tbb": ("tbbpool",), "omp": ("omppool",)}.get(wanted, ())
    for module in safe:
        try:
            __import__(f"numba.np.ufunc.{module}")
        except ImportError:
            continue
        return True
    return False


def concurrent_points(n_points: int, most: int = 2) -> int:
    """The number of threads for ``n_points`` independent parameter points: up to ``most``,
    and 1 where the threading layer is not thread-safe (:func:`threadsafe_layer`)."""
    if n_points < 2 or not threadsafe_layer():
        return 1
    return min(most, n_points)
