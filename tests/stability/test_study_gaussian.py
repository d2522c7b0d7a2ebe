"""The Gaussian stability inside a study (issue 43, 5): compute_point with σθ ≠ σθ̇ and, with
torque, a window whose θ̇ band the Gaussian's reach exceeds (the boundaries integrated again
over the Gaussian's box), against a seeded Monte Carlo of the same perturbations classified by
the exact boundaries' sides (ray parity over the curves: not Green's theorem); the same with
σθ and σθ̇ swapped is far from it, so a swap inside the study would fail."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.boundaries.exact import exact_boundaries
from atlas.physics.pendulum import Pendulum
from atlas.stability.study import StudySettings, compute_point

N = 200_000


def _monte_carlo(p: Pendulum, s_theta: float, s_dot: float, seed: int) -> tuple[float, float]:
    """(share of N Gaussian perturbations of well 0's rest state that stay in well 0, its
    standard error), classified on exact boundaries built over a box wider than the samples."""
    rng = np.random.default_rng(seed)
    theta = p.rest_angle + s_theta * rng.standard_normal(N)
    theta_dot = s_dot * rng.standard_normal(N)
    reach = 6.0
    b = exact_boundaries(p, ((p.rest_angle - reach * s_theta, p.rest_angle + reach * s_theta),
                             (-reach * s_dot, reach * s_dot)))
    inside = (np.abs(theta - p.rest_angle) < reach * s_theta) & (np.abs(theta_dot) < reach * s_dot)
    share = float(np.mean(inside & (b.side(theta, theta_dot) == 0)))
    return share, math.sqrt(share * (1.0 - share) / N)


@pytest.mark.slow
@pytest.mark.parametrize("alpha, torque", [(0.1, 0.0), (0.05, 0.3)])
def test_the_studys_gaussian_stability_is_the_monte_carlo_one(alpha, torque):
    s_theta, s_dot = 0.5, 1.4
    window = ((-1.0, 1.0), (-1.0, 1.0))  # REACH·σθ̇ ≫ 1: the band is integrated again
    point = compute_point(alpha, 1.0, torque, StudySettings(window=window,
                                                            sigma=(s_theta, s_dot)))
    got, error = point.gaussian
    p = Pendulum(alpha, 1.0, torque)
    share, se = _monte_carlo(p, s_theta, s_dot, seed=1)
    assert abs(got - share) <= 4 * se + error, (got, share, se)
    swapped, _ = _monte_carlo(p, s_dot, s_theta, seed=2)
    assert abs(swapped - got) > 10 * se  # a swap of σθ and σθ̇ is seen
