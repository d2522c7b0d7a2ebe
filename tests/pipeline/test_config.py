"""Configs: good ones load, every kind of bad one is a ConfigError naming the key."""

import math
from pathlib import Path

import pytest

from atlas import ConfigError, load_config
from atlas.pipeline.config import Config, parse_pi_expression

CONFIGS = sorted(Path(__file__).resolve().parents[2].glob("configs/*.yaml"))


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_shipped_configs_load(path):
    cfg = load_config(path)
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
    ("pendulum: {alpha: 0.1, omga0: 1}", "pendulum.omga0: unknown key"),
    ("pendulumm: {alpha: 0.1}", "pendulumm: unknown key"),
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
    ("separatrices: {tol: 1.0e-14}", "separatrices.tol = 1e-14 is below what double precision"),
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
