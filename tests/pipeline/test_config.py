"""Configs: good ones load, every kind of bad one is a ConfigError naming the key."""

import math
from pathlib import Path

import pytest

from atlas import ConfigError, load_config
from atlas.pipeline.config import Config, parse_pi_expression

CONFIGS = sorted(Path(__file__).resolve().parents[2].glob("configs/*.yaml"))
#: The shipped configs of ``atlas stability`` (validated as studies: no grid run's checks).
STUDIES = ("swing_stability.yaml",)


def _load_shipped(path: Path) -> Config:
    return load_config(path, study=path.name in STUDIES)


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_shipped_configs_load(path):
    cfg = _load_shipped(path)
    assert isinstance(cfg, Config)


def test_default_config_is_the_essays_figure_9():
    cfg = load_config(CONFIGS[[p.name for p in CONFIGS].index("default.yaml")])
    assert (cfg.pendulum.alpha, cfg.pendulum.omega0) == (0.1, 1.0)
    assert cfg.grid.theta0.start == -3 * math.pi and cfg.grid.theta0.stop == 3 * math.pi
    assert (cfg.grid.theta0.num, cfg.grid.theta_dot0.num) == (512, 512)
    assert str(cfg.output) == "outputs/default.h5"


def test_empty_config_gives_the_defaults(tmp_path):
    (tmp_path / "c.yaml").write_text("")
    assert load_config(tmp_path / "c.yaml") == Config()


@pytest.mark.parametrize("text,value", [
    ("3pi", 3 * math.pi), ("-pi/2", -math.pi / 2), ("2*pi", 2 * math.pi), ("pi", math.pi),
    ("-3pi", -3 * math.pi), ("0.5pi", 0.5 * math.pi), ("(1+2)*pi/3", math.pi), ("1e3", 1000.0),
    ("π/4", math.pi / 4), (" 2 pi ", 2 * math.pi),
])
def test_pi_expressions(text, value):
    assert parse_pi_expression(text) == pytest.approx(value, rel=1e-15)


@pytest.mark.parametrize("text", ["pi pi", "3pie", "__import__('os')", "2**pi", "pi/0", "",
                                  "1e999*0", "abs(-1)"])
def test_bad_pi_expressions(text):
    with pytest.raises(ValueError):
        parse_pi_expression(text)


