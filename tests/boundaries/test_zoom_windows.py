"""Zooms without torque into the k = 0 | 1 boundary and into the saddle (π, 0): widths 1 down
to 1e-9 (the checks: tests/boundaries/zoom_cases.py), and the refusal of narrower windows."""

from __future__ import annotations

import pytest

import atlas
from tests.boundaries.zoom_cases import cases, check_zoom


@pytest.mark.parametrize(("name", "width"), cases(["boundary", "saddle"]))
def test_a_zoom_traces_its_boundary_and_certifies_honestly(tmp_path, name, width):
    check_zoom(tmp_path, name, width)


def test_a_window_narrower_than_a_thousand_tol_is_refused(tmp_path):
    cfg = tmp_path / "narrow.yaml"
    cfg.write_text("""\
grid:
  theta0: {start: -2e-10, stop: 2e-10, num: 5}
  theta_dot0: {start: 2.4149382174, stop: 2.4149382178, num: 5}
""")
    with pytest.raises(ValueError, match=r"separatrices\.tol = 1e-12 is too coarse for a "
                                         r"window 4e-10 wide"):
        atlas.load_config(cfg)
