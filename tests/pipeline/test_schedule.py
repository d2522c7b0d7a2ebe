"""The tile schedulers and the backend words: a word names a device and a scheduler."""

from __future__ import annotations

import pytest

from atlas.defaults import BACKEND_WORDS
from atlas.labels.backends import BACKENDS
from atlas.pipeline.schedule import SCHEDULERS, resolve


def test_resolve_splits_the_backend_word_into_device_and_scheduler():
    assert resolve("cpu") == (BACKENDS["cpu"], SCHEDULERS["local"])
    assert resolve("cuda") == (BACKENDS["cuda"], SCHEDULERS["local"])
    assert resolve("dask") == (BACKENDS["cpu"], SCHEDULERS["dask"])
    assert set(BACKEND_WORDS) == {"cpu", "cuda", "dask"}
    assert {s for _, s in BACKEND_WORDS.values()} == set(SCHEDULERS)
    assert {d for d, _ in BACKEND_WORDS.values()} == set(BACKENDS)
    with pytest.raises(ValueError, match="backend must be one of"):
        resolve("tpu")


class _TileRun:
    def __init__(self, parallel):
        self.parallel_tile_writes = parallel


class _Tiles:
    def __init__(self, parallel):
        self.tile_run = _TileRun(parallel)


def test_only_dask_workers_write_tiles_and_only_where_the_format_takes_parallel_writes():
    assert not SCHEDULERS["local"].worker_writes(_Tiles(True))
    assert SCHEDULERS["dask"].worker_writes(_Tiles(True))
    assert not SCHEDULERS["dask"].worker_writes(_Tiles(False))
