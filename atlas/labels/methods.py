"""The discretisations atlas labels with, as data: the one place a method's name becomes a method.

After scipy's ``integrate._ivp`` (``METHODS = {"RK45": RK45, …}``): a :class:`Method` is its
name, order, kernels and flags, and :data:`METHODS` maps every name of
:data:`atlas.defaults.METHODS` to one. Two methods, both classical RK4 (order 4; Hairer,
Nørsett & Wanner, *Solving ODEs I*, §II.1), whose trajectories differ by O(dt⁴):

* "rk4" — on (θ, θ̇) with a sin per stage (:mod:`atlas.kernels.rk4`); CUDA runs it, and the
  running certificate's RK4 allowance is measured for it;
* "rk4-trigfree" — on (θ, θ̇, cos θ, sin θ) with no trigonometric function in a step, (cos θ,
  sin θ) re-synchronised from θ at every trap test (:mod:`atlas.kernels.trigfree`).

Each names its CPU kernels by ``"module:function"`` (imported on first use: the registry
itself loads no Numba) and gives its scalar form in plain Python (:class:`Scalar`), built
from the kernels' own factories, for ``atlas orbit`` and tests.
"""

from __future__ import annotations

import functools
import importlib
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

from atlas import defaults

__all__ = ["Method", "Scalar", "METHODS", "lookup"]


def load(target: str):
    """The object named by ``"package.module:attribute"`` (imported now)."""
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


class Scalar(NamedTuple):
    """A method's scalar form, plain Python with libm (``math.sin``), in the interface of the
    kernels' scalar labeller (:func:`atlas.kernels.rk4.make_label_orbit_torque`):

    step(θ, θ̇, c, s, α, ω0, dt, τ) -> (θ, θ̇, c, s): one step of ``dt`` [s];
    sync(θ, θ̇, ω0, τ, θ*, 1 − cos θ*) -> (c, s, k, E_k): at a trap test, the well k and its
        energy E_k [rad² s⁻²] (the trap of :mod:`atlas.kernels`), and the (c, s) = (cos θ,
        sin θ) the next steps start from (0.0 for a method that carries none).

    With τ = 0 both run the τ = 0 specialisation of the kernels (the untilted well energy),
    as the kernels do. The same discretisation as the method's straightforward kernel, rounded
    as Python rounds (no fused multiply-add): labels agree except where rounding decides.
    """

    step: Callable
    sync: Callable


@dataclass(frozen=True)
class Method:
    """One discretisation of θ̈ = −ω0² sin θ − 2αθ̇ + τ and where its code lives.

    name:      the name a config or :func:`atlas.label` gives (:data:`atlas.defaults.METHODS`).
    summary:   one line saying what it is.
    order:     its order of convergence (global error O(dt^order)).
    lanes:     ``"module:function"`` of its fast CPU kernel (the lane-blocked SIMD kernel).
    reference: ``"module:function"`` of its straightforward CPU kernel (one orbit per
               ``prange`` iteration, libm sin: the plain form the fast one is checked against).
    scalar:    ``"module:function"`` returning its :class:`Scalar` form.
    cuda:      whether the CUDA kernels run it.
    running:   whether the running certificate is established for it (its RK4 allowance,
               :func:`atlas.physics.running.rk4_allowance`, is measured for this method).
    resync:    what it re-synchronises at every trap test ("" when nothing): part of the
               method, a trajectory depends on where it happens.
    All kernels follow the contract of :mod:`atlas.kernels`.
    """

    name: str
    summary: str
    order: int
    lanes: str
    reference: str
    scalar: str
    cuda: bool
    running: bool
    resync: str = ""

    def __post_init__(self) -> None:
        if self.name not in defaults.METHODS:
            raise ValueError(f"method {self.name!r} is not one of {defaults.METHODS}")
        for field in ("lanes", "reference", "scalar"):
            module, colon, name = getattr(self, field).partition(":")
            if not (module.startswith("atlas.") and colon and name):
                raise ValueError(f"Method.{field} must read 'atlas.module:function', got "
                                 f"{getattr(self, field)!r}")

    def kernel(self, straightforward: bool = False) -> Callable:
        """Its CPU kernel (contract of :mod:`atlas.kernels`): the lane kernel, or with
        ``straightforward`` the reference kernel."""
        return load(self.reference if straightforward else self.lanes)

    def scalar_form(self) -> Scalar:
        """Its :class:`Scalar` form (built once)."""
        return _scalar(self.scalar)


