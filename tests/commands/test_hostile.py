"""Hostile input: files that are not what they claim, outputs in the way, a page that must not
run what a file says, and the exit statuses. The CLI runs in-process (``atlas.cli.main``)."""

import io
import json
import logging
import os
import re
import shutil
import warnings
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr

import atlas
from atlas import errors
from atlas.cli import main
from atlas.store.schema import FORMAT_VERSION

REPO = Path(__file__).resolve().parents[2]
XSS = "</script><script>alert(1)</script>"

TINY = """\
name: tiny
pendulum: {{alpha: 0.1, omega0: 1.0}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 12}}
  theta_dot0: {{start: -4, stop: 4, num: 8}}
integrator: {{dt: 0.01, t_max: 100}}
separatrices: {{enabled: {sep}}}
execution: {{tile_orbits: 48}}
output: {output}
"""


def cli(*args) -> tuple[int, str, str]:
    """``atlas ARGS`` in this process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, out.getvalue(), err.getvalue()


def refused(result, code, *fragments) -> str:
    status, _, err = result
    lines = err.strip().splitlines()
    assert status == code and len(lines) == 1 and "Traceback" not in err, (status, err)
    assert lines[0].startswith("atlas: error: "), lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def tiny_config(folder: Path, output: Path, sep=False, name="c.yaml") -> Path:
    path = folder / name
    path.write_text(TINY.format(output=output, sep=str(sep).lower()))
    return path


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> Path:
    """A valid atlas file (12 x 8 orbits, separatrices on); copy it before changing it."""
    tmp = tmp_path_factory.mktemp("good")
    out = tmp / "good.h5"
    code, _, err = cli("run", tiny_config(tmp, out, sep=True), "--quiet")
    assert code == 0, err
    return out


def _copy(good: Path, folder: Path, name="bad.h5") -> Path:
    path = folder / name
    shutil.copyfile(good, path)
    return path


def _rewrite(good: Path, folder: Path, change) -> Path:
    """A copy of ``good`` whose root dataset is passed through ``change`` (xarray), groups
    kept."""
    tree = atlas.open(good)
    tree = tree.load()
    tree.close()
    root = change(tree.to_dataset(inherit=False))
    path = folder / "bad.h5"
    root.to_netcdf(path, engine="h5netcdf")
    for name in tree.children:
        tree[name].to_dataset(inherit=False).to_netcdf(path, mode="a", group=name,
                                                       engine="h5netcdf")
    return path


def _attr(name, value):
    def change(f):
        if value is None:
            f.attrs.pop(name, None)
        else:
            f.attrs[name] = value
    return change


def _h5(change):
    def make(good, folder):
        path = _copy(good, folder)
        with h5py.File(path, "a") as f:
            change(f)
        return path
    return make


def _nan_attractor(ds):
    ds["attractor"] = ds["attractor"].astype(np.float32) * np.nan
    ds["attractor"].attrs.pop("_FillValue", None)
    return ds


def _int_t_trap(ds):
    ds["t_trap"] = ds["t_trap"].fillna(0).astype(np.int32)
    ds["t_trap"].attrs.pop("_FillValue", None)
    return ds


def _decreasing_theta0(f):
    f["theta0"][...] = f["theta0"][...][::-1]


def _flags(f):
    f["status"].attrs["flag_meanings"] = ("unresolved trapped nonfinite near_boundary running "
                                          "running_near_boundary")


BROKEN = [
    ("config attribute not JSON", _h5(_attr("config", "{not json")),
     "the config attribute is not valid JSON"),
    ("config attribute a list", _h5(_attr("config", "[1, 2]")), "not a JSON object"),
    ("float all-NaN attractor", lambda g, d: _rewrite(g, d, _nan_attractor),
     "variable attractor is float32, not int16"),
    ("newer format_version", _h5(_attr("format_version", np.int64(FORMAT_VERSION + 1))),
     f"format_version {FORMAT_VERSION + 1} is newer than this atlas reads"),
    ("format_version not a number", _h5(_attr("format_version", "two")),
     "format_version 'two' is not an integer"),
    ("theta0 decreasing", _h5(_decreasing_theta0), "theta0 is not strictly increasing"),
    ("status flags that mean something else", _h5(_flags), "status flag 0 means 'unresolved'"),
    ("summary variable missing", _h5(lambda f: f.__delitem__("d_cert")),
     "no d_cert variable"),
    ("dt not a number", _h5(_attr("dt", "fast")), "attribute dt is not a number"),
    ("unknown method", _h5(_attr("method", "euler")),
     "attribute method = 'euler' is not one of rk4, rk4-trigfree"),
    ("method an array", _h5(_attr("method", np.array([b"rk4-trigfree", b"rk4"]))),
     "is not one of rk4, rk4-trigfree"),
    ("t_trap int", lambda g, d: _rewrite(g, d, _int_t_trap), "variable t_trap is int32"),
]


@pytest.mark.slow
@pytest.mark.parametrize("what,make,fragment", BROKEN, ids=[b[0] for b in BROKEN])
def test_every_reader_refuses_a_file_that_fails_the_check(good, tmp_path, what, make,
                                                          fragment):
    """info, plot, view, orbit and atlas.open share one check: one line, exit 2, nothing
    written next to the file."""
    bad = make(good, tmp_path)
    before = bad.read_bytes()
    for args in (["info", bad], ["plot", bad], ["view", bad], ["orbit", bad, "0.5", "0"]):
        refused(cli(*args), 2, "bad.h5", fragment)
    with pytest.raises(atlas.InputFileError, match=re.escape(fragment)):
        atlas.open(bad)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.h5"]
    assert bad.read_bytes() == before


@pytest.mark.parametrize("version", [None, 2])
def test_an_older_format_is_refused_naming_its_version(good, tmp_path, version):
    """Files of an older layout (format 1: no ``format_version``; 2: α and ω0 as attributes)
    are refused with one line naming their version, for every reader."""
    path = _h5(_attr("format_version", None if version is None else np.int64(version)))(
        good, tmp_path)
    with h5py.File(path, "r") as f:
        assert ("format_version" in f.attrs) == (version is not None)
    code, out, err = cli("info", path)
    assert code == 2 and f"format_version {version or 1}, an older layout" in err, err
    assert len(err.strip().splitlines()) == 1
    with pytest.raises(atlas.InputFileError, match="run its config again"):
        atlas.open(path)


def test_info_shows_untrusted_attributes_on_one_line(good, tmp_path):
    path = _h5(_attr("created", "2026\nFAKE LINE"))(good, tmp_path)
    code, out, _ = cli("info", path)
    assert code == 0 and not any(line.startswith("FAKE") for line in out.splitlines())


def test_a_damaged_partial_manifest_is_one_line(tmp_path):
    partial = tmp_path / "x.h5.partial"
    (partial / "tiles").mkdir(parents=True)
    (partial / "manifest.json").write_text('{"schema": "atlas-partial/2", "layout": 7}')
    refused(cli("info", partial), 2, "x.h5.partial", "cannot be read")


# ---- the output of a run: never the config, never a file atlas did not write --------------

def test_the_config_is_never_its_own_output(tmp_path):
    cfg = tiny_config(tmp_path, tmp_path / "c.h5")
    before = cfg.read_bytes()
    link = tmp_path / "link.h5"
    link.symlink_to(cfg)
    for output in (cfg, link, Path(os.path.relpath(cfg))):
        for extra in ([], ["--force"]):
            refused(cli("run", cfg, "-o", output, "--quiet", *extra), 2,
                    "the output path is the config file being run")
    assert cfg.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml", "link.h5"]


def test_a_file_atlas_did_not_write_is_kept_unless_force(tmp_path, good):
    cfg = tiny_config(tmp_path, tmp_path / "c.h5")
    precious = tmp_path / "notes.h5"
    precious.write_bytes(b"my notes")
    refused(cli("run", cfg, "-o", precious, "--quiet"), 2, "notes.h5",
            "atlas did not write", "--force")
    assert precious.read_bytes() == b"my notes"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml", "notes.h5"]
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = np.arange(3)
    refused(cli("run", cfg, "-o", foreign, "--quiet"), 2, "atlas did not write")
    store = tmp_path / "other.zarr"
    store.mkdir()
    (store / "zarr.json").write_text(json.dumps({"zarr_format": 3, "node_type": "group",
                                                 "attributes": {}}))
    refused(cli("run", cfg, "-o", store, "--quiet"), 2, "Zarr store that atlas did not write")
    assert cli("run", cfg, "-o", precious, "--quiet", "--force")[0] == 0
    atlas.open(precious).close()


@pytest.mark.slow
def test_a_config_may_run_again_over_an_atlas_file(tmp_path, good):
    """`make` re-runs a changed config over its own finished output; another config's atlas
    file may be written over as well."""
    out = _copy(good, tmp_path, "out.h5")
    cfg = tiny_config(tmp_path, out)
    for _ in range(2):
        code, _, err = cli("run", cfg, "--quiet")
        assert code == 0, err
    assert json.loads(atlas.open(out).attrs["config"])["grid"]["theta0"]["num"] == 12


# ---- logging, exit statuses ----------------------------------------------------------------

@pytest.mark.slow
def test_vv_logs_atlas_detail_not_numba_internals(tmp_path):
    cfg = tiny_config(tmp_path, tmp_path / "v.h5")
    code, _, err = cli("run", "-vv", cfg, "--quiet")
    assert code == 0, err
    assert logging.getLogger("atlas").getEffectiveLevel() == logging.DEBUG
    for name in ("numba", "numba.core.ssa", "numba.core.byteflow", "filelock"):
        assert logging.getLogger(name).getEffectiveLevel() >= logging.WARNING, name
    cli("run", cfg, "--quiet")
    assert logging.getLogger("atlas").getEffectiveLevel() == logging.WARNING


def test_every_exit_status_is_documented():
    from atlas.pipeline.lock import OutputLocked

    codes = {cls: cls.exit_code for cls in (
        errors.AtlasError, errors.ConfigError, errors.InputFileError, errors.OutputInTheWay,
        errors.BackendUnavailable, errors.StorageError, errors.SeparatrixError, OutputLocked)}
    assert set(codes.values()) == {1, 2, 3}
    assert {c for c, code in codes.items() if code == 1} == {errors.StorageError,
                                                             errors.SeparatrixError}
    readme = (REPO / "README.md").read_text()
    section = readme[readme.index("## When something goes wrong"):]
    for status in (0, 1, 2, 3, errors.EXIT_INEXACT, 130, 143):
        assert f"**{status}**" in section, status


# ---- the page shows what a file says as text -----------------------------------------------

def test_the_page_escapes_names_attributes_and_file_names(tmp_path, good):
    evil = tmp_path / f"{XSS.replace('/', '_')}.h5"
    shutil.copyfile(good, evil)
    with h5py.File(evil, "a") as f:
        config = json.loads(f.attrs["config"])
        config["name"] = XSS
        f.attrs["config"] = json.dumps(config)
        for name in ("title", "created", "atlas_version"):
            f.attrs[name] = XSS + "<img src=x onerror=alert(2)>"
    page = tmp_path / "page.html"
    code, _, err = cli("view", evil, "-o", page)
    assert code == 0, err
    html = page.read_text(encoding="utf-8")
    assert XSS not in html and "<script>alert" not in html and "<img" not in html
    assert html.count("<script") == 2 and html.count("</script>") == 2
    data = json.loads(re.search(r'id="atlas-data">(.*?)</script>', html, re.S).group(1))
    assert data["name"] == XSS and data["created"].startswith(XSS)
    assert data["file"] == evil.name


@pytest.mark.slow
def test_zarr_atlas_is_checked_too(tmp_path):
    pytest.importorskip("zarr")
    out = tmp_path / "z.zarr"
    code, _, err = cli("run", tiny_config(tmp_path, out), "--quiet")
    assert code == 0, err
    atlas.open(out).close()
    import zarr

    zarr.open_group(out, mode="r+").attrs["format_version"] = FORMAT_VERSION + 5
    with warnings.catch_warnings():  # consolidated metadata: not in the v3 spec yet
        warnings.simplefilter("ignore")
        zarr.consolidate_metadata(out)
    refused(cli("info", out), 2, "z.zarr", "is newer than this atlas reads")


def test_xarray_default_open_still_reads_the_file(good):
    """The check does not change the file: plain xarray opens it as before."""
    with xr.open_dataset(good, engine="h5netcdf") as ds:
        assert "attractor" in ds


def test_a_partial_file_from_an_older_atlas_is_refused(tmp_path):
    """A ``.partial`` file (atlas before the tile store) or an unreadable manifest at the
    output: one line naming --restart; nothing in it is touched."""
    out = tmp_path / "x.h5"
    cfg = tiny_config(tmp_path, out)
    partial = tmp_path / "x.h5.partial"
    partial.write_bytes(b"an older atlas's partial file")
    refused(cli("run", cfg, "--quiet"), 2, "x.h5.partial", "cannot continue this partial run",
            "--restart")
    assert partial.read_bytes() == b"an older atlas's partial file" and not out.exists()
    partial.unlink()
    (partial / "tiles").mkdir(parents=True)
    (partial / "manifest.json").write_text("{broken")
    refused(cli("run", cfg, "--quiet"), 2, "cannot continue this partial run")
    assert (partial / "manifest.json").read_text() == "{broken"


def test_an_integer_beyond_float_range_in_a_config_is_one_line(tmp_path):
    """Found by tests/commands/test_fuzz.py at ATLAS_FUZZ_SCALE=10."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"pendulum: {{alpha: 1{'0' * 400}}}\n")
    refused(cli("run", cfg, "-o", tmp_path / "x.h5"), 2, "c.yaml", "pendulum.alpha")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]
