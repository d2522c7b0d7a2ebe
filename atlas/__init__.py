"""atlas: a Numba-accelerated phase-space atlas of the damped pendulum θ̈ = −ω0² sin θ − 2αθ̇."""

from .labels import LabelResult, label
from .model import Pendulum, critical_points

__version__ = "0.1.0"
__all__ = ["label", "LabelResult", "Pendulum", "critical_points", "__version__"]
