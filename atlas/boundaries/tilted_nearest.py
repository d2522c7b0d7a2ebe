"""Nearest points on the exact basin boundaries of the pendulum with torque: a state's nearest
boundary point (its minimal fatal shock from a rest state) and the running limit cycle's
minimal fatal shock, exact for the DOP853 dense output of the stable branches.

Both search the translates by 2πk of the branches' polynomial pieces
(:mod:`atlas.kernels.dense_curves`: ``nearest``, ``nearest_between``), bounded by the nearer
saddle (a boundary point), and repeat the search on the branches at rtol 1e-12 for the error.
Units: θ [rad], θ̇ [rad s⁻¹], distances in the (θ, θ̇) plane with both as one unit
("rad-ish"). Reference: Halekotte & Feudel, Sci. Rep. 10, 11783 (2020) (minimal fatal shocks).
"""

from __future__ import annotations

import math

import numpy as np

from atlas.boundaries.branches import FundamentalBranches, branch_pieces

__all__ = ["nearest_point", "running_shock", "near_first"]

_TWO_PI = 2.0 * math.pi


def near_first(search, near: float | None, bound: float):
    """``search(b)`` (a nearest-point search that finds nothing nearer than ``b``: NaN
    coordinates) first within ``near`` — the same distance found at another tolerance (they
    differ by some 1e-12) — a little widened, so that it prunes at once; then, if nothing
    was found there, within ``bound``."""
    if near is not None:
        found = search(near * (1.0 + 1e-6) + 1e-9)
        if not math.isnan(found[1]):
            return found
    return search(bound)


def _nearest(b, f: FundamentalBranches, theta: float, theta_dot: float,
             near: float | None = None):
    """(distance, θ, θ̇) of the nearest point of any Γ_k of ``f`` to one point
    (actual frame), exact for the dense output (:func:`atlas.kernels.dense_curves.
    nearest`): the nearer of the two saddles beside the point bounds the search, or
    ``near`` (the distance found at another tolerance) a little widened, where that
    finds it."""
    from atlas.kernels.dense_curves import nearest

    x, v = b.sign * theta, b.sign * theta_dot
    s = f.saddle
    j0 = math.floor((x - s) / _TWO_PI)
    best = min(math.hypot(x - s - _TWO_PI * j, v) for j in (j0, j0 + 1))
    lo, hi = f.theta_range
    ks = range(math.floor((x - best - hi - 1.0) / _TWO_PI),
               math.ceil((x + best - lo + 1.0) / _TWO_PI) + 1)
    shifts = _TWO_PI * np.array(ks, np.float64)
    d, t, w = near_first(lambda bound: nearest(f.pieces, shifts, float(x), float(v),
                                                bound), near, math.inf)
    return d, b.sign * t, b.sign * w

def running_shock(b):
    """The minimal fatal shock of the running limit cycle (Halekotte & Feudel 2020): the
    nearest pair of a point of the cycle and a point of a basin boundary (any tongue's),
    as (distance [rad-ish], the cycle's point θ [rad], θ̇ [rad s⁻¹], the boundary's point
    θ, θ̇, error [rad-ish]); NaN where there is no running cycle (not ``bistable``). The
    cycle is one turn from its crossing of the section θs
    (:func:`atlas.physics.running.cycle_section`, or :attr:`cycle` where known) by
    DOP853 at rtol 1e-12, as pieces; the pair is exact for the pieces
    (:func:`atlas.kernels.dense_curves.nearest_between`). The error: the distance's
    change with the boundaries at RTOL_CHECK, plus the cycle's own (its relative error
    times a bound on its speed)."""
    from atlas.kernels.dense_curves import nearest_between, ranges
    from atlas.kernels.dop853 import EVENT, FLOW, TURN, solve
    from atlas.physics.running import cycle_section

    if not b.bistable:
        return (math.nan,) * 6
    p = b.pendulum
    tau, rtol = abs(p.torque), 1e-12
    if b.known_cycle is not None:  # given, or found already: its crossing of θs
        cycle = b.known_cycle
        theta_s, v = b.sign * cycle.theta0, b.sign * float(cycle.theta_dot[0])
        period, cycle_error = cycle.period, cycle.error
        scale = (p.omega0**2 + tau) / (2.0 * p.alpha)
        turn = solve(FLOW, (p.alpha, p.omega0, tau, 0.0), TURN, (theta_s + _TWO_PI, 0.0),
                     (theta_s, v), 4.0 * period, rtol, (rtol * _TWO_PI, rtol * scale),
                     dim=2)
    else:  # only the crossing, not the sampled cycle, and the turn the search ended on
        theta_s, v, period, cycle_error, turn = cycle_section(
            p.alpha, p.omega0, p.torque, rtol=rtol, escapes=b.escapes, turn=True)
    if turn.status != EVENT:
        raise RuntimeError("the running cycle did not complete a turn")
    pieces = branch_pieces(turn)
    lo, hi = b.fundamental.theta_range
    shifts = _TWO_PI * np.arange(math.floor((theta_s - _TWO_PI - hi) / _TWO_PI),
                                 math.ceil((theta_s + 2.0 * _TWO_PI - lo) / _TWO_PI) + 1,
                                 dtype=np.float64)
    # the saddle (θs, 0) is on a boundary, the cycle's point (θs, v) above it: a bound
    bound = v * (1.0 + 1e-9)
    fine = nearest_between(pieces, b.fundamental.pieces, shifts, bound)
    check = near_first(lambda r: nearest_between(pieces, b.fundamental_check.pieces,
                                                  shifts, r), fine[0], bound)
    box = np.empty((pieces.shape[0], 2, 2))
    ranges(pieces, box)
    speed = float(np.abs(box[:, 1, :]).max())  # at least the cycle's largest speed
    error = (abs(fine[0] - check[0]) + cycle_error * speed
             + 4 * np.finfo(float).eps * max(fine[0], 1.0))
    d, a_t, a_v, b_t, b_v = (float(x) for x in fine)
    sign = b.sign
    return d, sign * a_t, sign * a_v, sign * b_t, sign * b_v, error

def nearest_point(b, theta: float, theta_dot: float):
    """(distance [rad-ish], θ [rad], θ̇ [rad s⁻¹], error [rad-ish]) of the nearest point
    of the boundaries to (θ, θ̇), exact for the dense output of the branches at rtol; the
    error is the change of the distance from RTOL_CHECK (docs/design/tilted-boundaries.md).
    """
    d, t, w = _nearest(b, b.fundamental, theta, theta_dot)
    check, *_ = _nearest(b, b.fundamental_check, theta, theta_dot, near=d)
    return d, t, w, abs(d - check) + 4 * np.finfo(float).eps * max(d, 1.0)
