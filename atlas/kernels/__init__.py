"""Numba kernels: numerical code only (no I/O, no config objects).

Every labelling kernel follows one contract, so backends are interchangeable:

    kernel(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
           attractor, status, n_trap) -> None

* ``theta0``, ``theta_dot0``: float64 1-D arrays of equal length N [rad, rad s⁻¹].
* each orbit is integrated with classical RK4 at step ``dt`` [s]; at steps
  n = 0, c, 2c, …, n_checks·c (c = ``check_every``) the energy trap is tested:
  k = round(θ / 2π), φ = θ − 2πk ∈ [−π, π], E_k = ½θ̇² + 2ω0² sin²(φ/2);
  the orbit is *trapped* in well k when E_k < ``energy_cap`` (= 2ω0²(1 − m), see
  :mod:`atlas.labels`) and integration of that orbit stops.
* outputs (preallocated, length N): ``attractor`` int32 (k, untouched unless trapped),
  ``status`` int8 (0 trapped, 1 unresolved, 2 nonfinite), ``n_trap`` int32 (the step
  count n at trapping, −1 otherwise).

Checks before any step and after a non-finite state are part of the contract: an initial
condition already inside a trap has n_trap = 0, and a NaN/inf state is reported at the
first check that sees it.
"""

TRAPPED, UNRESOLVED, NONFINITE = 0, 1, 2
#: Status set after labelling (never by a kernel): trapped, but not certified for the exact
#: equation (closer than d_cert to a basin boundary; see :mod:`atlas.certificate`).
NEAR_BOUNDARY = 3
