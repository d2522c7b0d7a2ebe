"""Classical RK4 for eq. (1) and the straightforward labelling kernel (one orbit per thread).

The RK4 step and the trap test are built by factories that close over a ``sin``
implementation, so the straightforward kernel (``math.sin``) and the lane-blocked kernel
(polynomial sin, :mod:`atlas.kernels.lanes`) share one definition of the method.

With a torque τ the step (the τ = 0 step's source in its τ ≠ 0 form, ``make_rk4_step_torque``),
the tilted trap and the running certificate (``make_well_energy_torque``,
``make_running_test``) are separate specialisations, so that the τ = 0 code stays that of
earlier versions; :func:`label_straightforward` dispatches.

Reference: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.1 (classical 4th-order
Runge–Kutta, local error O(dt⁵), global error O(dt⁴)).
"""

from __future__ import annotations

import linecache
import math

import numba as nb
import numpy as np

import atlas.kernels.vector_width  # noqa: F401 (before any njit: 512-bit vectors)
from atlas.kernels import (
    NONFINITE,
    RUNNING,
    TRAPPED,
    UNRESOLVED,
    cached_njit,
    tilt,
    tilt_versine,
    uses_torque,
)

# Fast-math flags that keep NaN/inf semantics honest (no 'nnan'/'ninf'): the kernels must
# see a non-finite state to report status NONFINITE.
FASTMATH = {"contract", "arcp", "nsz", "afn", "reassoc"}

TWO_PI = 2.0 * math.pi
INV_TWO_PI = 1.0 / TWO_PI


@nb.njit(inline="always")
def _identity(x):
    return x


# The RK4 step is written once, as source text with two holes, and compiled in two forms
# (:func:`specialise`): the τ = 0 form, θ̇' = −ω0² sin θ − 2αθ̇ exactly as earlier versions
# wrote it (adding a zero torque under fast-math may be reassociated and change the last bit
# of a trajectory), and the τ ≠ 0 form, θ̇' = τ − ω0² sin θ − 2αθ̇ with τ the last argument.
_RK4_STEP = """
def step(theta, theta_dot, alpha, omega0, dt{torque}):
    w2 = omega0 * omega0
    a2 = 2.0 * alpha
    h2 = 0.5 * dt
    p = reduce(theta)
    k1t = theta_dot
    k1v = {force}w2 * sin_near(p, 0.0) - a2 * theta_dot
    k2t = theta_dot + h2 * k1v
    k2v = {force}w2 * sin_near(p, h2 * k1t) - a2 * k2t
    k3t = theta_dot + h2 * k2v
    k3v = {force}w2 * sin_near(p, h2 * k2t) - a2 * k3t
    k4t = theta_dot + dt * k3v
    k4v = {force}w2 * sin_near(p, dt * k3t) - a2 * k4t
    h6 = dt / 6.0
    return (
        theta + h6 * (k1t + 2.0 * (k2t + k3t) + k4t),
        theta_dot + h6 * (k1v + 2.0 * (k2v + k3v) + k4v),
    )
"""


def specialise(source, name, torque, **env):
    """The plain Python function ``name`` defined by ``source`` in its τ = 0 form
    (``{torque}`` → nothing, ``{force}`` → ``-``: the acceleration starts −ω0²…) or its τ ≠ 0
    form (``{torque}`` → ``, torque``: one more argument; ``{force}`` → ``torque - ``), with
    ``env`` (the callables it calls) as its globals. Plain, so that the caller jits it for the
    CPU or (its ``py_func``) for CUDA, as with every factory here."""
    code = source.format(torque=", torque" if torque else "",
                         force="torque - " if torque else "-")
    filename = f"<atlas.kernels.rk4 {name}{' (torque)' if torque else ''}>"
    linecache.cache[filename] = (len(code), None, code.splitlines(True), filename)  # tracebacks
    namespace = {"__name__": __name__, **env}
    exec(compile(code, filename, "exec"), namespace)
    return namespace[name]


def make_rk4_step(sin, reduce=None, *, torque=False):
    """Return a jitted ``step(theta, theta_dot, alpha, omega0, dt) -> (theta, theta_dot)``.

    One classical RK4 step of θ' = θ̇, θ̇' = −ω0² sin θ − 2αθ̇ using the given ``sin``.
    With ``reduce`` given, the four stage angles θ + δ (δ = 0, ½dt·k1θ, ½dt·k2θ, dt·k3θ) share
    one argument reduction: ``sin`` is then called as ``sin(reduce(θ), δ)`` = sin(θ + δ)
    (:mod:`atlas.kernels.lanes` uses this with a polynomial sin). With ``torque`` the step of
    θ̇' = −ω0² sin θ − 2αθ̇ + τ, τ its last argument (:func:`make_rk4_step_torque`).
    """
    if reduce is None:
        reduce = _identity

        @nb.njit(inline="always", fastmath=FASTMATH)
        def sin_near(theta, delta):
            return sin(theta + delta)

    else:
        sin_near = sin

    step = specialise(_RK4_STEP, "step", torque, sin_near=sin_near, reduce=reduce)
    return nb.njit(inline="always", fastmath=FASTMATH)(step)


