"""The file formats: one lookup says which, each format round-trips an atlas through the
partial-run store, format 4's certificate is checked and read back, format 3 is still read,
and the store's modules import each other without a circle."""

import json
import shutil

import h5py
import numpy as np
import pytest
import xarray as xr

import atlas
from atlas.errors import InputFileError
from atlas.layout import Layout, points
from atlas.models.pendulum.description import PENDULUM
from atlas.store.formats import DEFAULT, FORMATS, format_for, format_named
from atlas.store.hdf5 import HDF5
from atlas.store.partial import TileStore, partial_path
from atlas.store.reader import (
    open_atlas,
    require_certificate,
    stored_certificate,
    stores_certificate,
)
from atlas.store.schema import (
    FORMAT_VERSION,
    SCHEMA,
    summary_dataset,
    with_barrier,
)
from atlas.store.zarrformat import Zarr

MAP_VARIABLES, FILLS = PENDULUM.map_variables, PENDULUM.fills
BASIN_VARIABLES, POINT_VARIABLES = PENDULUM.basin_variables, PENDULUM.point_variables

TORQUES = (0.3, -0.4)  # a parameter atlas over torque: one running cycle per point
CAPS = (1.25, -np.inf)  # the second point: no well can trap


class _Barrier:
    """What :func:`with_barrier` takes (the fields of RunningBarrier)."""

    def __init__(self, theta0, g, top, direction):
        self.theta0, self.g, self.top, self.direction = theta0, g, top, direction


def _layout() -> Layout:
    return Layout(x0=np.linspace(-3.0, 3.0, 7), v0=np.linspace(-2.0, 2.0, 5),
                  parameters={"alpha": np.array([0.1]), "omega0": np.array([1.0]),
                              "torque": np.array(TORQUES)},
                  swept=("torque",), rows_per_tile=2)


def _values(layout: Layout, index: int) -> dict:
    """Tile ``index``'s label arrays: distinct values from the tile's index."""
    _, rows = layout.tile(index)
    shape = (rows.stop - rows.start, layout.x0.size)
    ramp = np.arange(np.prod(shape)).reshape(shape) + 100 * index
    return {"attractor": (ramp % 5 - 2).astype(np.int16),
            "status": (ramp % 6).astype(np.int8),
            "t_trap": (ramp * 0.5).astype(np.float32),
            "boundary_distance": (ramp * 0.25).astype(np.float32)}


def _expected(layout: Layout) -> dict:
    full = {name: np.empty((len(TORQUES), 5, 7), var.dtype) for name, var in
            MAP_VARIABLES.items()}
    for index in range(layout.n_tiles):
        params, rows = layout.tile(index)
        for name, values in _values(layout, index).items():
            full[name][(*params, rows)] = values
    return full


def _summary(layout: Layout) -> xr.Dataset:
    points = []
    for cap in CAPS:
        point = {"k": np.array([-1, 0, 1])}
        point.update({name: np.array([0.2, 0.5, 0.3]) for name in BASIN_VARIABLES})
        point.update({name: 0.01 for name in POINT_VARIABLES})
        point["trap_energy_cap"] = cap
        points.append(point)
    return summary_dataset(layout, points)


def _groups(layout: Layout) -> dict:
    """One ``/limit_cycle`` node per point, with format 4's barrier."""
    groups = {}
    for p, torque in enumerate(TORQUES):
        sign = int(np.sign(torque))
        theta = np.linspace(0.0, 2 * np.pi, 9)
        cycle = xr.Dataset({"theta_dot": ("sample", sign * (2.0 + 0.1 * np.sin(theta))),
                            "time": ("sample", np.linspace(0.0, 3.0, 9))},
                           coords={"theta": ("sample", sign * theta)},
                           attrs={"period": 3.0, "mean_theta_dot": sign * 2.0,
                                  "direction": np.int8(sign)})
        barrier = _Barrier(-np.pi / 2, np.linspace(0.5, 0.6, 17) + p, 5.0 + p, sign)
        groups[f"limit_cycle/torque{p}"] = with_barrier(cycle, barrier).assign_attrs(
            layout.point(p))
    return groups


