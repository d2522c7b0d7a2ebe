"""The HDF5 writer of an atlas file's groups (atlas.store.hdf5._GroupStore) writes, object for
object, what xarray's h5netcdf store writes: the same datasets (types, shapes, layout, fill
values, data), the same attributes in the same order, the same dimension scales attached and
numbered, in the same order; the groups it does not cover go through h5netcdf itself."""

import h5netcdf
import h5py
import numpy as np
import pytest
import xarray as xr

from atlas.store import hdf5
from atlas.store.hdf5 import _group, _GroupStore, _netcdf, _stores


def _groups() -> dict[str, xr.Dataset]:
    """Groups like an atlas's (and some it does not have yet), in an order that mixes the
    writer's own groups with those it leaves to h5netcdf."""
    rng = np.random.default_rng(7)
    eigen = rng.normal(size=(3, 2))
    eigen[1, 0] = np.nan
    points = xr.Dataset(
        {"eigenvalue_real": (("point", "eigen"), eigen, {"units": "s-1", "long_name": "re"}),
         "kind": ("point", np.array(["attractor focus", "saddle", "node"])),
         "count": ((), np.int64(3), {"long_name": "a scalar variable"})},
        coords={"theta": ("point", [0.1, 3.0, 6.2], {"units": "rad"}),
                "n": ("point", np.array([0, 1, 2], np.int32))},
        attrs={"description": "critical points", "alpha": 0.05, "n_orbits": 13701,
               "window": np.array([-2.5, 3.5]), "warnings": ""})
    crossings = xr.Dataset(
        {"k_below": ("crossing", np.array([-32768, -8, 0], np.int16), {"comment": "-32768"}),
         "in_window": ("crossing", np.array([1, 0, 1], np.int8),
                       {"flag_values": np.array([0, 1], np.int8), "flag_meanings": "out in"}),
         "bracket": (("crossing", "torque"), rng.random((3, 2)))})  # the root's torque
    shadowing = xr.Dataset({"g": ("torque", rng.random(5))})  # a torque of its own length
    enclosing = xr.Dataset(coords={"torque": ("torque", [0.3, -0.4])})  # the root's torque
    enclosing["h"] = ("torque", rng.random(2))
    coordinate_first = xr.Dataset(coords={"sample": ("sample", np.arange(4.0))})
    coordinate_first["time"] = ("sample", rng.random(4), {"units": "s"})
    coordinate_last = xr.Dataset({"a": ("x", rng.random(2))}, coords={"x": [10, 20]})
    empty = xr.Dataset({"theta": ("point", np.zeros(0))})
    chunked = xr.Dataset({"v": ("s", np.arange(6.0))})
    chunked["v"].encoding["chunksizes"] = (3,)
    parent = xr.Dataset({"p": ("x", rng.random(3))})  # a group with data and a group in it
    inner = xr.Dataset({"c": ("x", rng.random(3))})  # on the parent's x, written by h5netcdf
    inner["c"].encoding["chunksizes"] = (3,)
    enum = xr.Dataset({"e": ("s", np.array([0, 1], dtype=h5py.enum_dtype(
        {"off": 0, "on": 1}, basetype="i1")))})
    return {"critical_points/torque0": points, "separatrices/torque0": crossings,
            "limit_cycle/torque0": coordinate_last, "separatrices/torque1": shadowing,
            "limit_cycle/torque1": coordinate_first, "separatrices/torque2": empty,
            "critical_points/torque1": points, "limit_cycle/torque2": chunked,
            "limit_cycle/torque3": enclosing, "extra": parent, "extra/inner": inner,
            "flags/enum": enum}


#: Groups the writer leaves to h5netcdf: a coordinate after a variable on its dimension, a
#: dimension of length 0, a chunked variable, a coordinate on an enclosing group's dimension,
#: a group that encloses another and the group inside it (chunked), an enum type.
_TO_H5NETCDF = {"limit_cycle/torque0", "separatrices/torque2", "limit_cycle/torque2",
                "limit_cycle/torque3", "extra", "extra/inner", "flags/enum"}


def _write(path, store, groups) -> None:
    """A root like an atlas's (a torque coordinate, a map on it), then ``groups`` each
    through ``store``, as the summary writes them."""
    with _netcdf(path, "w") as f:
        f.dimensions = {"torque": 2, "theta0": 3}
        f.create_variable("torque", ("torque",), np.float64, data=[0.3, -0.4])
        f.create_variable("theta0", ("theta0",), np.float64, data=[-1.0, 0.0, 1.0])
        f.create_variable("attractor", ("torque", "theta0"), np.int16, fillvalue=-32768)
        chosen = _stores(groups) if store is _GroupStore else dict.fromkeys(groups, store)
        for path_in_file, ds in groups.items():
            ds.dump_to_store(chosen[path_in_file](_group(f, path_in_file), mode="a"))


def _attr(file, value):
    """An attribute's value with HDF5 object references as the names they refer to."""
    if isinstance(value, np.ndarray) and value.dtype.names == ("dataset", "dimension"):
        return [(file[ref].name, int(axis)) for ref, axis in value]
    if isinstance(value, np.ndarray) and value.dtype == object:
        return [[file[ref].name for ref in refs] if isinstance(refs, np.ndarray) else refs
                for refs in value]
    return repr(value)