def make_well_energy(sin):
    """Return a jitted ``well_energy(theta, theta_dot, omega0) -> (k, E_k)``.

    k = round(θ/2π) is the nearest well, φ = θ − 2πk ∈ [−π, π], and
    E_k = ½θ̇² + ω0²(1 − cos φ) is evaluated as ½θ̇² + 2ω0² sin²(φ/2), which has no
    cancellation near the bottom of the well.
    """

    @nb.njit(inline="always", fastmath=FASTMATH)
    def well_energy(theta, theta_dot, omega0):
        k = math.floor(theta * INV_TWO_PI + 0.5)
        s = sin(0.5 * (theta - TWO_PI * k))
        return k, 0.5 * theta_dot * theta_dot + 2.0 * omega0 * omega0 * s * s

    return well_energy


@nb.njit(inline="always")
def _libm_sin(x):
    return math.sin(x)


rk4_step = make_rk4_step(_libm_sin)
well_energy = make_well_energy(_libm_sin)


# ------------------------------------------------------------------------- torque τ ≠ 0
# The τ ≠ 0 kernels are separate specialisations (the step from the same source as the τ = 0
# one, :data:`_RK4_STEP`), so that the τ = 0 kernels above stay exactly the code of earlier
# versions (adding 0.0 to the acceleration under fast-math may be reassociated and change the
# last bit of a trajectory).


def make_rk4_step_torque(sin, reduce=None):
    """Return a jitted ``step(theta, theta_dot, alpha, omega0, dt, torque) -> (θ, θ̇)``: one
    classical RK4 step of θ' = θ̇, θ̇' = −ω0² sin θ − 2αθ̇ + τ (``sin`` and ``reduce`` as in
    :func:`make_rk4_step`)."""
    return make_rk4_step(sin, reduce, torque=True)


def make_well_energy_torque(sin):
    """Return a jitted ``well_energy(theta, theta_dot, omega0, torque, shift, vers_shift)
    -> (k, E_k)`` for the tilted wells (kernel contract, :mod:`atlas.kernels`).

    ``shift`` = θ* = arcsin(τ/ω0²), ``vers_shift`` = 1 − cos θ*. k = round((θ + θ*)/2π) is the
    well whose strip −π − θ* ≤ φ < π − θ* (φ = θ − 2πk, between its two saddles) holds θ,
    and E_k = ½θ̇² + 2ω0² sin²(φ/2) − ω0²(1 − cos θ*) − τ(φ − θ*) its energy above the rest
    state (θ*, 0) (:meth:`atlas.physics.pendulum.Pendulum.energy`)."""

    @nb.njit(inline="always", fastmath=FASTMATH)
    def well_energy(theta, theta_dot, omega0, torque, shift, vers_shift):
        k = math.floor((theta + shift) * INV_TWO_PI + 0.5)
        phi = theta - TWO_PI * k
        s = sin(0.5 * phi)
        w2 = omega0 * omega0
        return k, (0.5 * theta_dot * theta_dot + w2 * (2.0 * (s * s) - vers_shift)
                   - torque * (phi - shift))

    return well_energy


def make_running_test(floor):
    """Return a jitted ``running(theta, theta_dot, sign, theta0, g, top) -> bool``: whether
    the state lies in the running certificate's region (kernel contract, :mod:`atlas.kernels`):
    with u = sign·θ, w = sign·θ̇ (sign = −1 mirrors a barrier given for τ > 0 onto τ < 0),
    w ≤ top and w ≥ ĝ(u), ĝ the linear interpolation of the M + 1 samples g over
    u − theta0 ∈ [0, 2π] (u reduced mod 2π). Never true when g is empty. ``floor`` is a
    float floor (np.floor on the CPU)."""

    @nb.njit(inline="always", fastmath=FASTMATH)
    def running(theta, theta_dot, sign, theta0, g, top):
        m = g.size - 1
        if m < 1:
            return False
        w = sign * theta_dot
        if not w <= top:
            return False
        x = sign * theta - theta0
        x = x - TWO_PI * floor(x * INV_TWO_PI)
        t = x * (m * INV_TWO_PI)
        i = min(max(floor(t), 0.0), m - 1.0)
        j = int(i)
        return w >= g[j] + (t - i) * (g[j + 1] - g[j])

    return running