ATTRS = {"format_version": np.int64(FORMAT_VERSION), "dt": 0.01, "t_max": 10.0,
         "method": "rk4", "check_every": np.int64(8), "config": json.dumps({"name": "t"})}


def _write(tmp_path, fmt, name) -> tuple:
    """An atlas of format ``fmt`` written through a partial run: half its tiles, the run
    reopened (the format read back from the manifest), the rest, then finalized."""
    layout = _layout()
    output = tmp_path / name
    partial = partial_path(output)
    tiles = TileStore.create(partial, layout, {"run": 1}, ATTRS, fmt.tile_run)
    assert (json.loads((partial / "manifest.json").read_text())["format"] == fmt.name)
    for index in range(0, layout.n_tiles, 2):
        tiles.write(index, _values(layout, index), {"count": np.array([index])})
    again = TileStore.open(partial, {"run": 1})
    assert again.tile_run == fmt.tile_run
    assert list(again.done()) == list(range(0, layout.n_tiles, 2))
    for index in again.todo():
        again.write(index, _values(layout, index), {"count": np.array([index])})
    assert again.todo().size == 0
    assert [int(again.read_tally(i)["count"][0]) for i in range(layout.n_tiles)] == \
        list(range(layout.n_tiles))
    again.finalize(output, _groups(layout), _summary(layout), {"backend": "cpu"})
    assert output.exists() and not partial.exists()
    return layout, output


# ---- which format ------------------------------------------------------------------------

def test_format_for_by_suffix():
    assert set(FORMATS) == {"hdf5", "zarr"} and DEFAULT is FORMATS["hdf5"]
    assert format_for("out/run.zarr") is FORMATS["zarr"]
    for name in ("run.h5", "run.nc", "run.hdf5", "run", "run.dat"):
        assert format_for(name) is FORMATS["hdf5"], name
    assert format_named("zarr") is FORMATS["zarr"]
    with pytest.raises(KeyError, match="known: hdf5, zarr"):
        format_named("netcdf3")


def test_format_for_by_content(tmp_path):
    """A name without a known suffix: what is there decides (HDF5's signature, also after
    a user block; a Zarr store's zarr.json); nothing recognisable: the default."""
    plain = tmp_path / "atlas_output"
    with h5py.File(plain, "w") as f:
        f["a"] = np.arange(3)
    blocked = tmp_path / "with_user_block"
    with h5py.File(blocked, "w", userblock_size=1024) as f:
        f["a"] = np.arange(3)
    store = tmp_path / "a_store"
    store.mkdir()
    (store / "zarr.json").write_text("{}")
    text = tmp_path / "notes"
    text.write_text("not an atlas")
    assert HDF5().recognises(plain) and HDF5().recognises(blocked)
    assert not HDF5().recognises(text) and not HDF5().recognises(store)
    assert Zarr().recognises(store) and not Zarr().recognises(plain)
    assert format_for(plain) is FORMATS["hdf5"] and format_for(blocked) is FORMATS["hdf5"]
    assert format_for(store) is FORMATS["zarr"]
    assert format_for(text) is DEFAULT and format_for(tmp_path / "absent") is DEFAULT
    # a suffix that names a format decides over what is there
    named = tmp_path / "named.h5"
    named.mkdir()
    (named / "zarr.json").write_text("{}")
    assert format_for(named) is FORMATS["hdf5"]
    assert Zarr().guess_can_open(tmp_path / "x.zarr") and HDF5().guess_can_open(plain)


# ---- each format round-trips an atlas ----------------------------------------------------

@pytest.mark.parametrize("fmt, name", [(HDF5(), "t.h5"), (Zarr(), "t.zarr")],
                         ids=["hdf5", "zarr"])
