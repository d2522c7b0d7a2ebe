"""The Python face of the package: ``dir(atlas)``, submodules without their own import, an
atlas computed in memory (``atlas.basins``, ``atlas.run(cfg, output=None)``) against the file
of the same config, and the status names of ``atlas.label``'s results."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import atlas
from atlas.status import STATUS_MEANINGS
from tests.helpers import REPO

#: The public API of docs and the contract (SPEC: "Python API"), all of which dir() must show.
PUBLIC = {"label", "linear", "LabelResult", "load_config", "Config", "run", "basins", "open",
          "Pendulum", "critical_points", "AtlasError", "ConfigError", "InputFileError",
          "BackendUnavailable", "__version__"}


def test_dir_lists_the_public_api_and_the_submodules():
    names = set(dir(atlas))
    assert PUBLIC <= names
    assert {"layout", "store", "pipeline", "views", "status", "boundaries"} <= names
    assert set(atlas.__all__) <= names
    for name in atlas.__all__:  # every name it lists is there
        assert getattr(atlas, name) is not None


def _fresh_python(code: str) -> str:
    """Run ``code`` in a new interpreter (this one has imported everything already)."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=REPO,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.slow
def test_submodules_load_on_use_and_import_atlas_stays_light():
    """``atlas.layout.points`` after a bare ``import atlas`` (the README's snippet), while
    ``import atlas`` itself loads neither the compiler nor the file stack."""
    out = _fresh_python("""
        import sys
        import atlas
        heavy = [m for m in ("numba", "xarray", "scipy", "pydantic", "h5py", "matplotlib",
                             "atlas.layout", "atlas.pipeline", "atlas.store") if m in sys.modules]
        print("heavy:", heavy)
        import xarray as xr
        ds = xr.Dataset(coords={"alpha": ("alpha", [0.1, 0.2]), "omega0": 1.0, "torque": 0.0})
        print("points:", atlas.layout.points(ds))
        print("lazy:", atlas.run.__module__, atlas.open.__module__)
        try:
            atlas.no_such_name
        except AttributeError as exc:
            print("missing:", exc)
    """)
    lines = dict(line.split(": ", 1) for line in out.splitlines())
    assert lines["heavy"] == "[]"
    assert lines["points"] == ("[{'alpha': 0.1, 'omega0': 1.0, 'torque': 0.0}, "
                               "{'alpha': 0.2, 'omega0': 1.0, 'torque': 0.0}]")
    assert lines["lazy"] == "atlas.pipeline.memory atlas.store.reader"
    assert "no_such_name" in lines["missing"]


# ----------------------------------------------------------------------- in memory

def _config(output, **extra):
    """A small parameter atlas (α swept: 4-D maps) in tiles of 3 rows (an edge tile too)."""
    return atlas.Config.model_validate({
        "name": "in-memory", "pendulum": {"alpha": [0.2, 0.3], "omega0": 1.0},
        "grid": {"theta0": {"start": "-3pi", "stop": "3pi", "num": 24},
                 "theta_dot0": {"start": -3.0, "stop": 3.0, "num": 20}},
        "integrator": {"dt": 0.02, "t_max": 100.0},
        "execution": {"tile_orbits": 72}, "output": str(output), **extra})


#: Root attributes that differ between two runs of one config by design.
RUN_ATTRS = {"created", "run_time_s"}


def _equal(a, b) -> bool:
    """Equal values and dtypes, NaN equal to NaN."""
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")


