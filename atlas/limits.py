"""What settings atlas can honour: limits set by double precision and by the file format.

The config validator (:mod:`atlas.pipeline.config`) checks them before any work, so a valid config
never fails once its basin map is computed; the numerical modules check them again.
"""

from __future__ import annotations

import math

import numpy as np

#: Range of the rates α [s⁻¹] and ω0 [rad s⁻¹] a config may give: within it the eigenvalues,
#: energies (ω0²) and trap margins stay finite in double precision; beyond it no dt that an
#: orbit's step budget allows is both stable and able to reach t_max.
MIN_RATE, MAX_RATE = 1e-6, 1e6
#: Most RK4 steps one orbit may take: step counts are int32 in every kernel.
MAX_STEPS = int(np.iinfo(np.int32).max)
#: Largest |k| of an attractor (θ* + 2πk, 0): ``attractor`` is int16 in the file.
MAX_WELL = int(np.iinfo(np.int16).max)
#: Largest relative safety margin m of the energy trap (:func:`atlas.labels.trap.trap_margin`):
#: beyond it dt is so coarse that the trap would certify little or nothing.
MAX_TRAP_MARGIN = 0.1


def reach(theta_abs: float, speed_abs: float, alpha: float) -> float:
    """Bound [rad] on |θ| along orbits starting at |θ0| ≤ ``theta_abs``, |θ̇0| ≤ ``speed_abs``.

    From θ̈ + 2αθ̇ = −ω0² sin θ the distance travelled is |θ̇0 − ω0²∫sin θ dt|/(2α), about
    |θ̇0|/(2α) for fast rotation, whose sin averages out; twice that plus a well of slack is
    the bound. Orbits must stay within the wells |k| ≤ MAX_WELL that the file can index.
    """
    return theta_abs + speed_abs / alpha + 2 * math.pi


def check_reach(theta_abs: float, speed_abs: float, alpha: float) -> None:
    """Raise ValueError (one line) if orbits may reach wells beyond |k| ≤ MAX_WELL."""
    bound = reach(theta_abs, speed_abs, alpha)
    if bound > 2 * math.pi * MAX_WELL:
        raise ValueError(f"orbits from this window may travel to |θ| ≈ {bound:.3g} rad, "
                         f"beyond the wells |k| ≤ {MAX_WELL} that an atlas file can index")
#: Smallest ``tol``, in units of the spacing of doubles at the window's largest |θ| or |θ̇|:
#: a bracket of width tol must still hold the multisection points (up to 7) as distinct,
#: well-separated doubles, and its midpoint must differ from both ends.
MIN_TOL_ULPS = 64
#: Smallest ``max_spacing`` [rad-ish]. At 1e-4 the chord error (≤ max_spacing²/8 ≈ 1.3e-9;
#: measured 6e-10) already equals the located curve's own O(dt⁴) offset from the exact
#: manifold at the default dt (6e-10 with the default method "rk4", 4e-9 with "rk4-trigfree"),
#: so a finer polyline adds points but no accuracy; and
#: the points grow as 1/max_spacing (default window, α = 0.1: 1654 at 0.05, 8e5 and ≈ 20 s
#: on 2 cores at 1e-4).
MIN_MAX_SPACING = 1e-4


#: Narrowest window side, in units of ``tol``: a boundary located to tol (every traced
#: point) is then resolved to 1/1000 of the window, and the points a zoom places
#: side/16 apart (:func:`atlas.boundaries.predictor.fine_spacing`) stay 60 tol apart, their
#: brackets disjoint. With the default tol 1e-12: windows down to 1e-9 wide.
MIN_WINDOW_TOLS = 1000


#: Narrowest window side [rad or rad s⁻¹] of a stability study: its fractions are exact areas
#: of the reference curves, good to their accuracy (≈ 1e-12 in position: DOP853 at rtol 1e-13,
#: and the coordinates' rounding, 16 eps·|θ|), so a fraction's error is about that accuracy
#: over the side: ≤ 1e-8 from 1e-4 on. (A grid run's zoom goes further: its labels are
#: certified point by point.)
MIN_STUDY_SIDE = 1e-4


