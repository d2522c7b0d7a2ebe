"""Every bifurcation inside a study's range is located, stored, printed and drawn, whichever
parameter the study sweeps: the homoclinic, saddle-node and focus–node values read along α, ω0
and τ (atlas.stability.bifurcations), each checked by a method of its own (τ_c's scaling
law, the rest state's eigenvalues, the critical points' existence)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from atlas.cli import main
from atlas.physics.pendulum import Pendulum
from atlas.stability import bifurcations as bif
from atlas.store.study import open_study
from tests.helpers import study_config

pytestmark = pytest.mark.slow  # runs the CLI in-process, computes a study

ALPHA, TORQUE = 0.1, 0.3


def _is_focus(alpha, omega0, torque) -> bool:
    """The rest state's eigenvalues are complex: a focus."""
    return Pendulum(alpha=alpha, omega0=omega0, torque=torque).attractor_eigenvalues()[0].imag != 0


def _drawn(ds, axis) -> tuple[list[float], list[float], list[str]]:
    """The x of every vertical line the study's 1-D stability figure draws, every value its
    labels name ("name = value", several joined by "; " on one line) and the labels."""
    from matplotlib.figure import Figure

    from atlas.views.study_plot import _stability_curves

    ax = Figure().add_subplot()
    _stability_curves(ds, axis)(ax)
    lines = [float(line.get_xdata()[0]) for line in ax.lines
             if len(set(map(float, line.get_xdata()))) == 1 and len(line.get_xdata()) == 2]
    texts = [t.get_text() for t in ax.texts]
    named = [float(part.rsplit(" = ", 1)[1]) for text in texts for part in text.split("; ")]
    return lines, named, texts


def _shown(value, lines, named, span) -> bool:
    """``value`` is named (to the label's 10 digits) and a line lies within 1 % of the
    range ``span`` of it (the one line of bifurcations that coincide on the page)."""
    return (any(math.isclose(value, v, rel_tol=1e-9) for v in named)
            and min(abs(value - x) for x in lines) < 0.01 * span)


@pytest.fixture(scope="module")
def over_omega0(tmp_path_factory):
    """A study over ω0 from 0.5 to 1.5 at α = 0.1, τ = 0.3: the saddle-node √τ ≈ 0.548, the
    focus–node (α⁴ + τ²)^(1/4) just above it and the homoclinic ω0_c ≈ 1.2 all inside."""
    tmp = tmp_path_factory.mktemp("omega0")
    cfg = study_config(tmp / "w.yaml", f"alpha: {ALPHA}, omega0: {{start: 0.5, stop: 1.5, "
                       f"num: 5}}, torque: {TORQUE}", tmp / "w.h5")
    assert main(["stability", str(cfg)]) == 0
    return tmp / "w.h5"


def test_a_study_over_omega0_locates_all_three(over_omega0):
    ds = open_study(over_omega0)
    omega_c = float(ds["homoclinic_omega0"])
    # τ_c(α, ω0) = ω0² τ_c(α/ω0, 1) (t → ω0 t): another frequency and damping than located
    scaled = omega_c**2 * bif.homoclinic_torque(ALPHA / omega_c, 1.0)
    assert abs(scaled - TORQUE) < 1e-10 * TORQUE
    assert 0.5 < omega_c < 1.5
    sn = float(ds["saddle_node_omega0"])
    assert Pendulum(alpha=ALPHA, omega0=sn * (1 + 1e-12), torque=TORQUE).has_rest_states
    assert not Pendulum(alpha=ALPHA, omega0=sn * (1 - 1e-12), torque=TORQUE).has_rest_states
    fn = float(ds["focus_node_omega0"])
    assert sn < fn < 1.5
    assert _is_focus(ALPHA, fn * (1 + 1e-9), TORQUE)
    assert not _is_focus(ALPHA, fn * (1 - 1e-9), TORQUE)


def test_a_study_over_omega0_prints_and_draws_them(over_omega0, capsys):
    ds = open_study(over_omega0)
    assert main(["info", str(over_omega0)]) == 0
    out = capsys.readouterr().out
    lines, named, texts = _drawn(ds, "omega0")
    for name in ("homoclinic_omega0", "saddle_node_omega0", "focus_node_omega0"):
        value = float(ds[name])
        assert f"bifurcation {name}: omega0 = {value:.12g}" in out
        assert _shown(value, lines, named, 1.0), (name, value, lines, texts)
    # the saddle-node √τ and the focus–node (α⁴ + τ²)^(1/4), 1.5e-4 apart: one line
    assert len(lines) == len(texts) == 2, texts


