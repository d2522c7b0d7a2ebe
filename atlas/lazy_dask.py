"""xarray without ``dask.array`` until a dask array exists: 0.3 s off every command's start.

xarray asks, for every array it wraps, whether it is a dask array, and answers by importing
``dask.array`` when dask is installed (``xarray.namedarray.pycompat.array_type("dask")``),
which takes about 0.3 s on the development machine — a tenth of ``atlas run``'s wall time,
a third of ``atlas plot``'s. No object can be a dask array before ``dask.array`` is imported,
so until then the honest answer is "no such type" (and likewise for xarray's check for dask
collections, which imports ``dask.base``, and for the dask scheduler that ``to_netcdf`` asks
about, which imports ``dask`` and ``distributed``: 0.3 s more). :func:`install` puts that
answer into xarray's cache of duck-array modules: the array type is looked up in ``sys.modules`` on
every call, and the real module (version, availability) is imported the first time anything
else is asked. Once dask is imported (``atlas run --backend dask``, ``xr.open_dataset(...,
chunks=...)``) xarray sees the real type, so chunked arrays behave exactly as without this.

Every atlas module that imports xarray imports this one right after it. If a future xarray
moves its cache, :func:`install` does nothing and xarray imports dask as before.
"""

from __future__ import annotations

import sys

__all__ = ["install"]


def install() -> bool:
    """Defer xarray's import of ``dask.array`` (see the module docstring). Idempotent;
    returns whether xarray now defers it."""
    try:
        from xarray.namedarray import pycompat

        cache = pycompat._cached_duck_array_modules
        base = pycompat.DuckArrayModule
    except (ImportError, AttributeError):
        return False
    _defer_collection_check()
    _defer_scheduler_check()
    if "dask" in cache:  # already looked up (real or deferred): nothing to gain or to do
        return isinstance(cache["dask"], _deferred_class(base))
    cache["dask"] = _deferred_class(base)()
    return True


def _defer_collection_check() -> None:
    """xarray's ``is_dask_collection`` imports ``dask.base`` (≈ 0.05 s) to answer for every
    array it wraps; a dask collection is an instance of a dask class, so before ``dask`` is
    imported the answer is no. Wrapped once; the wrapper asks the real function after."""
    try:
        from xarray.namedarray import utils
    except ImportError:
        return
    real = utils.is_dask_collection
    if getattr(real, "deferred_by_atlas", False):
        return

    def is_dask_collection(x) -> bool:
        return "dask" in sys.modules and real(x)

    is_dask_collection.deferred_by_atlas = True
    utils.is_dask_collection = is_dask_collection


def _defer_scheduler_check() -> None:
    """xarray's ``to_netcdf`` asks which dask scheduler is active
    (``xarray.backends.locks.get_dask_scheduler``), importing ``dask`` and ``distributed``
    (≈ 0.3 s) to answer; no scheduler can be active before ``dask`` is imported, so the answer
    is then None. Wrapped once, where xarray defines it and where ``to_netcdf`` calls it."""
    try:
        from xarray.backends import locks, writers
    except ImportError:
        return
    real = locks.get_dask_scheduler
    if getattr(real, "deferred_by_atlas", False):
        return

    def get_dask_scheduler(get=None, collection=None):
        return real(get, collection) if "dask" in sys.modules else None

    get_dask_scheduler.deferred_by_atlas = True
    for module in (locks, writers):
        if getattr(module, "get_dask_scheduler", None) is real:
            module.get_dask_scheduler = get_dask_scheduler


_DEFERRED: dict[type, type] = {}


def _deferred_class(base: type) -> type:
    """The deferred stand-in for xarray's ``DuckArrayModule("dask")`` (one class per base)."""
    if base in _DEFERRED:
        return _DEFERRED[base]

    class DeferredDask(base):
        def __init__(self):  # deliberately not base.__init__, which imports dask.array
            self._real = None

        def _loaded(self):
            if self._real is None:
                self._real = base("dask")
            return self._real

        @property
        def type(self):
            return self._loaded().type if "dask.array" in sys.modules else ()

        @property
        def module(self):
            return self._loaded().module

        @property
        def version(self):
            return self._loaded().version

        @property
        def available(self):
            return self._loaded().available

    _DEFERRED[base] = DeferredDask
    return DeferredDask


install()
