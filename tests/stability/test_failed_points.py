"""The failed-point path of a study (issue 43, 3), and points straddling the homoclinic torque.

A point whose exact boundaries fail (here made to, by a patched factory) is stored as failed:
``point_status`` 2, its values NaN, the ``failures`` attribute naming it and why; ``atlas
stability`` and ``atlas info`` say so in their summary; the other points are whole."""

from __future__ import annotations

import io
import json
from contextlib import redirect_stdout

import numpy as np
import pytest

from atlas.cli import main
from atlas.store.study import open_study
from tests.helpers import study_config

FAILING = 0.3


@pytest.fixture
def failing_factory(monkeypatch):
    """exact_boundaries raising, as a failed integration would, at torque FAILING."""
    from atlas.boundaries import exact

    real = exact.exact_boundaries

    def boundaries(pendulum, window, **kw):
        if pendulum.torque == FAILING:
            raise RuntimeError("a stable branch did not leave the band (planted)")
        return real(pendulum, window, **kw)

    monkeypatch.setattr(exact, "exact_boundaries", boundaries)


def _run(*args) -> tuple[int, str]:
    out = io.StringIO()
    with redirect_stdout(out):
        code = main([str(a) for a in args])
    return code, out.getvalue()


@pytest.mark.slow
def test_a_failed_point_is_stored_and_said(tmp_path, failing_factory):
    cfg = study_config(tmp_path / "s.yaml",
                       f"alpha: 0.1, omega0: 1.0, torque: [0.1, {FAILING}, 0.5]",
                       tmp_path / "s.h5")
    code, printed = _run("stability", cfg)
    assert code == 0
    assert "1 point(s) failed, values NaN (first at torque = 0.3)" in printed
    assert "failed: 0.1, 1, 0.3: the exact boundaries failed: a stable branch did not leave " \
           "the band (planted)" in printed
    ds = open_study(tmp_path / "s.h5")
    assert ds["point_status"].values.tolist() == [0, 2, 0]
    assert json.loads(ds.attrs["failures"]) == [
        "0.1, 1, 0.3: the exact boundaries failed: a stable branch did not leave the band "
        "(planted)"]
    failed = ds.sel(torque=FAILING)
    assert np.isnan(failed["running_stability"]) and np.all(np.isnan(failed["basin_stability"]))
    whole = ds.sel(torque=[0.1, 0.5])
    assert np.all(np.isfinite(whole["running_stability"]))
    code, info = _run("info", tmp_path / "s.h5")
    assert code == 0 and "1 point(s) failed" in info and "(planted)" in info


@pytest.mark.slow
def test_points_straddling_the_homoclinic_torque(tmp_path):
    """τ_c ± 1e-6 at α = 0.05 (τ_c = 0.1270088598, bSTAB's pendulum): both points exact, no
    running basin just below, a running basin just above (the cycle born at τ_c)."""
    tau_c = 0.12700885980
    cfg = study_config(tmp_path / "h.yaml",
                       f"alpha: 0.05, omega0: 1.0, torque: [{tau_c - 1e-6!r}, {tau_c + 1e-6!r}]",
                       tmp_path / "h.h5")
    assert _run("stability", cfg)[0] == 0
    ds = open_study(tmp_path / "h.h5")
    assert ds["point_status"].values.tolist() == [0, 0]
    below, above = ds["running_stability"].values
    assert below == 0.0 and above > 0.0
    assert float(ds["homoclinic_torque"]) == pytest.approx(tau_c, abs=1e-9)
    assert np.all(np.isfinite(ds["minimal_fatal_shock"].sel(k=0).values))
