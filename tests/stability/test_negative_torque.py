"""Negative torque at the stability layer (issue 43, 6): the mirror (θ, θ̇, τ) → (−θ, −θ̇, −τ)
maps the pendulum at −τ onto the one at τ and well k onto well −k, so on a window symmetric
about the origin every number of a study point at −τ equals the mirrored number at τ: the
basin stability of each well (the tongue with a running cycle, the strip without), the
running stability, both minimal fatal shocks (their feet mirrored), the Gaussian stability
with σθ ≠ σθ̇, and the tipping probabilities of a 1-D study over ±τ."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.stability.study import StudySettings, compute_point

WINDOW = ((-3.0, 3.0), (-4.0, 4.0))  # symmetric under θ → −θ, θ̇ → −θ̇


@pytest.mark.slow
@pytest.mark.parametrize("alpha, torque", [(0.05, 0.5), (0.2, 0.3), (0.1, 0.9)])
def test_a_point_at_minus_torque_is_the_mirror_of_the_point_at_torque(alpha, torque):
    settings = StudySettings(window=WINDOW, sigma=(0.4, 0.9))
    plus = compute_point(alpha, 1.0, torque, settings)
    minus = compute_point(alpha, 1.0, -torque, settings)
    tol = 1e-10
    assert sorted((-minus.k).tolist()) == sorted(plus.k.tolist())
    mirrored = dict(zip((-minus.k).tolist(), minus.fraction))
    for k, f, e in zip(plus.k.tolist(), plus.fraction, plus.error):
        assert mirrored[k] == pytest.approx(f, abs=e + tol), k
    assert minus.running == pytest.approx(plus.running, abs=plus.running_error + tol)
    # well 0's rest state (θ*, 0) mirrors to (−θ*, 0): the shock's distance is the same, its
    # foot mirrored
    assert minus.shock.distance == pytest.approx(plus.shock.distance, abs=1e-9)
    assert minus.shock.theta == pytest.approx(-plus.shock.theta, abs=1e-8)
    assert minus.shock.theta_dot == pytest.approx(-plus.shock.theta_dot, abs=1e-8)
    if math.isnan(plus.running_shock.distance):
        assert math.isnan(minus.running_shock.distance)
    else:
        assert minus.running_shock.distance == pytest.approx(plus.running_shock.distance,
                                                             abs=1e-8)
        assert minus.running_shock.theta_dot == pytest.approx(
            -plus.running_shock.theta_dot, abs=1e-6)
    (p_plus, e_plus), (p_minus, e_minus) = plus.gaussian, minus.gaussian
    assert 0.0 < p_plus < 1.0
    assert p_minus == pytest.approx(p_plus, abs=e_plus + e_minus + tol)


@pytest.mark.slow
def test_tipping_over_minus_torque_mirrors_tipping_over_torque(tmp_path):
    """The basins' overlaps between consecutive points of a 1-D study over −τ equal those
    over τ mirrored: the overlap of basin k at τ_s with basin m at τ_(s+1) (tipping
    probability × the source's basin stability) is that of −m at −τ_(s+1) with −k at −τ_s,
    the other study's step taken the other way (the running basin stays itself)."""
    from atlas.commands.stability import run_study
    from atlas.store.study import RUNNING_BASIN, open_study
    from tests.helpers import study_config

    torques = [0.1, 0.3, 0.5]
    studies = {}
    for name, values in (("plus", torques), ("minus", [-t for t in torques[::-1]])):
        cfg = study_config(tmp_path / f"{name}.yaml", f"alpha: 0.1, omega0: 1.0, torque: {values}",
                           tmp_path / f"{name}.h5", extra="stability: {tipping: true}\n")
        studies[name] = open_study(run_study(cfg)[1])

    def overlap(ds, step: int, source: int, target: int) -> float:
        p = float(ds["tipping_probability"].sel(step=step, source=source, target=target))
        at = ds.isel(torque=step)
        share = (float(at["running_stability"]) if source == RUNNING_BASIN else
                 float(at["basin_stability"].sel(k=source)) if source in ds["k"] else 0.0)
        return p * share if share > 0 else 0.0

    def mirror(k: int) -> int:
        return k if k == RUNNING_BASIN else -k

    plus, minus = studies["plus"], studies["minus"]
    steps = plus.sizes["step"]
    compared = 0
    for s in range(steps):
        for k in plus["source"].values.tolist():
            for m in plus["target"].values.tolist():
                if mirror(m) not in minus["source"] or mirror(k) not in minus["target"]:
                    continue
                a = overlap(plus, s, k, m)
                b = overlap(minus, steps - 1 - s, mirror(m), mirror(k))
                if np.isnan(a) and np.isnan(b):
                    continue
                assert b == pytest.approx(a, abs=1e-9), (s, k, m)
                compared += a > 1e-3
    assert compared >= 4  # real overlaps were compared, not only zeros