@functools.cache
def _scalar(target: str) -> Scalar:
    return load(target)()


def _sin_near(p, delta):
    return math.sin(p + delta)


def _same(x):
    return x


def rk4_scalar() -> Scalar:
    """"rk4" in plain Python: the kernels' step source (:func:`atlas.kernels.rk4.make_rk4_step`
    with libm sin and no shared reduction) and their well energies."""
    from atlas.kernels import rk4

    steps = (rk4.make_rk4_step(_sin_near, _same).py_func,
             rk4.make_rk4_step_torque(_sin_near, _same).py_func)
    energy = rk4.make_well_energy(math.sin).py_func
    energy_torque = rk4.make_well_energy_torque(math.sin).py_func

    def step(theta, theta_dot, c, s, alpha, omega0, dt, torque):
        if torque == 0.0:
            return (*steps[0](theta, theta_dot, alpha, omega0, dt), c, s)
        return (*steps[1](theta, theta_dot, alpha, omega0, dt, torque), c, s)

    def sync(theta, theta_dot, omega0, torque, shift, vers_shift):
        if torque == 0.0:
            return (0.0, 0.0, *energy(theta, theta_dot, omega0))
        return (0.0, 0.0, *energy_torque(theta, theta_dot, omega0, torque, shift, vers_shift))

    return Scalar(step, sync)


def trigfree_scalar() -> Scalar:
    """"rk4-trigfree" in plain Python: the kernels' step source
    (:data:`atlas.kernels.trigfree.trigfree_step`, ``trigfree_step_torque``) and their
    re-synchronisation with libm (``make_sync``, ``make_sync_torque``), as the method's scalar
    kernel ``label_orbit_trigfree`` runs them."""
    from atlas.kernels import trigfree

    libm = trigfree._libm_sin_cos_vers.py_func
    step0, step_torque = trigfree.trigfree_step.py_func, trigfree.trigfree_step_torque.py_func
    sync0 = trigfree.make_sync(libm).py_func
    sync_torque = trigfree.make_sync_torque(libm).py_func

    def step(theta, theta_dot, c, s, alpha, omega0, dt, torque):
        if torque == 0.0:
            return step0(theta, theta_dot, c, s, alpha, omega0, dt)
        return step_torque(theta, theta_dot, c, s, alpha, omega0, dt, torque)

    def sync(theta, theta_dot, omega0, torque, shift, vers_shift):
        if torque == 0.0:
            return sync0(theta, theta_dot, omega0)
        return sync_torque(theta, theta_dot, omega0, torque, shift, vers_shift)

    return Scalar(step, sync)


#: Every method by name, in the order of :data:`atlas.defaults.METHODS`.
METHODS: dict[str, Method] = {m.name: m for m in (
    Method(name="rk4", summary="classical RK4 on (θ, θ̇), a sin per stage", order=4,
           lanes="atlas.kernels.lanes:label_lanes",
           reference="atlas.kernels.rk4:label_straightforward",
           scalar="atlas.labels.methods:rk4_scalar", cuda=True, running=True),
    Method(name="rk4-trigfree", summary="classical RK4 on (θ, θ̇, cos θ, sin θ), no sin in a step",
           order=4, lanes="atlas.kernels.lanes:label_trigfree",
           reference="atlas.kernels.trigfree:label_trigfree_straightforward",
           scalar="atlas.labels.methods:trigfree_scalar", cuda=False, running=False,
           resync="(cos θ, sin θ) from θ, libm or the polynomial sin of atlas.kernels.fastsin"),
)}


def lookup(name: str) -> Method:
    """The :class:`Method` called ``name``; ValueError (one line) for an unknown name."""
    try:
        return METHODS[name]
    except (KeyError, TypeError):
        raise ValueError(f"method must be one of {defaults.METHODS}, got {name!r}") from None