def _same_trees(mem, disk) -> None:
    """Every node, variable, dim, dtype and value (NaN equal to NaN) and every attribute of
    ``disk`` (a file opened by atlas.open) is in ``mem``, and nothing more. The groups' float
    variables of a file carry ``_FillValue = NaN``, xarray's default encoding when it writes
    a group, not content: that one attribute is not asked of ``mem`` there."""
    assert {n.path for n in mem.subtree} == {n.path for n in disk.subtree}
    for node in disk.subtree:
        a, b = node.to_dataset(inherit=False), mem[node.path].to_dataset(inherit=False)
        assert set(a.variables) == set(b.variables), node.path
        assert set(a.coords) == set(b.coords), node.path
        for name, var in a.variables.items():
            twin = b.variables[name]
            where = f"{node.path} {name}"
            assert (var.dims, var.dtype) == (twin.dims, twin.dtype), where
            assert _equal(var.values, twin.values), where
            attrs = dict(var.attrs)
            if node.path != "/" and np.isnan(attrs.get("_FillValue", 0.0)):
                attrs.pop("_FillValue")
            assert attrs.keys() == twin.attrs.keys(), where
            for key, value in attrs.items():
                assert _equal(value, twin.attrs[key]), f"{where} {key}"
        own = {k: v for k, v in node.attrs.items() if k not in RUN_ATTRS}
        theirs = {k: v for k, v in mem[node.path].attrs.items() if k not in RUN_ATTRS}
        assert own.keys() == theirs.keys(), node.path
        for key, value in own.items():
            assert _equal(value, theirs[key]), f"{node.path} attribute {key}"


@pytest.mark.slow
def test_an_atlas_in_memory_is_the_file_of_its_config(tmp_path):
    """atlas.basins(cfg) writes nothing and holds what atlas.open gives of the file that
    atlas.run(cfg) writes: the same arrays (assembled there from HDF5 chunks copied tile by
    tile, here by numpy assignment), dtypes, fills, groups and attributes; and it is a valid
    atlas for every reader (the file check)."""
    from atlas.store.validate import check_tree

    cfg = _config(tmp_path / "atlas.h5")
    mem = atlas.basins(cfg, quiet=True)
    assert list(tmp_path.iterdir()) == []  # no file, no partial run, no lock
    check_tree(mem, "<in memory>")
    assert mem["attractor"].dims == ("alpha", "theta_dot0", "theta0")
    atlas.run(cfg, quiet=True)
    with atlas.open(cfg.output) as disk:
        _same_trees(mem, disk)
    # the maps compared are not trivial: several wells, a boundary distance for every orbit
    assert np.unique(mem["attractor"].values).size >= 3
    assert np.isfinite(mem["boundary_distance"].values).all()


def test_run_output_none_writes_nothing_and_a_path_writes_there(tmp_path):
    cfg = atlas.Config.model_validate({
        "pendulum": {"alpha": 0.5}, "separatrices": {"enabled": False},
        "grid": {"theta0": {"start": -1.0, "stop": 1.0, "num": 4},
                 "theta_dot0": {"start": -1.0, "stop": 1.0, "num": 3}},
        "output": str(tmp_path / "configured.h5")})
    tree = atlas.run(cfg, output=None, quiet=True)
    assert list(tmp_path.iterdir()) == []
    # from |θ0| ≤ 1, |θ̇0| ≤ 1 with α = 0.5 the energy stays below the saddles' 2ω0²: every
    # orbit rests in the well it starts in, k = 0
    assert tree["attractor"].shape == (3, 4) and (tree["attractor"].values == 0).all()
    assert tree.attrs["config"] == cfg.to_json()
    atlas.run(cfg, output=tmp_path / "elsewhere.h5", quiet=True)
    assert [p.name for p in tmp_path.iterdir()] == ["elsewhere.h5"]  # not cfg.output
    with atlas.open(tmp_path / "elsewhere.h5") as disk:
        assert _equal(disk["attractor"].values, tree["attractor"].values)


# ----------------------------------------------------------------------- status names

def test_label_status_names_say_rk4_map_and_differ_from_the_file():
    """atlas.label's codes by name: 0 and 4 are certificates of the RK4 map, which in a file
    (certified for the exact equation) carry other names."""
    meanings = atlas.LabelResult.status_meanings
    for code in (0, 4):
        assert "rk4" in meanings[code] and meanings[code] != STATUS_MEANINGS[code]
    for code in (1, 2):  # these mean the same in a file
        assert meanings[code] == STATUS_MEANINGS[code]
    # (0, 0.5) lies deep in well 0 (energy 0.125 < 2); a NaN start is nonfinite; (0, 3) has
    # energy 4.5 above the saddles' 2 and cannot be trapped within t_max = 0.32 s
    res = atlas.label([0.0, np.nan, 0.0], [0.5, 0.0, 3.0], alpha=0.1, omega0=1.0, t_max=0.32)
    assert res.status_names().tolist() == ["trapped_rk4_map", "nonfinite", "unresolved"]
    assert res.status_names().shape == res.status.shape
    with pytest.raises(ValueError, match=r"\[3\]"):  # a file's near_boundary: not a label's
        atlas.LabelResult(res.attractor, np.array([0, 3, 1], np.int8), res.t_trap).status_names()


