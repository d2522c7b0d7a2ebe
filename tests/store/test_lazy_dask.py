"""atlas.lazy_dask: xarray does not import dask.array until a dask array can exist, and
behaves as before once it does."""

import subprocess
import sys
import textwrap

import numpy as np


def _run(code: str) -> str:
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_xarray_work_without_dask_arrays_does_not_import_dask(tmp_path):
    """Neither dask.array (xarray's duck-array check) nor dask itself (to_netcdf's question
    about the active dask scheduler) is imported by writing and reading a file."""
    out = _run(f"""
        import sys
        import numpy as np
        import atlas.store.reader  # installs the deferral
        import xarray as xr
        ds = xr.Dataset({{"a": (("y", "x"), np.arange(6.0).reshape(2, 3))}})
        ds.to_netcdf("{tmp_path / 'a.h5'}", engine="h5netcdf")
        back = xr.open_dataset("{tmp_path / 'a.h5'}", engine="h5netcdf").load()
        assert (back.a.values == ds.a.values).all()
        print("dask.array" in sys.modules, "dask" in sys.modules)
    """)
    assert out == "False False"


def test_the_active_dask_scheduler_is_seen_once_dask_is_imported():
    """The deferred scheduler question asks dask as soon as dask is imported: to_netcdf's
    choice of locks follows the scheduler a user set."""
    out = _run("""
        import atlas.store.study  # installs the deferral
        from xarray.backends import locks, writers
        before = writers.get_dask_scheduler()
        import dask
        with dask.config.set(scheduler="processes"):
            print(before, writers.get_dask_scheduler(), locks.get_dask_scheduler())
    """)
    assert out == "None multiprocessing multiprocessing"


def test_datasets_with_index_coordinates_do_not_import_dask(tmp_path):
    """Building a dataset with an index coordinate (atlas's summary) and reading a file back
    import no part of dask (xarray's check for dask collections would import dask.base)."""
    path = tmp_path / "c.h5"
    import h5py
    with h5py.File(path, "w") as f:
        f["a"] = np.arange(3.0)
    out = _run(f"""
        import sys
        import numpy as np
        import atlas.store.reader  # installs the deferral
        import xarray as xr
        ds = xr.Dataset({{"a": ("k", np.arange(3.0))}}, coords={{"k": np.arange(3)}})
        back = xr.open_dataset("{path}", engine="h5netcdf").load()
        print(float(ds.a.sel(k=2)), float(back.a.sum()), "dask" in sys.modules)
    """)
    assert out == "2.0 3.0 False"


def test_without_the_deferral_xarray_imports_dask_array():
    """The control: the test above can fail — plain xarray imports dask.array."""
    out = _run("""
        import sys
        import numpy as np
        import xarray as xr
        xr.Dataset({"a": ("x", np.arange(3.0))}, coords={"x": np.arange(3)})
        print("dask.array" in sys.modules, "dask" in sys.modules)
    """)
    assert out == "True True"


def test_dask_arrays_are_recognised_once_dask_is_imported(tmp_path):
    out = _run(f"""
        import numpy as np
        import atlas.store.reader
        from atlas import lazy_dask
        import xarray as xr
        assert lazy_dask.install()  # idempotent: still deferred
        xr.Dataset({{"a": ("x", np.arange(4.0))}}).to_netcdf("{tmp_path / 'b.h5'}",
                                                           engine="h5netcdf")
        import dask.array as da
        arr = xr.DataArray(da.zeros(4, chunks=2), dims="x")
        lazy = xr.open_dataset("{tmp_path / 'b.h5'}", engine="h5netcdf", chunks={{}})
        print(arr.chunks, type(lazy.a.data).__module__.split(".")[0],
              float((arr + 1).sum().compute()), float(lazy.a.sum().compute()))
    """)
    assert out == "((2, 2),) dask 4.0 6.0"