def check_study_window(theta_window, theta_dot_window) -> None:
    """Raise ValueError, in one line naming the axis, if a side of a stability study's window
    ([rad], [rad s⁻¹]) is narrower than :data:`MIN_STUDY_SIDE`."""
    for axis, (lo, hi) in (("theta0", theta_window), ("theta_dot0", theta_dot_window)):
        side = float(hi) - float(lo)
        if side < MIN_STUDY_SIDE:
            raise ValueError(
                f"{axis}: a study's window {side:.3g} wide is narrower than "
                f"{MIN_STUDY_SIDE:g}: its exact fractions would carry the boundary curves' "
                "own error (about 1e-12 in position) relative to the window; widen it (a "
                "grid run, `atlas run`, zooms further)")


def _round_up(x: float) -> float:
    """``x`` rounded up to two significant digits (a bound that still holds when printed)."""
    unit = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.ceil(x / unit) * unit


def finest_tol(theta_window, theta_dot_window) -> float:
    """The finest separatrix ``tol`` [rad-ish] double precision resolves in this window
    ([rad], [rad s⁻¹]): ``MIN_TOL_ULPS`` (64) spacings of doubles at its largest |θ| or |θ̇|,
    rounded up to two significant digits (1.2e-13 for |θ| ≤ 3π; 1.9e-12 for |θ| ≤ 180)."""
    scale = max(abs(float(x)) for x in (*theta_window, *theta_dot_window))
    return _round_up(MIN_TOL_ULPS * float(np.spacing(scale)))


def check_separatrix_settings(theta_window, theta_dot_window, tol: float,
                              max_spacing: float) -> None:
    """Raise ValueError, with a one-line reason naming the setting, unless
    :func:`atlas.boundaries.trace.trace` can honour ``tol`` and ``max_spacing`` [rad-ish] in
    this window ([rad], [rad s⁻¹]).

    Pure and cheap: run it before any work. Bounds: 0 < ``tol``, and tol ≥ ``MIN_TOL_ULPS``
    (64) spacings of doubles at the window's largest coordinate (1.1e-13 for |θ| ≤ 3π), below
    which a bracket cannot be resolved; ``max_spacing`` ≥ ``MIN_MAX_SPACING`` (1e-4), below
    which the polyline outgrows the accuracy of the curve it joins (see the constant); and
    each side of the window ≥ ``MIN_WINDOW_TOLS`` (1000) tol, below which the located
    boundary is not resolved in it (a zoom narrower than 1e-9 at the default tol).
    """
    for name, value in (("tol", tol), ("max_spacing", max_spacing)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    theta_max = max(abs(float(x)) for x in theta_window)
    scale = max(theta_max, *(abs(float(x)) for x in theta_dot_window))
    need = MIN_TOL_ULPS * float(np.spacing(scale))
    if tol < need:
        where = "|θ|" if scale == theta_max else "|θ̇|"
        raise ValueError(f"tol = {tol:g} is below what double precision can resolve at "
                         f"{where} ≤ {scale:.3g} (needs ≥ {_round_up(need):.2g})")
    for axis, (lo, hi) in (("θ0", theta_window), ("θ̇0", theta_dot_window)):
        side = float(hi) - float(lo)
        if side < MIN_WINDOW_TOLS * tol:
            raise ValueError(
                f"tol = {tol:g} is too coarse for a window {side:.3g} wide in {axis}: a "
                f"boundary located to tol is resolved only in windows at least "
                f"{MIN_WINDOW_TOLS} tol = {MIN_WINDOW_TOLS * tol:.2g} wide (lower tol, down "
                f"to {_round_up(need):.2g} here, or widen the window)")
    if max_spacing < MIN_MAX_SPACING:
        raise ValueError(f"max_spacing = {max_spacing:g} is below {MIN_MAX_SPACING:g}: its "
                         "chord error max_spacing²/8 would fall below the curve's own accuracy "
                         f"(≈ 1e-9), at {1 / max_spacing:.0e} points per unit of length")