def test_each_format_round_trips_an_atlas_through_the_partial_store(tmp_path, fmt, name):
    if fmt.name == "zarr":
        pytest.importorskip("zarr")
    layout, output = _write(tmp_path, fmt, name)
    assert format_for(output) == fmt
    tree = open_atlas(output)  # checked, format 4 with its certificate
    root = tree.to_dataset(inherit=False)
    for var_name, values in _expected(layout).items():
        assert root[var_name].dtype == MAP_VARIABLES[var_name].dtype
        np.testing.assert_array_equal(root[var_name].values, values)
    assert root["attractor"].attrs["_FillValue"] == FILLS["attractor"]
    assert root.attrs["atlas_schema"] == SCHEMA and int(root.attrs["complete"]) == 1
    assert root.attrs["backend"] == "cpu" and root.attrs["format_version"] == FORMAT_VERSION
    assert root["trap_energy_cap"].attrs["units"] == "rad2 s-2"
    assert root["d_cert"].attrs["units"] == "1"
    np.testing.assert_array_equal(root["trap_energy_cap"].values, CAPS)
    assert stores_certificate(tree.attrs)
    for p, point in enumerate(points(root)):
        cert = stored_certificate(tree, point)
        assert cert.trap_energy_cap == CAPS[p]
        np.testing.assert_array_equal(cert.barrier.g, np.linspace(0.5, 0.6, 17) + p)
        assert (cert.barrier.theta0, cert.barrier.top) == (-np.pi / 2, 5.0 + p)
        assert cert.barrier.direction == int(np.sign(TORQUES[p]))
    require_certificate(tree, output)
    tree.close()
    assert atlas.open is open_atlas


def test_the_hdf5_format_keeps_encoded_chunks_and_zarr_its_own_store(tmp_path):
    """The partial store never asks which format: HDF5 hands it each tile's chunks to keep,
    Zarr writes the tile into its store in the folder and hands it nothing."""
    pytest.importorskip("zarr")
    layout = _layout()
    kept = {}
    for fmt in (HDF5(), Zarr()):
        tiles = TileStore.create(tmp_path / f"{fmt.name}.partial", layout, {}, {},
                                 fmt.tile_run)
        tiles.write(1, _values(layout, 1), {"count": np.array([1])})
        kept[fmt.name] = tiles.read_tile(1).chunks
    assert set(kept["hdf5"]) == set(MAP_VARIABLES) and kept["zarr"] == {}
    assert (tmp_path / "zarr.partial" / "atlas.zarr" / "zarr.json").is_file()
    assert not (tmp_path / "hdf5.partial" / "atlas.zarr").exists()


# ---- format 4's certificate, format 3 ----------------------------------------------------

@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """A valid format-4 HDF5 atlas with two running points; copy it before changing it."""
    return _write(tmp_path_factory.mktemp("good"), HDF5(), "good.h5")[1]


def _damaged(good, tmp_path, change):
    output = tmp_path / "bad.h5"
    shutil.copyfile(good, output)
    with h5py.File(output, "a") as f:
        change(f)
    return output


def _set(group, name, value):
    def change(f):
        f[group].attrs[name] = value
    return change


def _g(values):
    def change(f):
        f["limit_cycle/torque1/barrier_g"][...] = values
    return change


