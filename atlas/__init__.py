"""atlas: a Numba-accelerated phase-space atlas of the damped pendulum θ̈ = −ω0² sin θ − 2αθ̇ + τ.

    import atlas
    res = atlas.label(theta0, theta_dot0, alpha=0.1, omega0=1.0)   # certified labels
    cfg = atlas.load_config("configs/default.yaml")
    tree = atlas.run(cfg)                                           # also written to disk
    tree = atlas.open("outputs/default.h5")

The file-level API (config, run, open) loads xarray/pydantic on first use, so that
``import atlas`` for labelling alone starts fast.
"""

import sys as _sys

from atlas.errors import AtlasError, BackendUnavailable, ConfigError, InputFileError
from atlas.labels.labelling import LabelResult, label
from atlas.physics import linear
from atlas.physics.pendulum import Pendulum, critical_points

# The closed forms live in atlas.physics.linear; ``atlas.linear`` is their public name, also
# for ``import atlas.linear`` and ``from atlas.linear import solve``.
_sys.modules.setdefault(__name__ + ".linear", linear)

__version__ = "0.1.0"
__all__ = ["label", "linear", "LabelResult", "load_config", "Config", "run", "open",
           "Pendulum", "critical_points", "AtlasError", "ConfigError", "InputFileError",
           "BackendUnavailable", "__version__"]

_LAZY = {"load_config": ("atlas.pipeline.config", "load_config"),
         "Config": ("atlas.pipeline.config", "Config"),
         "run": ("atlas.pipeline.sweep", "run"), "open": ("atlas.store.reader", "open_atlas")}


def __getattr__(name: str):
    if name in _LAZY:
        from importlib import import_module

        module, attr = _LAZY[name]
        value = getattr(import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'atlas' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
