"""pytest fixtures shared by the test modules (plain helpers are in ``tests/helpers.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.helpers import SMALL, write_config


@pytest.fixture
def small_config(tmp_path):
    """A 24 × 16 default-window config writing into tmp_path (separatrices off)."""

    def make(sep: bool = False, name: str = "small.yaml", output: str | None = None) -> Path:
        out = output or str(tmp_path / "small.h5")
        return write_config(tmp_path / name, SMALL.format(sep=str(sep).lower(), output=out))

    return make
