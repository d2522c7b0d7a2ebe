"""Zooms with torque τ = 0.3 into a boundary of the tilted wells and into the tilted saddle:
widths 1 down to 1e-9 (the checks: tests/boundaries/zoom_cases.py). A file of its own so
that the test workers share the zooms out."""

from __future__ import annotations

import pytest

from tests.boundaries.zoom_cases import cases, check_zoom


@pytest.mark.parametrize(("name", "width"), cases(["tilted boundary", "tilted saddle"]))
def test_a_tilted_zoom_traces_its_boundary_and_certifies_honestly(tmp_path, name, width):
    check_zoom(tmp_path, name, width)
