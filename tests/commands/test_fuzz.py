"""Property-based hostile input (Hypothesis, seeded): random configs built from the schema's
keys with random types and values (ranges ``{start, stop, num}`` among them), random mutations
of a valid config (values and raw text), random byte-level damage to a valid atlas file, and
the same for ``atlas stability``: random study configs (with the ``stability.*`` keys and
parameter ranges), mutations of a valid one and damaged study files, fed to the real CLI.

Invariant: exit 0 with a sound file, or exit 2 with one ``atlas: error:`` line and nothing
created or overwritten; never a traceback, never a signal. The CLI runs in-process
(``atlas.cli.main``) for speed, a few cases in a subprocess (signals, core dumps).

``make test`` runs a small, fixed number of examples (well under a minute on two cores);
``ATLAS_FUZZ_SCALE=10`` (``make faults`` sets it) runs ten times as many.
"""

from __future__ import annotations

import gc
import io
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import atlas
from atlas import defaults
from atlas.cli import main

REPO = Path(__file__).resolve().parents[2]
SCALE = max(1, int(os.environ.get("ATLAS_FUZZ_SCALE", "1")))
FUZZ = settings(max_examples=40 * SCALE, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))

BASE = {"name": "fuzz", "pendulum": {"alpha": 0.1, "omega0": 1.0},
        "grid": {"theta0": {"start": "-3pi", "stop": "3pi", "num": 6},
                 "theta_dot0": {"start": -4, "stop": 4, "num": 4}},
        "integrator": {"dt": 0.05, "t_max": 20},
        "separatrices": {"enabled": False}, "execution": {"tile_orbits": 8}}
#: Every key of the config schema, as paths (and the sections themselves).
KEYS = [("name",), ("output",), ("check_radians",), ("pendulum",), ("pendulum", "alpha"),
        ("pendulum", "omega0"), ("pendulum", "torque"),
        ("grid",), ("grid", "theta0"), ("grid", "theta_dot0"),
        *[("grid", axis, key) for axis in ("theta0", "theta_dot0")
          for key in ("start", "stop", "num")],
        ("integrator",), ("integrator", "dt"), ("integrator", "t_max"),
        ("integrator", "method"), ("separatrices",),
        ("separatrices", "enabled"), ("separatrices", "tol"), ("separatrices", "max_spacing"),
        ("execution",), ("execution", "backend"), ("execution", "tile_orbits"),
        ("execution", "workers"), ("execution", "scheduler")]

scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-3, 40),
    st.sampled_from([0, -1, 1 << 20, 2**31, 2**63, 10**12, 10**400]),
    st.floats(-50, 50),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 5e-324, 1e-7, 1e7]),
    st.text(max_size=8),
    st.sampled_from(["3pi", "-pi/2", "2*pi", "pi/0", "1e309", "nan", "-inf", "3pie", "~",
                     "</script>", "cpu", "cuda", "dask", "tpu", "/", "..", "\x00", "rk4",
                     "rk4-trigfree", "rk5"]))
#: A parameter range ``{start, stop, num}``: whole with random values, or keys missing or
#: unknown.
ranges = (st.fixed_dictionaries({"start": scalars, "stop": scalars, "num": scalars})
          | st.dictionaries(st.sampled_from(["start", "stop", "num", "step"]), scalars,
                            max_size=4))
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=3)
                      | st.dictionaries(st.text(max_size=6), inner, max_size=3), max_leaves=6
                      ) | ranges
#: Text that YAML or the loader must refuse, spliced into a config.
YAML_SNIPPETS = ["&a [1, 2]\nx: *a", "!!python/object/apply:os.system ['true']", "{", "]",
                 "name: a\nname: b", "\t- x", "? [1]\n: 2", "%TAG !x! y", "--- \n---", "\ufeff",
                 "pendulum: {alpha: 0.1, alpha: 0.2}", "'" * 3, "\x00", "@x"]


def cli(*args) -> tuple[int, str]:
    """``atlas ARGS`` in-process: (exit status, stderr). Any exception escapes (a bug); one
    raised where Python cannot raise it (a ``__del__``) is on stderr as in a process of its
    own: "Exception ignored in …" and its traceback."""
    err = io.StringIO()
    hook = sys.unraisablehook
    sys.unraisablehook = lambda u: err.write(f"Exception ignored in: {u.object!r}\n"
                                             f"Traceback: {u.exc_value!r}\n")
    try:
        with redirect_stdout(io.StringIO()), redirect_stderr(err):
            code = main([str(a) for a in args])
            gc.collect()
    finally:
        sys.unraisablehook = hook
    return code, err.getvalue()


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: (p.read_bytes() if p.is_file() else b"<dir>") for p in folder.iterdir()}


