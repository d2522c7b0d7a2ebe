"""pytest fixtures shared by the test modules (plain helpers are in ``tests/helpers.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.helpers import SMALL, SWING, small_atlas, write_config


@pytest.fixture
def small_config(tmp_path):
    """A 24 × 16 default-window config writing into tmp_path (separatrices off)."""

    def make(sep: bool = False, name: str = "small.yaml", output: str | None = None) -> Path:
        out = output or str(tmp_path / "small.h5")
        return write_config(tmp_path / name, SMALL.format(sep=str(sep).lower(), output=out))

    return make


@pytest.fixture(scope="session")
def swing_atlas(tmp_path_factory) -> Path:
    """A small atlas file of the bistable swing pendulum (48 × 40 orbits of the swing window,
    t_max = 200 s, separatrices on: tilted wells, the running cycle and its barrier), built
    once for every module that reads one. Read it only: write anything else elsewhere."""
    tmp = tmp_path_factory.mktemp("swing")
    small_atlas(tmp, "swing", SWING, num=(48, 40), t_max=200.0)
    return tmp / "swing.h5"


@pytest.fixture(scope="session")
def small_atlas_file(tmp_path_factory) -> Path:
    """The atlas file of the small config (24 × 16 orbits of the default window, separatrices
    off, tiles of 100 orbits: 4 rows each), computed once in-process for the tests that only
    read one. Read it only: copy it to tmp_path to change it."""
    import atlas

    tmp = tmp_path_factory.mktemp("small")
    cfg = write_config(tmp / "small.yaml", SMALL.format(sep="false", output=tmp / "small.h5"))
    atlas.run(atlas.load_config(cfg), quiet=True)
    return tmp / "small.h5"
