"""bSTAB's published T-sweep of the constant-torque pendulum (M. Stender and N. Hoffmann,
"bSTAB: an open-source software for computing the basin stability of multi-stable dynamical
systems", Nonlinear Dynamics 107, 1451–1468, 2022, doi:10.1007/s11071-021-06786-5): θ̈ =
T − sin θ − 0.1θ̇ (α = 0.05, ω0 = 1) on the window θ ∈ [−5π/6, 7π/6], θ̇ ∈ [−10, 10] for every
T, N = 10,000 uniform samples per T. Their fixed-point share S_B(FP) is atlas's basin
stability summed over the rest states; every published entry lies within 3 of its standard
errors √(S(1 − S)/N) of atlas's exact value (the entries of 1 exactly: to 1e-10)."""

from __future__ import annotations

import math

import pytest

from atlas.stability.study import StudySettings, compute_points

pytestmark = pytest.mark.slow  # 21 tilted parameter points

N = 10_000
#: (T, S_B(FP)) as published (the running cycle first appears between T = 0.11 and 0.16).
PUBLISHED = [(0.01, 1.0), (0.06, 1.0), (0.11, 1.0), (0.16, 0.483), (0.21, 0.3967),
             (0.26, 0.3268), (0.31, 0.2756), (0.36, 0.238), (0.41, 0.2065), (0.46, 0.1703),
             (0.51, 0.147), (0.56, 0.1279), (0.61, 0.1034), (0.66, 0.0839), (0.71, 0.0653),
             (0.76, 0.0545), (0.81, 0.0391), (0.86, 0.0244), (0.91, 0.0172), (0.96, 0.0071)]


def test_the_published_t_sweep():
    window = ((-5 * math.pi / 6, 7 * math.pi / 6), (-10.0, 10.0))
    results = compute_points([(0.05, 1.0, t) for t, _ in PUBLISHED], StudySettings(window))
    for (torque, published), r in zip(PUBLISHED, results):
        assert r.status == 0, r.message
        fp = float(r.fraction.sum())
        assert abs(fp + r.running - 1.0) < 1e-9
        se = math.sqrt(published * (1 - published) / N)
        assert abs(fp - published) <= max(3 * se, 1e-10), (torque, fp, published, se)