def _objects(path) -> list:
    """Every object of the file in its groups' creation order, with its storage and its
    attributes (names in creation order, types, values)."""
    found = []
    with h5py.File(path, "r") as f:
        def visit(obj):
            plist = obj.id.get_create_plist()
            attrs = [(key, obj.attrs.get_id(key).dtype, obj.attrs.get_id(key).shape,
                      _attr(f, obj.attrs[key])) for key in obj.attrs]
            if isinstance(obj, h5py.Group):
                found.append((obj.name, plist.get_attr_creation_order(), attrs))
                for child in obj.values():
                    visit(child)
                return
            filters = [plist.get_filter(i)[0] for i in range(plist.get_nfilters())]
            data = repr(obj[()].tolist()) if obj.id.get_storage_size() else None
            found.append((obj.name, obj.dtype, h5py.check_string_dtype(obj.dtype), obj.shape,
                          obj.maxshape, obj.chunks, repr(obj.fillvalue), filters,
                          plist.get_layout(), plist.get_attr_creation_order(), data, attrs))

        visit(f)
    return found


def _encoding(var) -> dict:
    """A read variable's encoding but its file name, comparable (NaN fills as text)."""
    return {key: repr(value) for key, value in var.encoding.items() if key != "source"}


def test_the_group_store_writes_what_h5netcdf_writes(tmp_path, monkeypatch):
    groups = _groups()
    _write(tmp_path / "h5netcdf.h5", xr.backends.H5NetCDFStore, groups)
    through_h5netcdf = []
    prepare = xr.backends.H5NetCDFStore.prepare_variable
    monkeypatch.setattr(xr.backends.H5NetCDFStore, "prepare_variable",
                        lambda store, name, *args, **kwargs: through_h5netcdf.append(
                            store.ds.name) or prepare(store, name, *args, **kwargs))
    _write(tmp_path / "own.h5", _GroupStore, groups)
    assert {name.lstrip("/") for name in through_h5netcdf} == _TO_H5NETCDF
    expected, got = _objects(tmp_path / "h5netcdf.h5"), _objects(tmp_path / "own.h5")
    assert [entry[0] for entry in got] == [entry[0] for entry in expected]
    for mine, theirs in zip(got, expected):
        assert mine == theirs
    for path_in_file, ds in groups.items():  # each group as xarray reads it
        old = xr.open_dataset(tmp_path / "h5netcdf.h5", engine="h5netcdf", group=path_in_file)
        new = xr.open_dataset(tmp_path / "own.h5", engine="h5netcdf", group=path_in_file)
        with old, new:
            assert new.identical(old) and new.identical(ds)
            assert dict(new.sizes) == dict(old.sizes)
            for name, var in new.variables.items():  # _FillValue, dtype, storage
                assert _encoding(var) == _encoding(old[name]), name


@pytest.mark.parametrize("ds, error, match", [
    (xr.Dataset({"v": ("s", np.arange(2.0), {"flag": True})}), h5netcdf.CompatibilityError,
     "boolean"),  # no netCDF-4 type
    (xr.Dataset({"v": ("s", np.arange(2.0), {"NAME": "mine"})}), AttributeError, "NAME"),
    (xr.Dataset({"v": ("s", np.arange(2.0))}, attrs={"_Netcdf4Dimid": 3}), AttributeError,
     "_Netcdf4Dimid"),  # names netCDF-4's layout uses itself
    (xr.Dataset({"v": ("a/b", np.arange(2.0))}), ValueError, "/"),
], ids=["boolean", "reserved variable attribute", "reserved group attribute",
        "slash in a dimension"])
def test_the_group_store_refuses_what_h5netcdf_refuses(tmp_path, ds, error, match):
    """What xarray's h5netcdf store refuses, the group store refuses with the same error."""
    for store in (xr.backends.H5NetCDFStore, _GroupStore):
        with _netcdf(tmp_path / f"{store.__name__}.h5", "w") as f, \
                pytest.raises(error, match=match):
            ds.dump_to_store(store(_group(f, "g"), mode="a"))


def test_a_write_failing_in_a_group_leaves_the_file_closed(tmp_path, monkeypatch):
    """A group whose write fails (a full disk, simulated in h5py's dataset creation) ends the
    summary's writer with an OSError carrying the errno, not a crash of this process."""
    import errno

    from atlas.layout import Layout

    path = tmp_path / "s.h5"
    _write(path, xr.backends.H5NetCDFStore, {})
    real = h5py.Group.create_dataset
    calls = []

    def full_disk(group, name, *args, **kwargs):
        calls.append(name)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(group, name, *args, **kwargs)

    monkeypatch.setattr(h5py.Group, "create_dataset", full_disk)
    layout = Layout(x0=np.linspace(-1.0, 1.0, 3), v0=np.linspace(-1.0, 1.0, 2),
                    parameters={"alpha": np.array([0.1]), "omega0": np.array([1.0]),
                                "torque": np.array([0.3, -0.4])},
                    swept=("torque",), rows_per_tile=2)
    groups = {name: ds for name, ds in _groups().items() if name not in _TO_H5NETCDF}
    with pytest.raises(OSError) as caught:
        hdf5._write_summary(path, layout, groups, xr.Dataset(), {})
    assert caught.value.errno == errno.ENOSPC and "No space left" in str(caught.value)
    with h5py.File(path, "r") as f:  # closed by the writer, readable, not complete
        assert "complete" not in f.attrs
