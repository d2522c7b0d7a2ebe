"""Every default of atlas, written once: the essay's Figure 9 problem and the integrator.

The config models (:mod:`atlas.pipeline.config`), the public functions' keyword defaults and the
benchmarks all read these, so a default changes in one place.
"""

import math

import numpy as np

ALPHA = 0.1                                 #: damping constant α [s⁻¹]
OMEGA0 = 1.0                                #: natural angular frequency ω0 [rad s⁻¹]
THETA0_WINDOW = (-3 * math.pi, 3 * math.pi)  #: θ0 range of the grid [rad]
THETA_DOT0_WINDOW = (-4.0, 4.0)             #: θ̇0 range of the grid [rad s⁻¹]
GRID_NUM = 512                              #: points along each grid axis
DT = 0.01                                   #: RK4 step [s]
T_MAX = 200.0                               #: integration limit: unresolved after it [s]
METHOD = "rk4"                              #: the discretisation (one of METHODS)
#: Discretisations the CPU kernels offer (a config's ``integrator.method``; :data:`METHOD`,
#: "rk4", is the CUDA kernels' method too); re-exported as ``atlas.kernels.METHODS``.
METHODS = ("rk4", "rk4-trigfree")
SEPARATRIX_TOL = 1e-12                      #: bisection bracket width of a separatrix point
MAX_SPACING = 0.05                          #: largest vertex spacing of a separatrix polyline
TILE_ORBITS = 1 << 18                       #: orbits per tile of a sweep
#: orbits per tile on the GPU: about 15 waves of an H100/H200 (132 SMs × 2048 threads), so a
#: tile fills the device several times over and its chunks overlap on two streams
TILE_ORBITS_CUDA = 1 << 22
OUTPUT = "outputs/default.h5"               #: output file of a config without `output:`
#: The backend words of configs (``execution.backend``, default the first) and of
#: ``atlas run --backend``, each a device (:data:`atlas.labels.backends.BACKENDS`) and a tile
#: scheduler (:data:`atlas.pipeline.schedule.SCHEDULERS`).
BACKEND_WORDS = {"cpu": ("cpu", "local"), "cuda": ("cuda", "local"), "dask": ("cpu", "dask")}


def problem() -> dict:
    """The default problem as keyword values: α, ω0, dt, t_max (benchmarks, CPU and GPU)."""
    return {"alpha": ALPHA, "omega0": OMEGA0, "dt": DT, "t_max": T_MAX}


def grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(θ0 [rad], θ̇0 [rad s⁻¹]) of the n × n grid over the default window, flattened
    (θ0 fastest)."""
    theta0, theta_dot0 = np.meshgrid(np.linspace(*THETA0_WINDOW, n),
                                     np.linspace(*THETA_DOT0_WINDOW, n))
    return theta0.ravel().copy(), theta_dot0.ravel().copy()
