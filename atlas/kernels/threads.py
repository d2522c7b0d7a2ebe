"""How many parameter points may run their compiled kernels at once, from Python threads.

Independent parameter points (their exact boundaries, separatrices, study values) are
computed two at a time on threads: the compiled code releases the GIL, so the points'
serial parts overlap. Numba's parallel kernels may be called from several threads at once
only under a thread-safe threading layer (OpenMP or TBB); its ``workqueue`` layer, the one
left where neither library is installed, aborts the process on a concurrent call (Numba
documentation, "The Threading Layers"). :func:`concurrent_points` gives 1 there. The
results never depend on it: each point is computed alone.
"""

from __future__ import annotations

__all__ = ["concurrent_points", "threadsafe_layer"]


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
