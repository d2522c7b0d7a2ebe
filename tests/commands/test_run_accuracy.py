"""``atlas run`` and its accuracy check: a run whose traced separatrices lie farther from the
DOP853 stable manifold than their bound says so on stderr even with --quiet, keeps its file,
and exits 4 unless --accept-inexact."""

from __future__ import annotations

import h5py
import pytest

from tests.helpers import run_cli, write_config

#: dt = 0.05 puts the RK4 map's boundary about 1e-7 from the exact one, beyond the check's
#: bound (1e-8). (A coarse tol no longer does: a shot's point is its Newton estimate, within
#: about 1e-13 of the RK4 map's boundary whatever the bracket's width.)
COARSE = """\
name: coarse
pendulum: {{alpha: 0.5, omega0: 1.0}}
grid:
  theta0: {{start: -pi, stop: pi, num: 16}}
  theta_dot0: {{start: -2, stop: 2, num: 12}}
integrator: {{dt: 0.05, t_max: 100}}
separatrices: {{enabled: true, max_spacing: 0.5}}
output: {output}
"""


@pytest.mark.slow
def test_an_inexact_run_keeps_its_file_warns_and_exits_4(tmp_path):
    out = tmp_path / "coarse.h5"
    cfg = write_config(tmp_path / "c.yaml", COARSE.format(output=out))
    proc = run_cli("run", cfg, "--quiet")
    with h5py.File(out, "r") as f:  # the file, read without atlas: the check did exceed
        sep = f["separatrices"].attrs
        assert sep["discrepancy"].item() > sep["discrepancy_bound"].item()
    assert proc.returncode == 4, proc.stderr
    assert proc.stdout == ""  # --quiet: no summary ...
    lines = proc.stderr.strip().splitlines()  # ... but the warning and the exit's reason
    assert len(lines) == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "EXCEEDS bound 1e-08" in lines[0] and "alpha = 0.5" in lines[0]
    assert f"{out} is written" in lines[1] and "--accept-inexact" in lines[1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml", "coarse.h5"]

    accepted = run_cli("run", cfg, "--accept-inexact")
    assert accepted.returncode == 0, accepted.stderr
    assert "EXCEEDS bound" in accepted.stderr and "EXCEEDS bound" in accepted.stdout
    assert "is written, but" not in accepted.stderr
