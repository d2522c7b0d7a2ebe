"""``output: NAME.zarr``: the same atlas as the HDF5 file, also with Dask workers writing
their own tiles, and the same crash/resume behaviour."""

import numpy as np
import pytest
import xarray as xr

import atlas
from tests.helpers import crash_on_tile

pytestmark = pytest.mark.slow  # whole runs into Zarr

pytest.importorskip("zarr")
LABELS = ("attractor", "status", "t_trap", "boundary_distance", "basin_fraction",
          "basin_fraction_exact", "basin_fraction_grid_error_bound", "unresolved_fraction",
          "d_cert", "k")


def _root(tree):
    return tree.to_dataset(inherit=False)


@pytest.fixture
def cfg(small_config, tmp_path):
    return atlas.load_config(small_config(output=str(tmp_path / "small.zarr")))


def test_zarr_output_equals_the_hdf5_file(cfg, tmp_path, monkeypatch):
    with monkeypatch.context() as m:  # interrupted once: the resume writes the rest
        crash_on_tile(m, 3, KeyboardInterrupt())
        with pytest.raises(KeyboardInterrupt):
            atlas.run(cfg, quiet=True)
    assert (tmp_path / "small.zarr.partial" / "atlas.zarr").is_dir()
    with pytest.raises(atlas.InputFileError, match="partial"):
        atlas.open(tmp_path / "small.zarr.partial")
    z = atlas.run(cfg, quiet=True)
    h = atlas.run(cfg.model_copy(update={"output": tmp_path / "small.h5"}), quiet=True)
    for name in LABELS:
        np.testing.assert_array_equal(_root(z)[name].values, _root(h)[name].values)
    again = xr.open_datatree(tmp_path / "small.zarr", engine="zarr", mask_and_scale=False)
    root = _root(again)
    assert root["attractor"].dtype == np.int16 and root["status"].dtype == np.int8
    assert root["attractor"].attrs["_FillValue"] == -32768
    assert root.attrs["complete"] == 1 and set(again.children) == {"critical_points"}
    assert list(again["critical_points"]["kind"].values[1::2]) == ["attractor focus"] * 3
    assert not (tmp_path / "small.zarr.partial").exists()
    # run again over a finished store: replaced by an equal one
    atlas.run(cfg, quiet=True)
    np.testing.assert_array_equal(_root(atlas.open(cfg.output))["attractor"].values,
                                  root["attractor"].values)


def test_dask_workers_write_their_own_tiles(cfg, tmp_path, monkeypatch):
    """The client only records tiles: it never writes label arrays itself."""
    distributed = pytest.importorskip("distributed")
    from atlas.store.partial import TileStore

    def no_client_writes(*args, **kwargs):
        raise AssertionError("the client wrote a tile's arrays")

    recorded = []
    real_record = TileStore.record
    monkeypatch.setattr(TileStore, "write", no_client_writes)
    monkeypatch.setattr(TileStore, "record", lambda self, i, *a: (recorded.append(i),
                                                                   real_record(self, i, *a)))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster:
        dask_cfg = cfg.model_copy(update={"execution": cfg.execution.model_copy(
            update={"scheduler": cluster.scheduler_address})})
        z = atlas.run(dask_cfg, quiet=True, backend="dask")
    assert sorted(recorded) == [0, 1, 2, 3]
    monkeypatch.undo()
    h = atlas.run(cfg.model_copy(update={"output": tmp_path / "small.h5"}), quiet=True)
    for name in LABELS:
        np.testing.assert_array_equal(_root(z)[name].values, _root(h)[name].values)
