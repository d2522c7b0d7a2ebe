"""atlas: a Numba-accelerated phase-space atlas of the damped pendulum θ̈ = −ω0² sin θ − 2αθ̇.

    import atlas
    res = atlas.label(theta0, theta_dot0, alpha=0.1, omega0=1.0)   # certified labels
    cfg = atlas.load_config("configs/default.yaml")
    tree = atlas.run(cfg)                                           # also written to disk
    tree = atlas.open("outputs/default.h5")
"""

from . import linear
from .config import Config, load_config
from .errors import AtlasError, BackendUnavailable, ConfigError, InputFileError
from .labels import LabelResult, label
from .model import Pendulum, critical_points
from .store import open_atlas as open
from .sweep import run

__version__ = "0.1.0"
__all__ = ["label", "linear", "LabelResult", "load_config", "Config", "run", "open", "Pendulum",
           "critical_points", "AtlasError", "ConfigError", "InputFileError",
           "BackendUnavailable", "__version__"]