well_energy_torque = make_well_energy_torque(_libm_sin)
rk4_step_torque = make_rk4_step_torque(_libm_sin)
running_test = make_running_test(np.floor)

NO_BARRIER = np.zeros(0)
NO_BARRIER.flags.writeable = False


def torque_model(omega0, torque, running_theta0=0.0, running_g=None, running_top=math.inf,
                 span=0.0):
    """The tuple ``model`` the τ ≠ 0 kernels take: (τ, θ*, 1 − cos θ*, sign, running_theta0,
    running_g, running_top, span). θ* = arcsin(τ/ω0²) (:func:`atlas.kernels.tilt`), clamped to
    ±π/2 when |τ| ≥ ω0² (then there is no well and the caller passes an energy cap that no
    state reaches); sign = −1.0 for τ < 0 (the running barrier is mirrored), +1.0 otherwise;
    running_g float64 (empty: no running certificate); span = the longest run [s], for the
    lane kernels' choice of path (:mod:`atlas.kernels.lanes`)."""
    torque = float(torque)
    shift = tilt(omega0, torque)
    vers = tilt_versine(shift)
    g = NO_BARRIER if running_g is None else np.ascontiguousarray(running_g, dtype=np.float64)
    if g.ndim != 1:
        raise ValueError("running_g must be one-dimensional")
    if g.flags.writeable:  # always a read-only view: one compiled specialisation, not two
        g = g.view()
        g.flags.writeable = False
    return (torque, shift, vers, -1.0 if torque < 0.0 else 1.0, float(running_theta0), g,
            float(running_top), float(span))


@nb.njit(nogil=True, fastmath=FASTMATH)
def label_orbit(theta, theta_dot, alpha, omega0, dt, n_checks, check_every, energy_cap):
    """Label one orbit (kernel contract in :mod:`atlas.kernels`) with ``math.sin``; returns
    (status, k, n_trap), k meaningful only when trapped."""
    for j in range(n_checks + 1):
        if not (math.isfinite(theta) and math.isfinite(theta_dot)):
            return NONFINITE, 0, -1
        k, energy = well_energy(theta, theta_dot, omega0)
        if energy < energy_cap:
            return TRAPPED, k, j * check_every
        if j == n_checks:
            break
        for _ in range(check_every):
            theta, theta_dot = rk4_step(theta, theta_dot, alpha, omega0, dt)
    return UNRESOLVED, 0, -1


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def _label_straightforward(
    theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every, energy_cap,
    attractor, status, n_trap,
):
    """The τ = 0 specialisation of :func:`label_straightforward` (the kernel of earlier
    versions, unchanged: its labels are bit-identical to theirs)."""
    for i in nb.prange(theta0.size):
        st, k, nt = label_orbit(theta0[i], theta_dot0[i], alpha, omega0, dt, n_checks,
                                check_every, energy_cap)
        status[i] = st
        n_trap[i] = nt
        if st == TRAPPED:
            attractor[i] = np.int32(k)


def make_label_orbit_torque(sync, step, fastmath):
    """Return a jitted ``label_orbit(theta, theta_dot, alpha, omega0, dt, n_checks,
    check_every, energy_cap, model) -> (status, k, n_trap)`` for the tilted pendulum, one
    method's scalar labeller: ``sync(θ, θ̇, ω0, τ, θ*, 1 − cos θ*) -> (c, s, k, E_k)`` is the
    tilted trap (with the trig-free method's re-synchronised c, s; unused otherwise),
    ``step(θ, θ̇, c, s, α, ω0, dt, τ) -> (θ, θ̇, c, s)`` one step."""

    @nb.njit(nogil=True, fastmath=fastmath)
    def label_orbit(theta, theta_dot, alpha, omega0, dt, n_checks, check_every, energy_cap,
                    model):
        """Label one orbit of the tilted pendulum (kernel contract in :mod:`atlas.kernels`;
        ``model`` from :func:`torque_model`): the energy trap of the tilted wells, then the
        running certificate, at every check. Returns (status, k, n_trap), k meaningful only
        when trapped."""
        torque, shift, vers, sign, r_theta0, r_g, r_top, _ = model
        for j in range(n_checks + 1):
            if not (math.isfinite(theta) and math.isfinite(theta_dot)):
                return NONFINITE, 0, -1
            c, s, k, energy = sync(theta, theta_dot, omega0, torque, shift, vers)
            if energy < energy_cap:
                return TRAPPED, k, j * check_every
            if running_test(theta, theta_dot, sign, r_theta0, r_g, r_top):
                return RUNNING, 0, j * check_every
            if j == n_checks:
                break
            for _ in range(check_every):
                theta, theta_dot, c, s = step(theta, theta_dot, c, s, alpha, omega0, dt,
                                              torque)
        return UNRESOLVED, 0, -1

    return label_orbit


