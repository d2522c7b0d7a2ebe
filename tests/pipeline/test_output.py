"""The output-path policy (atlas.pipeline.output): what a run may write over, and where it
cannot write, decided before anything is made."""

import h5py
import numpy as np
import pytest

from atlas.errors import AtlasError, OutputInTheWay
from atlas.layout import Layout
from atlas.pipeline.output import check_output_path, check_output_target
from atlas.store.schema import SCHEMA


def _layout(n=4, alphas=1) -> Layout:
    return Layout(x0=np.linspace(-1, 1, n), v0=np.linspace(-1, 1, n),
                  parameters={"alpha": np.linspace(0.1, 1, alphas), "omega0": np.array([1.0]),
                              "torque": np.array([0.0])},
                  swept=("alpha",) if alphas > 1 else (), rows_per_tile=2)


def _atlas_like(path):
    with h5py.File(path, "w") as f:
        for name in ("attractor", "status", "t_trap"):
            f[name] = np.zeros(2)
        f.attrs["atlas_schema"] = SCHEMA


def test_what_a_run_may_write_over(tmp_path):
    config = tmp_path / "c.yaml"
    config.write_text("name: c\n")
    with pytest.raises(OutputInTheWay, match="the config file being run"):
        check_output_target(config, config, force=True)
    foreign = tmp_path / "foreign.h5"
    foreign.write_text("someone's notes")
    with pytest.raises(OutputInTheWay, match="an existing file that atlas did not write"):
        check_output_target(foreign, config)
    check_output_target(foreign, config, force=True)
    ours = tmp_path / "ours.h5"
    _atlas_like(ours)
    check_output_target(ours, config)  # an atlas file: run again over it
    check_output_target(tmp_path / "new.h5", config)
    store = tmp_path / "foreign.zarr"
    store.mkdir()
    (store / "zarr.json").write_text('{"zarr_format": 3, "node_type": "group"}')
    pytest.importorskip("zarr")
    with pytest.raises(OutputInTheWay, match="Zarr store that atlas did not write"):
        check_output_target(store, config)


def test_where_a_run_cannot_write(tmp_path):
    layout = _layout()
    check_output_path(tmp_path / "out.h5", layout)
    check_output_path(tmp_path / "deeper" / "out.zarr", layout)
    with pytest.raises(AtlasError, match="the output path is a directory"):
        check_output_path(tmp_path, layout)
    store = tmp_path / "run.zarr"
    store.mkdir()
    with pytest.raises(AtlasError, match="the output path is a directory"):
        check_output_path(store, layout)  # a folder, but no store in it
    (store / "zarr.json").write_text("{}")
    check_output_path(store, layout)  # a store of the format the name asks for
    named = tmp_path / "run.h5"
    named.mkdir()
    (named / "zarr.json").write_text("{}")
    with pytest.raises(AtlasError, match="the output path is a directory"):
        check_output_path(named, layout)  # .h5 asks for a file
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(AtlasError, match="is not a directory"):
        check_output_path(blocker / "out.h5", layout)
    with pytest.raises(AtlasError, match="may need up to"):
        check_output_path(tmp_path / "huge.h5", _layout(10**5, alphas=1000))  # 110 PB


def test_the_disk_check_counts_every_per_orbit_variable_a_file_stores(small_atlas_file):
    """BYTES_PER_ORBIT against a written file, read with h5py (not with atlas's schema): every
    dataset shaped like the grid (theta_dot0 rows × theta0 columns), at its stored dtype."""
    from atlas.pipeline.output import BYTES_PER_ORBIT, label_bytes

    with h5py.File(small_atlas_file, "r") as f:
        grid = (f["theta_dot0"].size, f["theta0"].size)
        stored = sum(f[name].dtype.itemsize for name in f
                     if isinstance(f[name], h5py.Dataset) and f[name].shape == grid)
    assert stored == BYTES_PER_ORBIT
    assert label_bytes(_layout(5, alphas=3)) == 3 * 5 * 5 * stored
