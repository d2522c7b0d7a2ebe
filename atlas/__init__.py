"""atlas: a Numba-accelerated phase-space atlas of the damped pendulum θ̈ = −ω0² sin θ − 2αθ̇ + τ.

    import atlas
    res = atlas.label(theta0, theta_dot0, alpha=0.1, omega0=1.0)   # labels of the RK4 map
    cfg = atlas.load_config("configs/default.yaml")
    tree = atlas.run(cfg)                                           # also written to disk
    tree = atlas.basins(cfg)                                        # in memory, written nowhere
    tree = atlas.open("outputs/default.h5")
    atlas.layout.points(tree.to_dataset())                          # submodules load on use

The file-level API (config, run, basins, open) and the submodules (``atlas.layout``,
``atlas.store``, …) load on first use (PEP 562 module ``__getattr__``), so that ``import
atlas`` for labelling alone starts fast: it imports numpy and the labelling front, not
Numba, xarray, scipy or pydantic. The version, written once in :mod:`atlas._version`, is
:data:`__version__` (what ``atlas --version`` prints and every file's ``atlas_version``).
"""

import sys as _sys

from atlas._version import __version__
from atlas.errors import AtlasError, BackendUnavailable, ConfigError, InputFileError
from atlas.labels.labelling import LabelResult, label
from atlas.physics import linear
from atlas.physics.pendulum import Pendulum, critical_points

# The closed forms live in atlas.physics.linear; ``atlas.linear`` is their public name, also
# for ``import atlas.linear`` and ``from atlas.linear import solve``.
_sys.modules.setdefault(__name__ + ".linear", linear)

__all__ = ["label", "linear", "LabelResult", "load_config", "Config", "run", "basins", "open",
           "Pendulum", "critical_points", "AtlasError", "ConfigError", "InputFileError",
           "BackendUnavailable", "__version__"]

#: The public names loaded on first use: name → (module, attribute).
_LAZY = {"load_config": ("atlas.pipeline.config", "load_config"),
         "Config": ("atlas.pipeline.config", "Config"),
         "run": ("atlas.pipeline.memory", "run"),
         "basins": ("atlas.pipeline.memory", "basins"),
         "open": ("atlas.store.reader", "open_atlas")}


def _submodules() -> set[str]:
    """The public submodules and subpackages of atlas (``atlas.layout``, ``atlas.store``, …)."""
    from pkgutil import iter_modules

    return {m.name for m in iter_modules(__path__) if not m.name.startswith("_")}


def __getattr__(name: str):
    from importlib import import_module

    if name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(import_module(module), attr)
    elif not name.startswith("_") and name in _submodules():
        value = import_module(f"{__name__}.{name}")  # also sets the attribute
    else:
        raise AttributeError(f"module 'atlas' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | _submodules())