def _one_line(code: int, err: str) -> None:
    lines = err.strip().splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1 and lines[0].startswith("atlas: error: "), err
    assert "Traceback" not in err


def _set(config: dict, path: tuple, value, delete: bool) -> None:
    node = config
    for key in path[:-1]:
        if not isinstance(node.get(key), dict):
            node[key] = {}
        node = node[key]
    if delete:
        node.pop(path[-1], None)
    else:
        node[path[-1]] = value


def _cheap_enough(text: str, folder: Path) -> bool:
    """Run only what a unit test can afford: a valid config whose run is tiny, on the CPU,
    without separatrices (a refused config always runs: refusing is quick)."""
    cfg_path = folder / "probe.yaml"
    cfg_path.write_text(text, encoding="utf-8", errors="surrogateescape")
    try:
        cfg = atlas.load_config(cfg_path, output=folder / "probe.h5")
    except atlas.AtlasError:
        return True
    finally:
        cfg_path.unlink()
    orbits = cfg.grid.theta0.num * cfg.grid.theta_dot0.num * len(cfg.pendulum.points)
    steps = cfg.integrator.t_max / cfg.integrator.dt
    return (orbits * steps <= 2e5 and orbits <= 4096 and cfg.execution.backend == "cpu"
            and not cfg.separatrices.enabled
            and (cfg.execution.tile_orbits or defaults.TILE_ORBITS) >= 4)


#: Torques a config must refuse (one line naming pendulum.torque, exit 2): not numbers, not
#: finite, beyond ±MAX_RATE² (1e12 rad/s²), a bad item of a list, and |τ| = ω0² (the
#: saddle-node, where no basin is certified; ω0 = 1 here).
BAD_TORQUES = [".nan", ".inf", "-.inf", "1.0e+13", "-1.0e+13", "fast", "true", "[0, .nan]",
               "[0.5, 1.0e+13]", "[0.1, fast]", "1", "-1", "[0, 1]", "[]", "{x: 1}"]


@pytest.mark.parametrize("torque", BAD_TORQUES)
def test_bad_torques_are_refused_in_one_line(tmp_path, torque):
    """The torque key is in :data:`KEYS`; these values of it are refused outright (the
    random configs may never draw them)."""
    rest = yaml.safe_dump({k: v for k, v in BASE.items() if k != "pendulum"})
    cfg = tmp_path / "c.yaml"
    cfg.write_text(rest + f"pendulum: {{alpha: 0.1, omega0: 1.0, torque: {torque}}}\n")
    out = tmp_path / "out.h5"
    out.write_bytes(b"an earlier result")
    before = _snapshot(tmp_path)
    code, err = cli("run", cfg, "-o", out, "--quiet")
    _one_line(code, err)
    assert "pendulum.torque" in err, err
    assert _snapshot(tmp_path) == before


def _run_config(text: str, good: Path) -> None:
    """``atlas run`` on ``text`` over an earlier atlas file; check the invariant."""
    with tempfile.TemporaryDirectory(prefix="atlas-fuzz-") as tmp:
        folder = Path(tmp)
        if not _cheap_enough(text, folder):
            return
        cfg = folder / "c.yaml"
        cfg.write_text(text, encoding="utf-8", errors="surrogateescape")
        out = folder / "out.h5"
        shutil.copyfile(good, out)
        before = _snapshot(folder)
        code, err = cli("run", cfg, "-o", out, "--quiet")
        if code == 0:
            atlas.open(out).close()
            assert set(_snapshot(folder)) <= {*before, "out.h5.lock"}, err
        else:
            _one_line(code, err)
            assert _snapshot(folder) == before, err


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> Path:
    """A valid atlas (12 x 8 orbits, separatrices on: its groups are damaged too)."""
    tmp = tmp_path_factory.mktemp("fuzz")
    cfg = {**BASE, "grid": {"theta0": {"start": "-3pi", "stop": "3pi", "num": 12},
                            "theta_dot0": {"start": -4, "stop": 4, "num": 8}},
           "integrator": {"dt": 0.01, "t_max": 100}, "separatrices": {"enabled": True},
           "output": str(tmp / "good.h5")}
    (tmp / "good.yaml").write_text(yaml.safe_dump(cfg))
    code, err = cli("run", tmp / "good.yaml", "--quiet")
    assert code == 0, err
    return tmp / "good.h5"


@pytest.mark.slow
@FUZZ
@given(st.dictionaries(st.sampled_from(KEYS), values, max_size=6)
       | st.dictionaries(st.text(max_size=8), values, max_size=4).map(lambda d: {(k,): v
                                                                                for k, v in
                                                                                d.items()}))
def test_random_configs_from_the_schema(good, entries):
    config: dict = {}
    for path, value in entries.items():
        _set(config, path, value, delete=False)
    _run_config(yaml.safe_dump(config, allow_unicode=True), good)


