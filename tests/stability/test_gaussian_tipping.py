"""Gaussian-perturbation stability and tipping probabilities: Green's theorem against the
closed form on a rectangle, → 1 as σ → 0, the uniform fraction's 1/σ trend as σ grows, and
both against seeded Monte Carlo samples of the same exact basins
(:meth:`ExactBoundaries.side`), within 4 standard errors; tipping rows sum to 1."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ndtr

from atlas.boundaries.basins import RUNNING_SIDE
from atlas.boundaries.exact import exact_boundaries
from atlas.physics.pendulum import Pendulum
from atlas.stability.gaussian import gaussian_stability
from atlas.stability.polygons import BasinShape, basin_shape, window_basins
from atlas.stability.tipping import tipping_matrix


def test_green_on_a_rectangle_is_the_closed_form():
    """A rectangular 'basin' [a, b] × [c, d]: P = (Φ(b/σθ) − Φ(a/σθ))(Φ(d/σθ̇) − Φ(c/σθ̇))."""
    a, b, c, d = -0.3, 1.1, -0.7, 0.4
    shape = BasinShape(np.array([a, b, b, a]), np.array([c, c, d, d]), speed=50.0,
                       chord_error=0.0, reference_error=0.0, rest_theta=0.0)
    for s_theta, s_dot in ((0.5, 0.8), (2.0, 0.1)):
        value, _ = gaussian_stability(shape, s_theta, s_dot)
        exact = (ndtr(b / s_theta) - ndtr(a / s_theta)) * (ndtr(d / s_dot) - ndtr(c / s_dot))
        assert abs(value - exact) < 1e-13


@pytest.mark.slow
@pytest.mark.parametrize("alpha, torque, sigma", [(0.1, 0.0, 0.9), (0.05, 0.5, 0.6)])
def test_gaussian_against_monte_carlo(alpha, torque, sigma):
    p = Pendulum(alpha, 1.0, torque)
    window = ((-2 * math.pi, 2 * math.pi), (-12.0, 12.0))
    b = exact_boundaries(p, window)
    shape = basin_shape(b, 12.5 * sigma)
    assert gaussian_stability(shape, 1e-3, 1e-3)[0] == pytest.approx(1.0, abs=1e-12)
    value, error = gaussian_stability(shape, sigma, sigma)
    rng = np.random.default_rng(20250925)
    n = 40_000
    theta = p.rest_angle + sigma * rng.standard_normal(n)
    theta_dot = sigma * rng.standard_normal(n)
    inside = (np.abs(theta) < 2 * math.pi) & (np.abs(theta_dot) < 12.0)
    assert inside.all()
    hits = float(np.mean(b.side(theta, theta_dot) == 0))
    se = math.sqrt(hits * (1 - hits) / n)
    assert abs(value - hits) < 4 * se + error, (value, hits, se)
    assert 0.05 < value < 0.999  # a case where the boundary matters


@pytest.mark.slow
def test_gaussian_follows_the_uniform_fractions_trend_as_sigma_grows():
    """Far out, orbits lose about 4πα of speed a turn, so well 0's basin is one band of
    fixed height among ever more: its share of a box of half-width L falls as 1/L (the
    uniform fraction), and its Gaussian probability as 1/σ. Both fall monotonically, and
    their local log-log slopes tend to −1 together as σ grows (the uniform one over a box
    of ±3σ around the rest state)."""
    p = Pendulum(0.1, 1.0, 0.0)
    sigmas = (8.0, 16.0, 32.0)
    gauss, uniform = [], []
    for sigma in sigmas:
        half = 3.0 * sigma
        b = exact_boundaries(p, ((-half, half), (-half, half)))
        gauss.append(gaussian_stability(basin_shape(b, 12.5 * sigma), sigma, sigma)[0])
        uniform.append(float(b.areas.fraction[list(b.areas.k).index(0)]))
    for values in (gauss, uniform):
        assert values[0] > values[1] > values[2] > 0.0
        slopes = -np.diff(np.log(values)) / np.diff(np.log(sigmas))
        assert abs(slopes[1] - 1.0) < abs(slopes[0] - 1.0) and abs(slopes[1] - 1.0) < 0.2, \
            slopes
    assert abs(gaussian_stability(basin_shape(b, 12.5 * 0.01), 0.01, 0.01)[0] - 1.0) < 1e-12


@pytest.mark.slow
@pytest.mark.parametrize("before, after", [((0.1, 0.0), (0.15, 0.0)),
                                           ((0.05, 0.1), (0.05, 0.2))])
def test_tipping_against_monte_carlo(before, after):
    """Consecutive points (α, τ): a change of damping (strips to strips), and a torque step
    across the homoclinic torque (≈ 0.127: the running basin appears)."""
    window = ((-math.pi, math.pi), (-4.0, 4.0))
    bounds = [exact_boundaries(Pendulum(a, 1.0, t), window) for a, t in (before, after)]
    ks = np.union1d(bounds[0].areas.k, bounds[1].areas.k)
    labels = np.append(ks, RUNNING_SIDE)
    basins = [window_basins(basin_shape(b), window, b.areas.k, b.running_possible)
              for b in bounds]
    matrix = tipping_matrix(basins[0], basins[1], labels)
    rows = np.isfinite(matrix).all(axis=1)
    assert rows.sum() >= 2
    assert np.allclose(matrix[rows].sum(axis=1), 1.0, atol=1e-6)
    rng = np.random.default_rng(7)
    n = 40_000
    theta = rng.uniform(*window[0], n)
    theta_dot = rng.uniform(*window[1], n)
    side0, side1 = (b.side(theta, theta_dot) for b in bounds)
    for i, a in enumerate(labels):
        mask = side0 == a
        if mask.sum() < 300:
            continue
        for j, target in enumerate(labels):
            hits = float(np.mean(side1[mask] == target))
            se = math.sqrt(max(hits * (1 - hits), 1.0 / mask.sum()) / mask.sum())
            assert abs(matrix[i, j] - hits) < 4 * se + 1e-6, (a, target, matrix[i, j], hits)
    if after[1] > 0.127:  # wells tip into the new running basin
        assert matrix[list(labels).index(0), -1] > 0.0