BAD = [
    ("pendulum: {alpha: 0.1, omga0: 1}", "pendulum.omga0: unknown key (did you mean omega0?)"),
    ("pendulumm: {alpha: 0.1}", "pendulumm: unknown key (did you mean pendulum?)"),
    ("grid: {theta0: {start: 0, stop: 1, n: 8}}", "grid.theta0.n: unknown key (did you mean num?)"),
    ("grid: {theta-dot0: {start: 0, stop: 1, num: 8}}",
     "grid.theta-dot0: unknown key (did you mean theta_dot0?)"),
    ("integrator: {dt: -1, tmax: 5}", "integrator.tmax: unknown key (did you mean t_max?)"),
    ("pendulum: {alpha: fast}", "pendulum.alpha"),
    ("pendulum: {alpha: .nan}", "pendulum.alpha"),
    ("pendulum: {alpha: .inf}", "pendulum.alpha"),
    ("pendulum: {alpha: -0.1}", "pendulum.alpha: damping must be >= 0"),
    ("pendulum: {alpha: 0}", "no orbit ever settles"),
    ("pendulum: {omega0: 0}", "pendulum.omega0: must be > 0"),
    ("pendulum: {omega0: -1}", "pendulum.omega0"),
    ("pendulum: {alpha: [0.1, -1, 0.3]}", "pendulum.alpha: item 1: damping must be >= 0"),
    ("pendulum: {alpha: [0.1, fast]}", "pendulum.alpha: item 1: cannot read 'fast'"),
    ("pendulum: {omega0: [1, .nan]}", "pendulum.omega0: item 1: must be a finite number"),
    ("pendulum: {alpha: []}", "pendulum.alpha"),
    ("pendulum: {alpha: true}", "pendulum.alpha"),
    ("integrator: {dt: 0}", "integrator.dt: must be greater than 0 (got 0.0)"),
    ("integrator: {dt: -0.01}", "integrator.dt"),
    ("integrator: {dt: 3.0}", "integrator.dt = 3 is beyond RK4's stability limit"),
    ("integrator: {t_max: 0}", "integrator.t_max"),
    ("integrator: {t_max: 1e9, dt: 0.001}", "steps per orbit is more than"),
    ("grid: {theta0: {start: 0, stop: 1e6, num: 8}}", "beyond the wells |k| ≤ 32767"),
    ("grid: {theta_dot0: {start: 0, stop: 1e5, num: 8}}", "grid: orbits from this window"),
    ("grid: {theta0: {start: 0, stop: 1, num: 1}}", "grid.theta0.num"),
    ("grid: {theta0: {start: 1, stop: 1, num: 8}}", "grid.theta0: start (1) must be less"),
    ("grid: {theta0: {start: 3pi, stop: -3pi, num: 8}}", "grid.theta0"),
    ("grid: {theta0: {start: 3pie, stop: 4, num: 8}}", "grid.theta0.start: cannot read '3pie'"),
    ("grid: {theta0: {start: 0, stop: 1}}", "grid.theta0.num: missing"),
    ("grid: {theta0: {start: 0, stop: 1, num: 2.5}}", "grid.theta0.num"),
    ("separatrices: {tol: 0}", "separatrices.tol"),
    ("separatrices: {max_spacing: 1.0e-6}", "separatrices.max_spacing = 1e-06 is below 0.0001"),
    ("execution: {backend: gpu}", "execution.backend"),
    ("integrator: {method: rk5}", "integrator.method: must be 'rk4' or 'rk4-trigfree'"),
    ("integrator: {method: rk4-trigfree}\nexecution: {backend: cuda}",
     "integrator.method: 'rk4-trigfree' has no CUDA kernel"),
    ("integrator: {method: rk4-trigfree}\npendulum: {torque: [0, 0.5]}",
     "integrator.method: 'rk4-trigfree' is for the pendulum without torque"),
    ("name: [1, 2]", "name"),
    ("- 1\n- 2", "a config must be a mapping"),
    ("pendulum: {alpha: 0.1\n", "line"),
    ("grid:\n  theta0: {start: 0, stop: 1, num: 4}\n   bad: indent", "YAML syntax error"),
    ("pendulum:\n  alpha: 0.1\n  omega0: 1\n  alpha: 0.2\n",
     "line 4: key 'alpha' given twice (first on line 2)"),
    ("name: a\nname: b\n", "line 2: key 'name' given twice (first on line 1)"),
    ("a: &x 1\nname: *x\n", "line 1: YAML anchors and aliases"),
    ("pendulum: {omega0: 1.0e+300}", "pendulum.omega0: must be between 1e-06 and 1e+06"),
    ("pendulum: {omega0: 1.0e-300}", "pendulum.omega0: must be between 1e-06 and 1e+06"),
    ("pendulum: {alpha: 1.0e+300}", "pendulum.alpha: must be at most 1e+06"),
    ("pendulum: {alpha: [0.1, 1.0e+200]}", "pendulum.alpha: item 1: must be at most"),
]


@pytest.mark.parametrize("text,message", BAD, ids=[m for _, m in BAD])
def test_bad_configs_name_the_key(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    line = str(info.value)
    assert message in line
    assert line.startswith(str(path)) and "\n" not in line


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(ConfigError, match="no such config file"):
        load_config(tmp_path / "nope.yaml")
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(tmp_path)  # a directory
    binary = tmp_path / "b.yaml"
    binary.write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(binary)


def test_billion_laughs_is_refused_at_once(tmp_path):
    """Nine levels of nested aliases would expand to 9⁹ items: refused before expansion."""
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]" for i in range(1, 9)]
    path = tmp_path / "laughs.yaml"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError, match="anchors and aliases"):
        load_config(path)  # a hang here would time the test suite out