@pytest.mark.slow
@FUZZ
@given(st.lists(st.tuples(st.sampled_from(KEYS), values, st.booleans()), min_size=1,
                max_size=3))
def test_mutated_valid_configs(good, mutations):
    config = yaml.safe_load(yaml.safe_dump(BASE))
    for path, value, delete in mutations:
        _set(config, path, value, delete)
    _run_config(yaml.safe_dump(config, allow_unicode=True), good)


@FUZZ
@given(st.lists(st.tuples(st.floats(0, 1), st.sampled_from(YAML_SNIPPETS) | st.text(max_size=4),
                          st.integers(0, 3)), min_size=1, max_size=3))
def test_mutated_config_text(good, edits):
    text = yaml.safe_dump(BASE)
    for where, snippet, cut in edits:
        i = int(where * len(text))
        text = text[:i] + snippet + text[i + cut:]
    _run_config(text, good)


def _damage(data: bytes, edits, truncate) -> bytes:
    out = bytearray(data)
    n = len(out)
    for region, offset, byte in edits:  # metadata sits near both ends of an HDF5 file
        i = {0: offset % 4096, 1: offset % n, 2: n - 1 - offset % 4096}[region]
        out[i] = byte
    return bytes(out[: int(truncate * n)] if truncate else out)


@pytest.mark.slow
@FUZZ
@given(st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2**31), st.integers(0, 255)),
                min_size=1, max_size=12),
       st.one_of(st.none(), st.floats(0.0, 1.0, exclude_max=True)))
def test_damaged_atlas_files(good, edits, truncate):
    with tempfile.TemporaryDirectory(prefix="atlas-fuzz-") as tmp:
        bad = Path(tmp) / "bad.h5"
        bad.write_bytes(_damage(good.read_bytes(), edits, truncate))
        try:
            atlas.open(bad).close()
        except atlas.InputFileError:
            pass
        for args in (["info", bad], ["plot", bad], ["view", bad, "-o", Path(tmp) / "v.html"]):
            before = _snapshot(Path(tmp))
            code, err = cli(*args)
            if code != 0:
                _one_line(code, err)
                assert _snapshot(Path(tmp)) == before, (args, err)


@pytest.mark.slow
def test_damaged_files_and_configs_in_a_subprocess(good, tmp_path):
    """No signal, no core dump, no traceback: a few cases through the real executable."""
    rng = random.Random(2026)
    data = good.read_bytes()
    cases = []
    for i in range(2):
        bad = tmp_path / f"bad{i}.h5"
        bad.write_bytes(_damage(data, [(rng.randrange(3), rng.randrange(2**31),
                                        rng.randrange(256)) for _ in range(16)], None))
        cases.append(["info", bad])
    cases.append(["plot", tmp_path / "bad0.h5"])
    hostile = tmp_path / "c.yaml"
    hostile.write_text("pendulum: {omega0: 1e300, alpha: &a [1, *a]}\n")
    cases.append(["run", hostile, "-o", tmp_path / "x.h5"])
    for args in cases:
        proc = subprocess.run([sys.executable, "-m", "atlas.cli", *map(str, args)],
                              capture_output=True, text=True, cwd=REPO, timeout=120)
        assert proc.returncode in (0, 2), (args, proc.returncode, proc.stderr)
        assert "Traceback" not in proc.stderr
        if proc.returncode == 2:
            assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr


# ------------------------------------------------------------------ atlas stability (studies)

STUDY_BASE = {"name": "fuzz-study",
              "pendulum": {"alpha": 0.2, "omega0": 1.0,
                           "torque": {"start": 0.0, "stop": 0.4, "num": 2}},
              "grid": {"theta0": {"start": "-pi", "stop": "pi", "num": 2},
                       "theta_dot0": {"start": -3, "stop": 3, "num": 2}},
              "stability": {"sigma_theta": 0.1, "sigma_theta_dot": 0.2, "tipping": True}}
#: The keys a study reads: the config's, the ``stability`` section's, and each pendulum
#: parameter's range keys.
STUDY_KEYS = [*KEYS, ("stability",), ("stability", "sigma_theta"),
              ("stability", "sigma_theta_dot"), ("stability", "tipping"),
              *[("pendulum", name, key) for name in ("alpha", "omega0", "torque")
                for key in ("start", "stop", "num")]]
#: What a study's run may cost here: points, and wells its window and Gaussian box reach.
STUDY_POINTS, STUDY_WELLS = 3, 6