@pytest.mark.slow
def test_an_atlas_with_torque_in_memory_is_its_file(swing_atlas):
    """With a torque (tilted wells, the running cycle, its barrier in /limit_cycle): the
    in-memory atlas of the config stored in the shared swing atlas file is that file."""
    with atlas.open(swing_atlas) as disk:
        cfg = atlas.Config.model_validate_json(disk.attrs["config"])
        mem = atlas.basins(cfg, quiet=True)
        assert any(node.path.startswith("/limit_cycle") for node in mem.subtree)
        assert (mem["status"].values == 4).any()  # running orbits, certified
        _same_trees(mem, disk)


# ------------------------------------------------- reading and drawing, as the docs show them

def test_attractor_is_float32_in_plain_xarray_and_int16_as_the_docs_say(tmp_path):
    """README and docs/output.md: plain ``xr.open_dataset`` decodes ``attractor``'s fill value
    to NaN (float32); ``mask_and_scale={"attractor": False}`` and ``atlas.open`` keep the
    stored int16 and its fill value, with the same labels. t_max = 2 s leaves some orbits
    without a label, so that the fill value is met."""
    import xarray as xr

    from tests.helpers import small_atlas

    small_atlas(tmp_path, "short", {"alpha": 0.1, "omega0": 1.0}, theta=("-3pi", "3pi"),
                speed=(-4.0, 4.0), num=(12, 8), t_max=2.0, separatrices=False)
    path = tmp_path / "short.h5"
    with xr.open_dataset(path, engine="h5netcdf") as plain, \
            xr.open_dataset(path, engine="h5netcdf",
                            mask_and_scale={"attractor": False}) as kept, \
            atlas.open(path) as tree:
        decoded, stored, opened = (plain["attractor"].values, kept["attractor"].values,
                                   tree["attractor"].values)
        fill = kept["attractor"].attrs["_FillValue"]
        assert plain["t_trap"].dtype == kept["t_trap"].dtype == np.float32  # others as stored
    assert decoded.dtype == np.float32 and stored.dtype == opened.dtype == np.int16
    assert fill == -32768
    np.testing.assert_array_equal(stored, opened)
    labelled = stored != fill
    assert 0 < labelled.sum() < labelled.size  # both kinds of orbit are there
    np.testing.assert_array_equal(decoded[labelled], stored[labelled])
    assert np.isnan(decoded[~labelled]).all()


def test_basin_map_draws_the_point_asked_into_the_axes_given(tmp_path):
    """``atlas.views.maps.basin_map(tree, ax=ax, alpha=i)`` (README, docs/output.md): it draws
    into ``ax`` (no figure of its own), returns it, and shows the i-th α of a parameter atlas:
    its title, and its labels pixel for pixel (a grid this small is not coarsened)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from atlas.views.maps import basin_map
    from tests.helpers import small_atlas

    tree = small_atlas(tmp_path, "two", {"alpha": [0.1, 0.3], "omega0": 1.0},
                       theta=("-3pi", "3pi"), speed=(-4.0, 4.0), num=(12, 8), t_max=200.0,
                       separatrices=False)
    fig, axes = plt.subplots(1, 2)
    figures = plt.get_fignums()
    try:
        for i, ax in enumerate(axes):
            assert basin_map(tree, ax=ax, alpha=i) is ax
            assert f"α = {(0.1, 0.3)[i]:g} s⁻¹" in ax.get_title()
            drawn = np.ma.filled(ax.images[0].get_array().astype(float), np.nan)
            k = tree["attractor"].isel(alpha=i).values
            np.testing.assert_array_equal(drawn, np.where(k == -32768, np.nan, k))
        assert plt.get_fignums() == figures
        # the two points differ, so that drawing the wrong one shows
        assert (tree["attractor"].isel(alpha=0) != tree["attractor"].isel(alpha=1)).any()
    finally:
        plt.close(fig)
