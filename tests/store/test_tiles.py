"""The partial-run store: tile files are whole or absent, identity is checked before anything
is touched, stored chunks are exactly HDF5's own encoding, damaged tiles are redone."""

import h5py
import numpy as np
import pytest

import atlas
from atlas.pipeline.config import config_hash
from atlas.pipeline.identity import run_identity
from atlas.pipeline.sweep import layout_of
from atlas.store.hdf5 import encode_chunk
from atlas.store.partial import IdentityMismatch, TileStore, partial_path
from tests.helpers import REPO


@pytest.fixture
def cfg(small_config):
    return atlas.load_config(small_config())


@pytest.mark.parametrize("dtype, fill", [(np.int16, -32768), (np.int8, 0),
                                         (np.float32, np.float32(np.nan))])
def test_encoded_chunks_are_hdf5s_own(tmp_path, dtype, fill):
    """A chunk written by HDF5 itself (shuffle + gzip 4), read back raw, equals
    encode_chunk's bytes, also for an edge chunk (3 of 4 rows)."""
    rng = np.random.default_rng(1)
    values = rng.integers(-5, 5, size=(7, 24)).astype(dtype)
    with h5py.File(tmp_path / "ref.h5", "w") as f:
        d = f.create_dataset("v", data=values, chunks=(4, 24), compression="gzip",
                             compression_opts=4, shuffle=True, fillvalue=fill)
        for row in (0, 4):
            mask, raw = d.id.read_direct_chunk((row, 0))
            assert mask == 0
            assert raw == encode_chunk(values[row:row + 4], 4, fill)


def test_identity_decides_what_a_run_continues(cfg):
    same = run_identity(cfg, "cpu")
    assert run_identity(cfg, "dask") == same  # dask runs the CPU kernels
    assert run_identity(cfg, "cuda") != same
    other = cfg.model_copy(update={"execution": cfg.execution.model_copy(
        update={"tile_orbits": 7})})
    assert run_identity(other, "cpu") == same
    other = cfg.model_copy(update={"integrator": cfg.integrator.model_copy(
        update={"dt": 0.02})})
    assert run_identity(other, "cpu") != same
    other = cfg.model_copy(update={"integrator": cfg.integrator.model_copy(
        update={"method": "rk4-trigfree"})})
    assert run_identity(other, "cpu") != same and config_hash(other) != config_hash(cfg)
    # with the default method, identity and hash are those of the versions before the keys
    # (method; and check_radians, stability and model, which change no pendulum's result)
    # (so their partial runs continue and their files' hashes stay comparable)
    assert "method" not in same["integrator"] and cfg.integrator.method == "rk4"
    import hashlib
    import json

    before = cfg.model_dump(mode="json", exclude={"output", "execution", "name", "stability",
                                                  "check_radians", "model"})
    del before["integrator"]["method"]
    assert config_hash(cfg) == hashlib.sha256(
        json.dumps(before, sort_keys=True).encode()).hexdigest()[:16]
    # the hash atlas recorded for the shipped default config before the key existed
    assert config_hash(atlas.load_config(REPO / "configs" / "default.yaml")) \
        == "2f968ecadc4c3325"
    # enabled separatrices measure d_cert, which decides the tiles' certified statuses;
    # while they are off their settings change nothing
    sep = cfg.separatrices
    assert not sep.enabled
    other = cfg.model_copy(update={"separatrices": sep.model_copy(update={"tol": 1e-10})})
    assert run_identity(other, "cpu") == same
    on = cfg.model_copy(update={"separatrices": sep.model_copy(update={"enabled": True})})
    finer = on.model_copy(update={"separatrices": on.separatrices.model_copy(
        update={"tol": 1e-10})})
    assert len({run_identity(c, "cpu")["separatrices"].__repr__()
                for c in (cfg, on, finer)}) == 3


def test_identity_is_checked_before_anything_is_touched(cfg):
    path = partial_path(cfg.output)
    store = TileStore.create(path, layout_of(cfg), run_identity(cfg, "cpu"), {})
    leftover = path / "tiles" / ".0000003.npz.123.tmp"
    leftover.write_bytes(b"half a tile")
    with pytest.raises(IdentityMismatch) as err:
        TileStore.open(path, run_identity(cfg, "cuda"))
    assert err.value.differs == ["kernels"]
    assert leftover.exists()  # untouched by a refused open
    again = TileStore.open(path, run_identity(cfg, "cpu"))
    assert not leftover.exists() and again.done().size == 0 and store.todo().size == 4


@pytest.mark.slow
def test_a_damaged_tile_is_set_aside_and_computed_again(cfg):
    tree = atlas.run(cfg, quiet=True)
    clean = tree["attractor"].values.copy()
    from tests.helpers import crash_on_tile

    mp = pytest.MonkeyPatch()
    crash_on_tile(mp, 4, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        atlas.run(cfg, quiet=True)
    mp.undo()
    path = partial_path(cfg.output)
    tile = path / "tiles" / "0000001.npz"
    tile.write_bytes(tile.read_bytes()[:-40])  # a tile file corrupted on disk
    again = atlas.run(cfg, quiet=True)
    np.testing.assert_array_equal(again["attractor"].values, clean)
    assert not path.exists()


def test_tile_write_is_atomic(cfg, monkeypatch):
    """A write that dies half-way leaves no tile file, only a temporary one (cleared later)."""
    path = partial_path(cfg.output)
    store = TileStore.create(path, layout_of(cfg), run_identity(cfg, "cpu"), {})
    values = {"attractor": np.zeros((4, 24), np.int16), "status": np.zeros((4, 24), np.int8),
              "t_trap": np.zeros((4, 24), np.float32),
              "boundary_distance": np.ones((4, 24), np.float32)}
    tally = {"k0": np.int64(0), "count": np.array([96])}

    def dies(fh, **arrays):
        fh.write(b"PK half")
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez", dies)
    with pytest.raises(KeyboardInterrupt):
        store.write(2, values, tally)
    assert store.done().size == 0
    monkeypatch.undo()
    store.write(2, values, tally)
    assert list(store.done()) == [2] and store.read_tile(2).tally["count"].tolist() == [96]


@pytest.mark.slow
def test_an_interrupted_removal_never_leaves_half_a_partial_run(cfg, monkeypatch):
    """Killed while deleting the finished run's tiles (after the output is in place): the
    partial folder was renamed away first, so the next run neither finds half a partial run
    (no manifest) nor refuses; it clears the leftover."""
    from atlas.store import partial as tiles

    real = tiles.shutil.rmtree

    def dies_half_way(path, *args, **kwargs):
        if ".partial" in path.name and (path / "manifest.json").exists():
            (path / "manifest.json").unlink()  # rmtree got as far as the manifest
            raise KeyboardInterrupt
        real(path, *args, **kwargs)

    monkeypatch.setattr(tiles.shutil, "rmtree", dies_half_way)
    with pytest.raises(KeyboardInterrupt):
        atlas.run(cfg, quiet=True)
    monkeypatch.undo()
    assert atlas.open(cfg.output).attrs["complete"] == 1
    assert not partial_path(cfg.output).exists()
    atlas.run(cfg, quiet=True)
    assert sorted(p.name for p in cfg.output.parent.iterdir() if "small.h5" in p.name) == [
        "small.h5"]