def _cheap_study(text: str, folder: Path) -> bool:
    """Run only a small study (a refused config always runs: refusing is quick): at most
    STUDY_POINTS points, whose window and Gaussian box stay within STUDY_WELLS wells of
    travel (:func:`atlas.limits.reach`), on this machine."""
    from atlas.limits import reach
    from atlas.stability.gaussian import REACH

    cfg_path = folder / "probe.yaml"
    cfg_path.write_text(text, encoding="utf-8", errors="surrogateescape")
    try:
        cfg = atlas.load_config(cfg_path, output=folder / "probe.h5", study=True)
    except atlas.AtlasError:
        return True
    finally:
        cfg_path.unlink()
    g, stab, alpha = cfg.grid, cfg.stability, min(cfg.pendulum.alphas)
    boxes = [(max(abs(g.theta0.start), abs(g.theta0.stop)),
              max(abs(g.theta_dot0.start), abs(g.theta_dot0.stop)))]
    if stab is not None and stab.sigma_theta is not None:
        boxes.append((math.pi + REACH * stab.sigma_theta, REACH * stab.sigma_theta_dot + 0.5))
    return (len(cfg.pendulum.points) <= STUDY_POINTS and cfg.execution.backend == "cpu"
            and all(reach(t, v, alpha) <= 2 * math.pi * STUDY_WELLS for t, v in boxes))


def _run_study(text: str, good: Path) -> None:
    """``atlas stability`` on ``text`` over an earlier study file; the invariant of
    :func:`_run_config`."""
    from atlas.store.study import open_study

    with tempfile.TemporaryDirectory(prefix="atlas-fuzz-") as tmp:
        folder = Path(tmp)
        if not _cheap_study(text, folder):
            return
        cfg = folder / "c.yaml"
        cfg.write_text(text, encoding="utf-8", errors="surrogateescape")
        out = folder / "out.h5"
        shutil.copyfile(good, out)
        before = _snapshot(folder)
        code, err = cli("stability", cfg, "-o", out)
        if code == 0:
            open_study(out)
            assert set(_snapshot(folder)) <= set(before), err
        else:
            _one_line(code, err)
            assert _snapshot(folder) == before, err


def test_the_valid_study_is_cheap_enough_to_run(tmp_path):
    """The mutations start from a study the fuzzer runs (not one it skips as too dear), so
    that the valid ones among them exercise the path that writes a study."""
    assert _cheap_study(yaml.safe_dump(STUDY_BASE), tmp_path)
    assert not _cheap_study(yaml.safe_dump({**STUDY_BASE, "stability": {
        "sigma_theta": 0.3, "sigma_theta_dot": 0.5}}), tmp_path)  # the bound bites


@pytest.fixture(scope="module")
def good_study(tmp_path_factory) -> Path:
    """A valid study file (2 points, the Gaussian and the tipping probabilities: every
    variable a study stores is there to be damaged)."""
    tmp = tmp_path_factory.mktemp("fuzz-study")
    (tmp / "good.yaml").write_text(yaml.safe_dump({**STUDY_BASE,
                                                   "output": str(tmp / "good.h5")}))
    code, err = cli("stability", tmp / "good.yaml")
    assert code == 0, err
    return tmp / "good.h5"


@pytest.mark.slow
@FUZZ
@given(st.dictionaries(st.sampled_from(STUDY_KEYS), values, max_size=6))
def test_random_study_configs_from_the_schema(good_study, entries):
    config: dict = {}
    for path, value in entries.items():
        _set(config, path, value, delete=False)
    _run_study(yaml.safe_dump(config, allow_unicode=True), good_study)


@pytest.mark.slow
@FUZZ
@given(st.lists(st.tuples(st.sampled_from(STUDY_KEYS), values, st.booleans()), min_size=1,
                max_size=3))
def test_mutated_valid_study_configs(good_study, mutations):
    config = yaml.safe_load(yaml.safe_dump(STUDY_BASE))
    for path, value, delete in mutations:
        _set(config, path, value, delete)
    _run_study(yaml.safe_dump(config, allow_unicode=True), good_study)


@pytest.mark.slow
@FUZZ
@given(st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2**31), st.integers(0, 255)),
                min_size=1, max_size=12),
       st.one_of(st.none(), st.floats(0.0, 1.0, exclude_max=True)))
def test_damaged_study_files(good_study, edits, truncate):
    """``atlas info``, ``atlas info --check`` and ``atlas plot`` of a damaged study file."""
    with tempfile.TemporaryDirectory(prefix="atlas-fuzz-") as tmp:
        bad = Path(tmp) / "bad.h5"
        bad.write_bytes(_damage(good_study.read_bytes(), edits, truncate))
        for args in (["info", bad], ["info", "--check", bad],
                     ["plot", bad, "--outdir", Path(tmp) / "figures"]):
            before = _snapshot(Path(tmp))
            code, err = cli(*args)
            if code != 0:
                _one_line(code, err)
                assert _snapshot(Path(tmp)) == before, (args, err)
