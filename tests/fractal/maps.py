"""Two maps whose basins Attractors.jl's tests measure, written here in numpy (independent of
atlas.fractal): the Grebogi map of Grebogi, McDonald, Ott & Yorke, *Phys. Lett. A* 99, 415
(1983), and Newton's method for z³ = 1. Their reference values are Attractors.jl's
test/basins/uncertainty_tests.jl (the bounds its tests assert)."""

from __future__ import annotations

import math

import numpy as np

#: The Grebogi map's parameters (Attractors.jl's test: a, b, J0).
A, B, J0 = 1.32, 0.9, 0.3


def grebogi_step(theta, x):
    """θ' = θ + a sin 2θ − b sin 4θ − x sin θ (mod 2π), x' = −J0 cos θ."""
    return (np.mod(theta + A * np.sin(2 * theta) - B * np.sin(4 * theta) - x * np.sin(theta),
                   2 * math.pi),
            -J0 * np.cos(theta))


def grebogi_label(theta, x, steps: int = 200, split: bool = True):
    """The attractor that (θ, x) reaches: the fixed points (0, −J0) and (π, J0), both stable
    (multipliers 0.34 and 0). θ is taken mod 2π on [0, 2π), so an orbit reaches θ = 0 from
    above or θ = 2π from below (the map's slope there is 0.34 > 0: it never crosses): with
    ``split`` those are two labels (0 and 2, π is 1), as a recurrence finder on the cells of
    [0, 2π] sees them (Attractors.jl); without, one. −1 where no fixed point is within 1e-3
    after ``steps``."""
    theta, x = np.array(theta, float), np.array(x, float)
    for _ in range(steps):
        theta, x = grebogi_step(theta, x)
    near0 = np.minimum(theta, 2 * math.pi - theta) < 1e-3
    out = np.full(theta.shape, -1, np.int64)
    out[near0 & (theta < math.pi)] = 0
    out[near0 & (theta > math.pi)] = 2 if split else 0
    out[np.abs(theta - math.pi) < 1e-3] = 1
    out[np.abs(x - np.where(out == 1, J0, -J0)) > 1e-3] = -1
    return out


def grebogi_basins(n: int, split: bool = True) -> np.ndarray:
    """The labels on Attractors.jl's grid: θ = range(0, 2π, n) along the first axis (rows),
    x = range(−0.5, 0.5, n) along the second."""
    theta = np.linspace(0, 2 * math.pi, n)[:, None]
    x = np.linspace(-0.5, 0.5, n)[None, :]
    return grebogi_label(*np.broadcast_arrays(theta, x), split=split)


def newton_basins(n: int, steps: int = 100) -> np.ndarray:
    """Basins of Newton's method for z³ − 1 on range(−1, 1, n)²: the index (0, 1, 2) of the
    cube root of unity reached, −1 where none is within 1e-6."""
    re = np.linspace(-1, 1, n)
    z = re[:, None] + 1j * re[None, :]
    with np.errstate(all="ignore"):
        for _ in range(steps):
            z = z - (z ** 3 - 1) / (3 * z ** 2)
    roots = np.exp(2j * math.pi * np.arange(3) / 3)
    d = np.abs(z[..., None] - roots)
    out = np.argmin(d, axis=-1)
    out[~(np.min(d, axis=-1) < 1e-6)] = -1
    return out
