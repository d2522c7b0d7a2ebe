"""The devices that label orbits, as data: the one place "which backend?" is answered.

A :class:`Backend` (cpu, cuda) knows whether it can run here (one line why not), its default
tile size, the methods (:mod:`atlas.labels.methods`) it has kernels for and which kernel
labels a tile; every kernel follows the contract of :mod:`atlas.kernels`, so they are
interchangeable. The device is kept apart from the tile *scheduler* (local threads or Dask,
:mod:`atlas.pipeline.schedule`), which also says which device a config's backend word means.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

from atlas import defaults
from atlas.labels.methods import METHODS, load
from atlas.labels.methods import lookup as lookup_method

__all__ = ["Backend", "BACKENDS", "KERNELS", "lookup", "resolve_method"]

#: The kernel variants every backend offers: None (its fast kernel) and "straightforward"
#: (the plain one-orbit-per-thread kernel, libm sin, that the fast one is checked against).
KERNELS = (None, "straightforward")


@dataclass(frozen=True)
class Backend:
    """A device that labels orbits.

    name:        "cpu" or "cuda" (also the file's and the run identity's kernel class).
    summary:     one line saying what runs.
    tile_orbits: orbits per tile of a sweep by default (:data:`atlas.defaults.TILE_ORBITS`,
                 ``TILE_ORBITS_CUDA``).
    methods:     the methods (:data:`atlas.defaults.METHODS`) it has kernels for.
    kernels:     ``"module:function"`` of its own kernel (it takes ``variant="fast"`` or
                 ``"straightforward"``), or None: each method's CPU kernels
                 (:meth:`atlas.labels.methods.Method.kernel`).
    status:      ``"module:function"`` returning (usable?, device name or one line why not),
                 never raising; None: always usable.
    requires:    ``"module:function"`` raising :class:`~atlas.errors.BackendUnavailable`
                 (one line, with what to install) where it is not usable; None: nothing.
    """

    name: str
    summary: str
    tile_orbits: int
    methods: tuple[str, ...]
    kernels: str | None = None
    status: str | None = None
    requires: str | None = None

    def __post_init__(self) -> None:
        for m in self.methods:
            lookup_method(m)  # a name that is no method fails here, not in a run

    def available(self) -> tuple[bool, str]:
        """(usable here?, the device, or one line saying why not). Never raises."""
        return (True, self.summary) if self.status is None else load(self.status)()

    def require(self) -> None:
        """Raise :class:`~atlas.errors.BackendUnavailable` (one line) unless usable here."""
        if self.requires is not None:
            load(self.requires)()

    @property
    def default_method(self) -> str:
        """The method it runs unless told: :data:`atlas.defaults.METHOD` if it has kernels for
        it, else its first."""
        return defaults.METHOD if defaults.METHOD in self.methods else self.methods[0]

    def check_method(self, method: str) -> None:
        """ValueError (one line) unless ``method`` is a method it has kernels for."""
        lookup_method(method)
        if method not in self.methods:
            runs = ", ".join(repr(m) for m in self.methods)
            raise ValueError(f"method: {method!r} has no {self.name.upper()} kernel; the "
                             f"{self.name} backend runs {runs} (set method: "
                             f"{self.methods[0]}, or run on the CPU)")

    def kernel(self, method: str, kernel: str | None = None) -> Callable:
        """The function that labels a tile with ``method``: the contract of
        :mod:`atlas.kernels`, its fast kernel or (``kernel="straightforward"``) its plain
        one. ValueError (one line) for a method it does not run or an unknown kernel."""
        _check_kernel(kernel)
        self.check_method(method)
        if self.kernels is None:
            return lookup_method(method).kernel(straightforward=kernel == "straightforward")
        return functools.partial(load(self.kernels), variant=kernel or "fast")


def _check_kernel(kernel) -> None:
    if kernel not in KERNELS:
        raise ValueError(f"kernel must be one of {KERNELS}, got {kernel!r}")


#: Every backend by name.
BACKENDS: dict[str, Backend] = {b.name: b for b in (
    Backend(name="cpu", summary="Numba kernels on this machine's CPU cores",
            tile_orbits=defaults.TILE_ORBITS, methods=defaults.METHODS),
    Backend(name="cuda", summary="Numba CUDA kernels on an NVIDIA GPU",
            tile_orbits=defaults.TILE_ORBITS_CUDA,
            methods=tuple(m.name for m in METHODS.values() if m.cuda),
            kernels="atlas.kernels.cuda_host:label_cuda",
            status="atlas.kernels.cuda:cuda_status", requires="atlas.kernels.cuda:require_cuda"),
)}

def lookup(name: str) -> Backend:
    """The :class:`Backend` called ``name`` ("cpu", "cuda"); ValueError (one line) otherwise."""
    try:
        return BACKENDS[name]
    except (KeyError, TypeError):
        raise ValueError(f"backend must be one of {tuple(BACKENDS)}, got {name!r}") from None


def resolve_method(backend: str, kernel: str | None, method: str | None) -> str:
    """The method :func:`atlas.label` runs for its arguments ``backend``, ``kernel`` and
    ``method``: ``method``, or the backend's :attr:`~Backend.default_method` when None.
    ValueError (one line) for an unknown backend, kernel or method, or a method the backend
    has no kernel for."""
    device = lookup(backend)
    _check_kernel(kernel)
    method = device.default_method if method is None else method
    device.check_method(method)
    return method
