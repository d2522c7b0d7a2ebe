"""``make atlas CONFIG=…``: the atlas file is a target of its config, its figures a target of
the file, so figures missing after an ``atlas run`` of the same config are drawn."""

from __future__ import annotations

import os
import shutil
import subprocess

import pytest

from tests.helpers import REPO

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="no make")


def _dry_run(config) -> list[str]:
    """The commands ``make atlas CONFIG=config`` would run (the venv taken as installed)."""
    proc = subprocess.run(["make", "-n", "atlas", f"CONFIG={config}",
                           "-o", ".venv/.installed-run"],
                          cwd=REPO, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    return [line for line in proc.stdout.splitlines() if "atlas " in line]


def test_make_atlas_draws_the_figures_a_run_did_not(tmp_path):
    out = tmp_path / "m.h5"
    config = tmp_path / "m.yaml"
    config.write_text(f"name: m\noutput: {out}\n")
    assert [line.split()[1] for line in _dry_run(config)] == ["run", "plot"]
    out.write_bytes(b"")  # as `atlas run` left it: newer than its config, no figures
    os.utime(config, (1, 1))
    assert _dry_run(config) == [f".venv/bin/atlas plot {out}"]
    (tmp_path / "m.png").write_bytes(b"")  # drawn: nothing to do
    assert _dry_run(config) == []
