"""The fundamental stable branches of the tilted saddle: Γ_0 = L_0 ∪ R_0 of the canonical
pendulum with torque τ > 0, integrated once.

θ̈ = −ω0² sin θ − 2αθ̇ + τ (α > 0 [s⁻¹], ω0 [rad s⁻¹], 0 < τ < ω0² [rad s⁻²]). Each branch of
the saddle (π − θ*, 0) is integrated by DOP853 (rtol = atol, dense output; compiled,
:mod:`atlas.kernels.dop853`) in reversed time from START_DISTANCE along the stable
eigenvector until θ̇ leaves a band; :class:`FundamentalBranches` holds both as the dense
outputs, as polynomial pieces (:mod:`atlas.kernels.dense_curves`: exact areas and nearest
points) and as polylines refined to a chord tolerance (:class:`Polyline`: the sides and
distances of :class:`atlas.boundaries.tilted.TiltedBoundaries`, every other boundary being a
2π translate). Units: θ [rad], θ̇ [rad s⁻¹], chord errors in the (θ, θ̇) plane with both as
one unit ("rad-ish"). References: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5–6
(DOP853 and its dense output). Derivation: docs/design/tilted-boundaries.md.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from atlas.boundaries.manifold import DenseOutput
from atlas.physics.pendulum import START_DISTANCE, Pendulum

__all__ = ["FundamentalBranches", "Polyline", "integrate_branch", "branch_pieces",
           "CHORD_TOL", "MAX_SEGMENT"]

#: Largest distance [rad-ish] of a branch from its polyline's chords, aimed for: the chords
#: the sides and distances search (the distances themselves are measured to the dense
#: output), whose vertices the trace starts from.
CHORD_TOL = 1e-6
#: Longest polyline segment [rad-ish] (keeps the coarse chords of the distance search short:
#: their length enters its pruning bound).
MAX_SEGMENT = 0.004


def integrate_branch(p: Pendulum, sign: int, rtol: float, bottom: float, top: float):
    """DOP853 along the branch of the saddle (π − θ*, 0) of ``p`` (τ ≥ 0) arriving from the
    left (``sign`` −1, L) or right (+1, R), in reversed time from START_DISTANCE along the
    stable eigenvector, until θ̇ leaves (bottom, top) (compiled:
    :func:`atlas.kernels.dop853.integrate`, scipy's method step for step). Returns (dense
    output of (θ, θ̇), the :class:`atlas.kernels.dop853.Solution`, 'top' or 'bottom')."""
    from atlas.kernels.dop853 import BAND, EVENT, REVERSED, solve

    s = p.saddle_angle
    e0, e1 = p.saddle_stable_direction()
    start = [s + sign * START_DISTANCE * e0, sign * START_DISTANCE * e1]
    t_cap = 1e4 * (1.0 / p.alpha + 1.0 / p.omega0)
    sol = solve(REVERSED, (p.alpha, p.omega0, p.torque, 0.0), BAND, (bottom, top), start,
                t_cap, rtol, (rtol,), dim=2)
    if sol.status != EVENT:
        raise RuntimeError(f"a stable branch did not leave the band (status {sol.status})")
    end = sol.y[-1, 1]
    dense = DenseOutput(sol.t, sol.t_old, sol.h, sol.y_old[:, :2], sol.F[:, :, :2])
    return dense, sol, "top" if end - top >= bottom - end else "bottom"


def branch_pieces(sol) -> np.ndarray:
    """The branch ``sol`` (from its start next to the saddle outward) as polynomial pieces,
    one per DOP853 step, the last cut at the event (:mod:`atlas.kernels.dense_curves`)."""
    from atlas.kernels.dense_curves import from_dense

    span = np.ones(sol.h.size)
    span[-1] = (sol.t[-1] - sol.t_old[-1]) / sol.h[-1]
    out = np.empty((sol.h.size, 2, 8))
    from_dense(np.ascontiguousarray(sol.y_old), np.ascontiguousarray(sol.F[:, ::-1]), span,
               out)
    return out


def _refine(dense, t, tol: float, longest: float):
    """The polyline of ``dense`` (a curve of reversed time) through times ⊇ ``t``: (times,
    vertices (2, n), chord error). Its chord error — the distance of the dense output at the
    middle of each segment's time interval from the chord — is ≤ ``tol`` (it shrinks like
    the square of a segment, so a segment is cut into ⌈1.2√(error/tol)⌉ pieces), and no
    segment is longer than ``longest``. Each segment is measured once (compiled:
    :func:`atlas.kernels.segments.refine`)."""
    from atlas.kernels.segments import refine

    times, xy, error, ok = refine(np.ascontiguousarray(t, dtype=np.float64), dense.t,
                                  dense.t_old, dense.h, np.ascontiguousarray(dense.y_old),
                                  dense.F, float(tol), float(longest))
    if not ok:
        raise RuntimeError("the branch polyline did not reach its chord tolerance")
    return times, xy, float(error)


class Polyline:
    """A polyline of Γ_0 = L_0 ∪ R_0 (canonical): ``left``, ``right`` (2, n) each from the
    saddle out (the saddle first), ``theta``, ``theta_dot`` (from L_0's end through the
    saddle to R_0's end), ``times`` (each branch's reversed times at its vertices, the
    saddle's left out), ``chord_error``; and per segment of ``theta``: ``step``, the step of
    the packed dense output (:attr:`FundamentalBranches.packed`) whose polynomial it is the chord
    of (−1 for the two straight pieces at the saddle), and ``span``, its x range there."""

    def __init__(self, fundamental: FundamentalBranches, parts, times, chord_error: float):
        saddle = np.array([[fundamental.saddle], [0.0]])
        self.left, self.right = (np.concatenate([saddle, xy], axis=1) for xy in parts)
        self.theta, self.theta_dot = np.concatenate([self.left[:, ::-1], self.right[:, 1:]],
                                                    axis=1)
        self.times, self.chord_error = times, chord_error
        self._fundamental = fundamental

    @cached_property
    def _pieces(self):
        """(step, span) of every segment of ``theta`` (made on first use: the distance search
        needs them, the reference polyline and the drawn curves do not)."""
        (l_step, l_span), (r_step, r_span) = (
            self._fundamental.pieces_of(i, t) for i, t in enumerate(self.times))
        return (np.concatenate([l_step[::-1], r_step]),
                np.ascontiguousarray(np.concatenate([l_span[::-1, ::-1], r_span])))

    @property
    def step(self) -> np.ndarray:
        return self._pieces[0]

    @property
    def span(self) -> np.ndarray:
        return self._pieces[1]


class FundamentalBranches:
    """Γ_0 = L_0 ∪ R_0 of the canonical pendulum ``p`` (τ > 0) at rtol ``rtol``: its two
    branches integrated (``ends``, ``bistable``), as polynomial pieces (``pieces``, from L_0's
    end through the saddle to R_0's end: the exact areas and nearest points), packed
    (``packed``: both branches' dense outputs, L_0's steps first: the distance search's
    curves) and as polylines (:meth:`polyline`: sides and distances of the grid's points)."""

    def __init__(self, p: Pendulum, rtol: float, bottom: float, top: float):
        from atlas.kernels.dense_curves import reversed_pieces, segment

        self.saddle = p.saddle_angle
        self.branches = [integrate_branch(p, sign, rtol, bottom, top) for sign in (-1, 1)]
        self.ends = [end for _, _, end in self.branches]
        (_, left, _), (_, right, _) = self.branches
        s = self.saddle
        self.pieces = np.concatenate([
            reversed_pieces(branch_pieces(left)),
            segment(left.y[0, 0], left.y[0, 1], s, 0.0),
            segment(s, 0.0, right.y[0, 0], right.y[0, 1]),
            branch_pieces(right)])
        self.theta_range = (float(min(left.y[:, 0].min(), right.y[:, 0].min())),
                            float(max(left.y[:, 0].max(), right.y[:, 0].max())))
        self._polylines = {}

    @cached_property
    def packed(self):
        """(F (steps, powers, 2) highest power first, y_old (steps, 2)) of both branches'
        dense outputs, L_0's steps first, and the first step of each branch."""
        dense = [d for d, _, _ in self.branches]
        return (np.ascontiguousarray(np.concatenate([d.F for d in dense])),
                np.ascontiguousarray(np.concatenate([d.y_old for d in dense])),
                (0, dense[0].h.size))

    def pieces_of(self, branch: int, times):
        """(step in :attr:`packed`, x span (n, 2)) of each segment of ``branch``'s polyline
        through the saddle and the vertices at reversed ``times``: −1 for the straight piece
        from the saddle, then the step that holds each chord's middle time."""
        dense = self.branches[branch][0]
        step = np.clip(np.searchsorted(dense.t, 0.5 * (times[:-1] + times[1:]), "right") - 1,
                       0, dense.h.size - 1)
        span = np.column_stack([(times[:-1] - dense.t_old[step]) / dense.h[step],
                                (times[1:] - dense.t_old[step]) / dense.h[step]])
        first = self.packed[2][branch]
        return (np.concatenate([[-1], step + first]).astype(np.int64),
                np.concatenate([np.zeros((1, 2)), span]))

    def polyline(self, tol: float = CHORD_TOL, times=None) -> Polyline:
        """The polyline (made once per ``tol``): through the reversed times ``times`` (the
        per-branch times of another polyline) if given, else refined to ``tol``."""
        key = tol if times is None else ("times", id(times))
        if key not in self._polylines:
            chord_error, all_times, parts = 0.0, [], []
            for i, (dense, sol, _) in enumerate(self.branches):
                steps = sol.t
                if times is None:
                    t, xy, err = _refine(dense, steps, tol, MAX_SEGMENT)
                    chord_error = max(chord_error, err)
                else:
                    t = np.append(times[i][times[i] < steps[-1]], steps[-1])
                    xy = dense(t)
                all_times.append(t)
                parts.append(xy)
            self._polylines[key] = Polyline(self, parts, all_times, chord_error)
        return self._polylines[key]

    @property
    def bistable(self) -> bool:
        """Whether L_0 turns down (leaves the band at the bottom): tongues, a running basin."""
        return self.ends[0] == "bottom"