BARRIER_DAMAGE = [
    ("g ends below its start", _g(np.linspace(0.6, 0.5, 17)), "ends below its start"),
    ("g not finite", _g(np.r_[0.5, np.nan, np.full(15, 0.6)]), "barrier_g is not finite"),
    ("top below g", _set("limit_cycle/torque0", "barrier_top", 0.55),
     "barrier_top = 0.55 is not above every barrier_g"),
    ("direction 0", _set("limit_cycle/torque0", "barrier_direction", np.int8(0)),
     "barrier_direction = 0 is not +1 or -1"),
    ("direction of the other point", _set("limit_cycle/torque1", "barrier_direction",
                                          np.int8(1)),
     "barrier_direction = 1 is not the cycle's direction -1"),
    ("no theta0", lambda f: f["limit_cycle/torque0"].attrs.__delitem__("barrier_theta0"),
     "no /limit_cycle/torque0 attribute barrier_theta0"),
    ("no barrier", lambda f: f["limit_cycle/torque0"].__delitem__("barrier_g"),
     "/limit_cycle/torque0 group has no barrier_g"),
    ("no cap", lambda f: f.__delitem__("trap_energy_cap"), "no trap_energy_cap variable"),
    ("cap NaN", lambda f: f["trap_energy_cap"].__setitem__(0, np.nan),
     "trap_energy_cap holds NaN"),
]


@pytest.mark.parametrize("what, change, fragment", BARRIER_DAMAGE,
                         ids=[d[0] for d in BARRIER_DAMAGE])
def test_format_4_refuses_a_damaged_certificate(good, tmp_path, what, change, fragment):
    bad = _damaged(good, tmp_path, change)
    with pytest.raises(InputFileError, match="bad.h5") as err:
        open_atlas(bad)
    assert fragment in str(err.value) and len(str(err.value).splitlines()) == 1


def _as_format_3(f):
    """What a format-3 writer left: no cap, no barrier."""
    f.attrs["format_version"] = np.int64(3)
    del f["trap_energy_cap"]
    for p in range(len(TORQUES)):
        node = f[f"limit_cycle/torque{p}"]
        del node["barrier_g"], node["barrier_sample"]
        for name in list(node.attrs):
            if name.startswith("barrier_"):
                del node.attrs[name]


def test_a_format_3_file_is_read_without_a_certificate(good, tmp_path):
    path = _damaged(good, tmp_path, _as_format_3)
    tree = open_atlas(path)  # checked as format 3
    try:
        root = tree.to_dataset(inherit=False)
        assert int(root.attrs["format_version"]) == 3 and "trap_energy_cap" not in root
        assert root["attractor"].dtype == np.int16
        assert not stores_certificate(tree.attrs)
        assert stored_certificate(tree, points(root)[0]) is None
        with pytest.raises(InputFileError) as err:
            require_certificate(tree, path)
        assert str(err.value) == (
            f"{path} was written in format 3, which does not store the certificate its "
            "labels used; recompute it by running its config again (`atlas run CONFIG`)")
    finally:
        tree.close()
    # a format-3 file still has the rest of its schema checked
    with h5py.File(path, "a") as f:
        del f["d_cert"]
    with pytest.raises(InputFileError, match="no d_cert variable"):
        open_atlas(path)


# ---- no circle ---------------------------------------------------------------------------

def test_the_store_has_no_import_circle_and_one_home_per_library():
    """Built with grimp, import-linter's graph: no two store modules import each other
    (directly or not); only the formats import h5py, h5netcdf, zarr; the partial store
    imports neither; nothing in the store imports physics, labels or kernels."""
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("atlas", include_external_packages=True)
    store = sorted(m for m in graph.find_children("atlas.store"))
    assert {"atlas.store.schema", "atlas.store.format", "atlas.store.formats",
            "atlas.store.hdf5", "atlas.store.zarrformat", "atlas.store.partial",
            "atlas.store.reader", "atlas.store.validate"} <= set(store)
    for a in store:
        for b in store:
            if a < b:
                assert not (graph.chain_exists(a, b) and graph.chain_exists(b, a)), (a, b)
    for module in store:
        libraries = graph.find_modules_directly_imported_by(module) & {"h5py", "h5netcdf",
                                                                       "zarr"}
        assert not libraries or module in {"atlas.store.hdf5", "atlas.store.zarrformat"}, \
            (module, libraries)
        for other in ("atlas.physics", "atlas.labels", "atlas.kernels", "numba"):
            assert not graph.chain_exists(module, other, as_packages=True), (module, other)
