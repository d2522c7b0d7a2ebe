"""The peer's side of :mod:`tools.peer_driven`: pynamicalsys's basins of attraction of the
driven pendulum θ̈ + 2αθ̇ + ω0² sin θ = A cos(Ω t), run by the peer's own interpreter (this
file imports only pynamicalsys and numpy, never atlas).

M. Rolim Sales et al., "pynamicalsys: A Python toolkit for the analysis of dynamical
systems", Chaos, Solitons and Fractals 201, 117269 (2025).

``ContinuousDynamicalSystem.basin_of_attraction(map_type="SM")`` integrates each initial
condition for ``transient_time``, records ``num_intersections`` returns of the stroboscopic
map (sampling time one drive period T = 2π/Ω) and clusters the returns' centroids with
DBSCAN (``eps``, ``min_samples``): one cluster, one basin. The centroid of θ is meaningless
for a rotating orbit (θ grows by 2π w per return, and its lift depends on the initial
condition), so the pendulum is handed to it on its cylinder, as the state
u = (cos θ, sin θ, θ̇): u̇ = (−θ̇ sin θ, θ̇ cos θ, −2αθ̇ − ω0² sin θ + A cos Ω t), the same
flow. Each cluster's attractor is then read from the final state on P of a few of its
members (the peer's ``stroboscopic_map``), which :mod:`tools.peer_driven` matches to atlas's
attractors.

Reads one JSON job on stdin ({"theta0": [...], "theta_dot0": [...], "alpha", "omega0",
"amplitude", "frequency", "steps_per_period", "transient_periods", "samples", "eps",
"repeats", "members"}) and writes one JSON result on stdout: the labels, the seconds (wall
and CPU, all threads) of the first (cold: Numba's compilation included) and of each later
(warm) call, and per cluster the final states of its members.
"""

import json
import math
import sys
import time

import numpy as np
from numba import njit
from pynamicalsys import ContinuousDynamicalSystem


@njit
def pendulum_on_cylinder(time, u, parameters):
    """u̇ [s⁻¹] of u = (cos θ, sin θ, θ̇ [rad s⁻¹]) at time [s]; parameters (α [s⁻¹],
    ω0 [rad s⁻¹], A [rad s⁻²], Ω [rad s⁻¹]). sin θ is read as u1/|(u0, u1)|, so that
    RK4's drift off the unit circle does not change the force."""
    alpha, omega0, amplitude, frequency = parameters
    radius = math.sqrt(u[0] * u[0] + u[1] * u[1])
    dudt = np.empty_like(u)
    dudt[0] = -u[1] * u[2]
    dudt[1] = u[0] * u[2]
    dudt[2] = (-2.0 * alpha * u[2] - omega0 * omega0 * u[1] / radius
               + amplitude * math.cos(frequency * time))
    return dudt


def main() -> None:
    job = json.load(sys.stdin)
    theta0 = np.asarray(job["theta0"], np.float64)
    theta_dot0 = np.asarray(job["theta_dot0"], np.float64)
    u = np.column_stack([np.cos(theta0), np.sin(theta0), theta_dot0])
    period = 2.0 * math.pi / job["frequency"]
    ds = ContinuousDynamicalSystem(
        equations_of_motion=pendulum_on_cylinder, system_dimension=3,
        parameters=[job["alpha"], job["omega0"], job["amplitude"], job["frequency"]])
    ds.integrator("rk4", time_step=period / job["steps_per_period"])
    transient = job["transient_periods"] * period
    seconds, cpu_seconds = [], []
    for _ in range(job["repeats"]):
        start, cpu_start = time.perf_counter(), time.process_time()
        labels = ds.basin_of_attraction(u, job["samples"], transient_time=transient,
                                        map_type="SM", sampling_time=period,
                                        eps=job["eps"], min_samples=job["min_samples"])
        seconds.append(time.perf_counter() - start)
        cpu_seconds.append(time.process_time() - cpu_start)
    # Each cluster's members (the first `members` in a fixed random order) followed to P.
    rng = np.random.default_rng(0)
    clusters = {}
    for label in np.unique(labels[labels >= 0]):
        where = np.flatnonzero(labels == label)
        chosen = rng.permutation(where)[:job["members"]]
        strobe = ds.stroboscopic_map(u[chosen], job["samples"], sampling_time=period,
                                     transient_time=transient)
        last = strobe[:, -1, 1:]  # (members, 3): the last return of each
        clusters[int(label)] = {
            "size": int(where.size), "members": chosen.tolist(),
            "theta": np.arctan2(last[:, 1], last[:, 0]).tolist(),
            "theta_dot": last[:, 2].tolist()}
    json.dump({"labels": labels.tolist(), "seconds": seconds, "cpu_seconds": cpu_seconds,
               "clusters": clusters},
              sys.stdout)


if __name__ == "__main__":
    main()