def test_oversized_config_is_refused_unread(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text("name: " + "x" * (2 << 20) + "\n")
    with pytest.raises(ConfigError, match="too large for a config"):
        load_config(path)


def test_yaml_error_reports_the_line(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("name: x\npendulum: {alpha: 0.1\noutput: y\n")
    with pytest.raises(ConfigError, match=r"line \d+"):
        load_config(path)


def test_parameter_lists_make_a_sweep(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("pendulum: {alpha: [0.1, 0.5, 2pi/4], omega0: 1}")
    cfg = load_config(path)
    assert cfg.pendulum.swept == ("alpha",)  # only the lists are dims
    assert cfg.pendulum.alphas == pytest.approx([0.1, 0.5, math.pi / 2])
    assert cfg.pendulum.omega0s == [1.0] and cfg.pendulum.torques == [0.0]
    assert [p["alpha"] for p in cfg.pendulum.points] == pytest.approx([0.1, 0.5, math.pi / 2])
    path.write_text("pendulum: {omega0: [1, 2], torque: [0, 0.25, 0.5]}")
    pendulum = load_config(path).pendulum
    assert pendulum.swept == ("omega0", "torque")
    assert [(p["omega0"], p["torque"]) for p in pendulum.points] == \
        [(1, 0), (1, 0.25), (1, 0.5), (2, 0), (2, 0.25), (2, 0.5)]  # C order over the dims


def test_a_single_point_config_sweeps_nothing():
    cfg = Config()
    assert cfg.pendulum.swept == () and len(cfg.pendulum.points) == 1
    assert cfg.pendulum.points[0] == {"alpha": 0.1, "omega0": 1.0, "torque": 0.0}


def test_output_override(tmp_path):
    (tmp_path / "c.yaml").write_text("output: a.h5")
    assert str(load_config(tmp_path / "c.yaml", output="b.h5").output) == "b.h5"


@pytest.mark.parametrize("key", ["alpha", "omega0", "torque"])
def test_a_value_listed_twice_is_refused(tmp_path, key):
    """A parameter point is named by its values: a sweep may not list one value twice."""
    path = tmp_path / "twice.yaml"
    path.write_text(f"pendulum: {{{key}: [0.5, 0.25, 0.5]}}")
    with pytest.raises(ConfigError, match=f"pendulum.{key}: the value 0.5 is listed twice"):
        load_config(path)


def test_an_unknown_key_with_no_near_one_gets_no_guess(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("pendulum: {colour: red}")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value).endswith("pendulum.colour: unknown key")


def _warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]


@pytest.mark.parametrize("start,stop,hint", [
    ("-90", "90", "did you mean -pi/2 … pi/2?"),
    ("-180", "180", "did you mean -pi … pi?"),
    ("0", "360", "did you mean 0 … 2pi?"),
    ("-45", "135", "did you mean -pi/4 … 3pi/4?"),
    ("-10pi", "10pi", None),  # ten turns: wide, not degrees
])
def test_a_window_that_looks_like_degrees_warns(tmp_path, caplog, start, stop, hint):
    """θ0 is in radians: a window with ends like ±90 or ±180, or wider than 8 turns, loads
    (it is valid) with one warning; where both ends are whole numbers, the hint reads them
    as degrees (90° = π/2)."""
    path = tmp_path / "deg.yaml"
    path.write_text(f"grid: {{theta0: {{start: {start}, stop: {stop}, num: 8}}}}\n")
    cfg = load_config(path)
    turns = (cfg.grid.theta0.stop - cfg.grid.theta0.start) / (2 * math.pi)
    units = [w for w in _warnings(caplog) if "radians" in w]
    assert len(units) == 1
    assert units[0].startswith(f"warning: {path}: grid.theta0: θ0 is in radians")
    assert f"spans {turns:.1f} turns" in units[0] and "check_radians: false" in units[0]
    assert (hint in units[0]) if hint else ("did you mean" not in units[0])
    caplog.clear()
    path.write_text(path.read_text() + "check_radians: false\n")
    silenced = load_config(path)
    assert not [w for w in _warnings(caplog) if "radians" in w]
    assert silenced.check_radians is False


def test_the_units_key_changes_no_result(tmp_path):
    """``check_radians`` silences a warning; it is not part of the run's identity, its hash,
    or (at its default) the config stored in a file."""
    from atlas.pipeline.config import config_hash
    from atlas.pipeline.identity import run_identity

    loud, quiet = Config(), Config(check_radians=False)
    assert run_identity(loud, "cpu") == run_identity(quiet, "cpu")
    assert config_hash(loud) == config_hash(quiet)
    assert "check_radians" not in loud.to_json() and '"check_radians": false' in quiet.to_json()


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_shipped_configs_load_without_warnings(path, caplog):
    _load_shipped(path)
    assert _warnings(caplog) == []


@pytest.mark.parametrize("window,tol", [("{start: -3pi, stop: 3pi, num: 8}", 1e-14),
                                        ("{start: -180, stop: 180, num: 8}", 1e-12)])
def test_a_tol_finer_than_doubles_resolve_is_raised_with_a_warning(tmp_path, caplog, window,
                                                                    tol):
    """A bisection bracket narrower than 64 spacings of doubles at the window's largest |θ0|
    cannot be resolved: the finest that can (rounded up to two digits) is used, and said.
    (±180 was refused over this, a setting its user never chose.)"""
    import numpy as np

    path = tmp_path / "c.yaml"
    path.write_text(f"grid: {{theta0: {window}}}\nseparatrices: {{tol: {tol!r}}}\n")
    cfg = load_config(path)
    need = 64 * np.spacing(max(abs(cfg.grid.theta0.start), abs(cfg.grid.theta0.stop)))
    step = 10.0 ** (math.floor(math.log10(need)) - 1)  # one unit of the second digit
    used = cfg.separatrices.tol
    assert need <= used < need + step and float(f"{used:.1e}") == used  # two digits, up
    line = next(w for w in _warnings(caplog) if "separatrices.tol" in w)
    assert f"separatrices.tol = {tol:g} is finer than double precision resolves" in line
    assert f"tol = {cfg.separatrices.tol:.2g}" in line


def test_a_window_in_degrees_warns_once_degrees_first(tmp_path, caplog):
    """±180 with a tol of 1e-12 once gave two warnings, the tol's first (a consequence) and
    the degrees' second (the cause): now one, the degrees first, the tol it raised after.
    With ``check_radians: false`` the window is meant, and the tol's warning stands alone."""
    path = tmp_path / "deg.yaml"
    path.write_text("grid: {theta0: {start: -180, stop: 180, num: 8}}\n"
                    "separatrices: {tol: 1.0e-12}\n")
    cfg = load_config(path)
    (line,) = _warnings(caplog)
    degrees, tol = line.index("θ0 is in radians"), line.index("separatrices.tol = 1e-12")
    assert line.startswith(f"warning: {path}: grid.theta0:") and degrees < tol
    assert "did you mean -pi … pi?" in line and f"tol = {cfg.separatrices.tol:.2g}" in line
    caplog.clear()
    path.write_text(path.read_text() + "check_radians: false\n")
    load_config(path)
    (line,) = _warnings(caplog)
    assert line.startswith(f"warning: {path}: separatrices.tol = 1e-12 is finer")
    assert "radians" not in line


def test_a_tol_the_window_resolves_is_kept(tmp_path, caplog):
    path = tmp_path / "c.yaml"
    path.write_text("grid: {theta0: {start: -180, stop: 180, num: 8}}\n"
                    "separatrices: {tol: 1.0e-11}\n")
    assert load_config(path).separatrices.tol == 1e-11
    assert not [w for w in _warnings(caplog) if "separatrices.tol" in w]


@pytest.mark.parametrize("path", [p for p in CONFIGS if p.name not in STUDIES],
                         ids=lambda p: p.name)
def test_every_shipped_sweep_traces_its_separatrices(path):
    """A shipped sweep certifies its labels for the exact equation: its separatrices are on
    (they measure the boundary shift d_cert that certification needs)."""
    assert _load_shipped(path).separatrices.enabled
