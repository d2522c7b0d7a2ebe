"""The real CLI in a subprocess: end to end, and exit status 2 with one line on bad input."""

import h5py
import numpy as np
import pytest

from tests.helpers import run_cli
from tests.pipeline.test_config import BAD


def _one_clean_line(proc, *fragments):
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    assert lines[0].startswith("atlas: error: ")
    for fragment in fragments:
        assert fragment in lines[0]
    return lines[0]


@pytest.mark.slow
def test_run_info_plot_end_to_end(small_config, tmp_path):
    cfg = small_config()
    proc = run_cli("run", cfg)  # one run: its file and its summary (not --quiet)
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "small.h5"
    assert out.exists() and not (tmp_path / "small.h5.partial").exists()
    assert "24 x 16" in proc.stdout and "basins" in proc.stdout and "unresolved 0" in proc.stdout
    info = run_cli("info", out)
    assert info.returncode == 0, info.stderr
    assert "complete" in info.stdout and "alpha = 0.1" in info.stdout
    assert "area fraction (exact)" in info.stdout and "d_cert" in info.stdout
    plot = run_cli("plot", out)
    assert plot.returncode == 0, plot.stderr
    assert (tmp_path / "small.png").stat().st_size > 10_000
    assert (tmp_path / "small_t_trap.png").stat().st_size > 10_000
    assert (tmp_path / "small_boundary_distance.png").stat().st_size > 10_000


@pytest.mark.slow
def test_bad_config_exits_2_and_writes_nothing(tmp_path):
    cfg = tmp_path / "bad.yaml"
    out = tmp_path / "out.h5"
    cfg.write_text(f"pendulum: {{alpha: 0.1, omga0: 1}}\noutput: {out}\n")
    _one_clean_line(run_cli("run", cfg), "bad.yaml", "pendulum.omga0", "unknown key")
    assert list(tmp_path.iterdir()) == [cfg]


@pytest.mark.slow
def test_bad_config_does_not_overwrite_an_existing_output(tmp_path):
    out = tmp_path / "out.h5"
    out.write_bytes(b"precious")
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(f"integrator: {{dt: -1}}\noutput: {out}\n")
    _one_clean_line(run_cli("run", cfg), "integrator.dt")
    assert out.read_bytes() == b"precious"


@pytest.mark.slow
@pytest.mark.parametrize("args,fragment", [
    (["run"], "the following arguments are required: config"),
    (["run", "nope.yaml"], "nope.yaml: no such config file"),
    (["frobnicate"], "invalid choice"),
    (["run", "configs/default.yaml", "--backend", "tpu"], "invalid choice"),
    (["run", "configs/default.yaml", "--bogus"], "unrecognized arguments"),
])
def test_bad_arguments(args, fragment):
    _one_clean_line(run_cli(*args), fragment)


@pytest.mark.slow
def test_info_and_plot_refuse_files_that_are_not_atlases(tmp_path):
    missing = tmp_path / "missing.h5"
    text = tmp_path / "text.h5"
    text.write_text("not hdf5 at all")
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = np.arange(3)
    for cmd in ("info", "plot"):
        _one_clean_line(run_cli(cmd, missing), "missing.h5", "no such file")
        _one_clean_line(run_cli(cmd, text), "text.h5", "not an atlas file")
        _one_clean_line(run_cli(cmd, foreign), "foreign.h5", "not an atlas")


@pytest.mark.slow
def test_truncated_file_is_refused(small_atlas_file, tmp_path):
    data = small_atlas_file.read_bytes()
    cut = tmp_path / "cut.h5"
    cut.write_bytes(data[: len(data) // 2])
    _one_clean_line(run_cli("info", cut), "cut.h5")
    _one_clean_line(run_cli("plot", cut), "cut.h5")
    assert not (tmp_path / "cut.png").exists()


@pytest.mark.slow
def test_cuda_backend_without_a_gpu_is_one_clear_line(small_config, tmp_path):
    env = {k: v for k, v in __import__("os").environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    proc = run_cli("run", small_config(), "--backend", "cuda", env=env)
    _one_clean_line(proc, "backend 'cuda'")
    assert not (tmp_path / "small.h5").exists()


@pytest.mark.slow
def test_a_cuda_override_of_a_trigfree_config_is_one_clear_line(tmp_path):
    """``--backend cuda`` on a config with ``integrator.method: rk4-trigfree``: refused before
    anything is written (the CUDA kernels run rk4 only), GPU or not."""
    cfg = tmp_path / "tf.yaml"
    cfg.write_text(f"integrator: {{method: rk4-trigfree}}\noutput: {tmp_path / 'tf.h5'}\n")
    proc = run_cli("run", cfg, "--backend", "cuda")
    _one_clean_line(proc, f"{cfg}: integrator.method: 'rk4-trigfree' has no CUDA kernel")
    assert list(tmp_path.iterdir()) == [cfg]


@pytest.mark.slow
@pytest.mark.parametrize("text,message", BAD, ids=[m for _, m in BAD])
def test_every_bad_config_through_the_cli(tmp_path, text, message):
    out = tmp_path / "out.h5"
    out.write_bytes(b"an earlier result")
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(text)
    _one_clean_line(run_cli("run", cfg, "-o", out), "bad.yaml", message)
    assert out.read_bytes() == b"an earlier result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml", "out.h5"]


@pytest.mark.slow
def test_figures_and_bench_refuse_an_output_folder_they_cannot_make(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    _one_clean_line(run_cli("figures", "--outdir", blocker / "figs"), "cannot create")
    _one_clean_line(run_cli("bench", "--quick", "--output", blocker / "b.json"), "cannot create")


def test_python_dash_m_atlas_and_the_bench_modules():
    """``python -m atlas`` is the CLI; the GPU benchmark (with its driven pendulum's row)
    does not import the CPU one (the CPU benchmark calls the GPU rows, never the other way
    round)."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "atlas", "bench", "--help"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("usage: atlas bench") and "--quick" in proc.stdout
    probe = ("import sys, atlas.commands.bench_gpu; "
             "print(sorted(m for m in sys.modules if m.startswith('atlas.commands.bench')))")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["['atlas.commands.bench_gpu',",
                                   "'atlas.commands.bench_gpu_driven']"]


@pytest.mark.slow
def test_plot_and_open_refuse_a_partial_file(small_config, tmp_path):
    import atlas
    from atlas.pipeline.identity import run_identity
    from atlas.pipeline.sweep import layout_of
    from atlas.store import partial as store
    from atlas.store.partial import TileStore

    cfg = atlas.load_config(small_config())
    partial = store.partial_path(cfg.output)
    TileStore.create(partial, layout_of(cfg), run_identity(cfg, "cpu"), {})
    _one_clean_line(run_cli("plot", partial), "a partial atlas", "atlas run CONFIG")
    assert not partial.with_suffix(".png").exists()
    with pytest.raises(atlas.InputFileError, match="partial"):
        atlas.open(partial)