def test_a_study_over_torque_marks_the_focus_node_torque(tmp_path, capsys):
    """At α = 0.2, ω0 = 1 the rest state turns node at τ = √(1 − α⁴) ≈ 0.9992, inside a
    study up to 1 (with the saddle-node) — as the eigenvalues say."""
    cfg = study_config(tmp_path / "t.yaml", "alpha: 0.2, omega0: 1.0, torque: [0.0, 0.5, 1.0]",
                       tmp_path / "t.h5")
    assert main(["stability", str(cfg)]) == 0
    ds = open_study(tmp_path / "t.h5")
    fn = float(ds["focus_node_torque"])
    assert _is_focus(0.2, 1.0, fn * (1 - 1e-9)) and not _is_focus(0.2, 1.0, fn * (1 + 1e-9))
    lines, named, texts = _drawn(ds, "torque")
    for value in (fn, float(ds["saddle_node_torque"]), float(ds["homoclinic_torque"])):
        assert _shown(value, lines, named, 1.0), (value, lines, texts)
    # the two a hair apart (0.9992 and 1) are one line, whose one label names both
    assert len(lines) == 2 and any("focus → node τ" in t and "saddle-node τ" in t
                                   for t in texts), texts
    assert main(["info", str(tmp_path / "t.h5")]) == 0
    assert f"focus_node_torque: torque = {fn:.12g}" in capsys.readouterr().out


def test_the_closed_forms_agree_with_each_other():
    """The focus–node surface α⁴ + τ² = ω0⁴ read along each axis gives the same point."""
    for omega0, torque in [(1.0, 0.5), (2.0, 3.9), (1.1, 0.2)]:
        a = bif.focus_node_damping(omega0, torque)
        assert math.isclose(bif.focus_node_torque(a, omega0), abs(torque), rel_tol=1e-12)
        assert math.isclose(bif.focus_node_omega0(a, torque), omega0, rel_tol=1e-12)
    assert math.isnan(bif.focus_node_torque(1.2, 1.0))
    assert math.isnan(bif.saddle_node_omega0(0.0))
    assert bif.homoclinic_omega0(0.1, 0.0, 0.5, 1.5) is None


def test_a_map_draws_each_bifurcation_once_where_it_lies(tmp_path):
    """An ω0 × τ map (its focus–node curve was missing before it was read along τ): the
    homoclinic, saddle-node and focus–node curves each drawn once, as the stored values; an
    α × ω0 map without torque has no homoclinic or saddle-node curve to draw (NaN), and
    shows none in its legend."""
    from matplotlib.figure import Figure

    from atlas.views.study_plot import _stability_map

    def legend(name, pendulum):
        cfg = study_config(tmp_path / f"{name}.yaml", pendulum, tmp_path / f"{name}.h5")
        assert main(["stability", str(cfg)]) == 0
        ds = open_study(tmp_path / f"{name}.h5")
        ax = Figure().add_subplot()
        y, x = [d for d in ("alpha", "omega0", "torque") if d in ds.dims]
        _stability_map(ds, x, y)(ax)
        drawn = [line for line in ax.lines if line.get_color() != "white"]
        labels = [line.get_label() for line in drawn]
        assert len(labels) == len(set(labels)), labels  # each bifurcation drawn once
        return ds, dict(zip(labels, drawn))

    ds, lines = legend("wt", "alpha: 0.1, omega0: {start: 0.8, stop: 1.2, num: 3}, "
                             "torque: {start: 0.2, stop: 0.9, num: 3}")
    assert sorted(lines) == ["focus → node τ", "homoclinic τ_c", "saddle-node τ = ω0²"]
    # torque across, ω0 up: each a torque over the ω0 values
    for label, name in (("focus → node τ", "focus_node_torque"),
                        ("homoclinic τ_c", "homoclinic_torque"),
                        ("saddle-node τ = ω0²", "saddle_node_torque")):
        np.testing.assert_array_equal(lines[label].get_xdata(), ds[name].values)
        np.testing.assert_array_equal(lines[label].get_ydata(), ds["omega0"].values)
    # α × τ: the focus–node read along α over τ, (1 − τ²)^(1/4), has no sample inside
    # α ∈ [0.3, 0.5] on these torques; read along τ over α, √(1 − α⁴), every one is inside
    ds, lines = legend("at", "alpha: {start: 0.3, stop: 0.5, num: 3}, omega0: 1.0, "
                             "torque: {start: 0.0, stop: 1.2, num: 4}")
    np.testing.assert_array_equal(lines["focus → node τ"].get_xdata(),
                                  ds["focus_node_torque"].values)
    np.testing.assert_array_equal(lines["focus → node τ"].get_ydata(), ds["alpha"].values)
    assert "focus → node α" not in lines
    _, lines = legend("aw", "alpha: {start: 0.5, stop: 1.5, num: 2}, "
                            "omega0: {start: 0.8, stop: 1.2, num: 2}, torque: 0.0")
    assert sorted(lines) == ["focus → node α"]