@nb.njit(inline="always", fastmath=FASTMATH)
def _sync_torque(theta, theta_dot, omega0, torque, shift, vers_shift):
    k, energy = well_energy_torque(theta, theta_dot, omega0, torque, shift, vers_shift)
    return 0.0, 0.0, k, energy


@nb.njit(inline="always", fastmath=FASTMATH)
def _step_cs_torque(theta, theta_dot, c, s, alpha, omega0, dt, torque):
    theta, theta_dot = rk4_step_torque(theta, theta_dot, alpha, omega0, dt, torque)
    return theta, theta_dot, c, s


#: The tilted pendulum's scalar labeller with ``math.sin`` (:func:`make_label_orbit_torque`).
label_orbit_torque = make_label_orbit_torque(_sync_torque, _step_cs_torque, FASTMATH)


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def _label_straightforward_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks,
                                  check_every, energy_cap, model, attractor, status, n_trap):
    for i in nb.prange(theta0.size):
        st, k, nt = label_orbit_torque(theta0[i], theta_dot0[i], alpha, omega0, dt, n_checks,
                                       check_every, energy_cap, model)
        status[i] = st
        n_trap[i] = nt
        if st == TRAPPED:
            attractor[i] = np.int32(k)


def label_straightforward(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                          energy_cap, attractor, status, n_trap, torque=0.0,
                          running_theta0=0.0, running_g=None, running_top=math.inf):
    """Label orbits one per ``prange`` iteration with ``math.sin`` (kernel contract in
    :mod:`atlas.kernels`). The plain implementation that the fast kernels are measured and
    checked against. With τ = 0 and no running barrier it runs the τ = 0 specialisation
    (the kernel of earlier versions), else the tilted one."""
    if not uses_torque(torque, running_g):
        _label_straightforward(theta0, theta_dot0, alpha, omega0, dt, n_checks, check_every,
                               energy_cap, attractor, status, n_trap)
        return
    model = torque_model(omega0, torque, running_theta0, running_g, running_top)
    _label_straightforward_torque(theta0, theta_dot0, alpha, omega0, dt, n_checks,
                                  check_every, energy_cap, model, attractor, status, n_trap)


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def propagate_straightforward(theta, theta_dot, alpha, omega0, dt, n_steps):
    """Advance every orbit by ``n_steps`` RK4 steps in place (no early exit): bulk throughput
    reference and the fixed-duration integrator used by tests and figures."""
    for i in nb.prange(theta.size):
        th = theta[i]
        v = theta_dot[i]
        for _ in range(n_steps):
            th, v = rk4_step(th, v, alpha, omega0, dt)
        theta[i] = th
        theta_dot[i] = v


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def record_straightforward(theta, theta_dot, alpha, omega0, dt, every, out):
    """Trajectories: ``out[:, i, j]`` = (θ, θ̇) of orbit j after i·``every`` RK4 steps, for
    i < out.shape[1] (figures and phase portraits; the same step as every kernel here)."""
    for j in nb.prange(theta.size):
        th, v = theta[j], theta_dot[j]
        out[0, 0, j], out[1, 0, j] = th, v
        for i in range(1, out.shape[1]):
            for _ in range(every):
                th, v = rk4_step(th, v, alpha, omega0, dt)
            out[0, i, j], out[1, i, j] = th, v


@cached_njit(parallel=True, nogil=True, fastmath=FASTMATH)
def record_torque(theta, theta_dot, alpha, omega0, torque, dt, every, out):
    """:func:`record_straightforward` for θ̈ = −ω0² sin θ − 2αθ̇ + τ (the τ ≠ 0 labelling
    kernels' step): ``out[:, i, j]`` = (θ, θ̇) of orbit j after i·``every`` RK4 steps."""
    for j in nb.prange(theta.size):
        th, v = theta[j], theta_dot[j]
        out[0, 0, j], out[1, 0, j] = th, v
        for i in range(1, out.shape[1]):
            for _ in range(every):
                th, v = rk4_step_torque(th, v, alpha, omega0, dt, torque)
            out[0, i, j], out[1, i, j] = th, v
