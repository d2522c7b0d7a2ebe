"""The Makefile's two install stamps: ``make run`` installs the runtime only, ``make test`` the
dev extras too, and neither order installs a thing twice or recomputes the atlas for nothing.

The Makefile runs in a scratch folder whose ``.venv/bin/python`` is a script that records its
arguments, so each test reads exactly which pip commands make ran.
"""

from __future__ import annotations

import os
import shutil
import subprocess

import pytest

from tests.helpers import REPO

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="no make")

RUN, DEV = ".venv/.installed-run", ".venv/.installed"


@pytest.fixture
def checkout(tmp_path):
    """A folder with the Makefile, a pyproject.toml older than anything made, and a recording
    ``.venv/bin/python``."""
    shutil.copy(REPO / "Makefile", tmp_path)
    (tmp_path / "pyproject.toml").write_text("")
    os.utime(tmp_path / "pyproject.toml", (1, 1))
    python = tmp_path / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(f'#!/bin/sh\necho "$*" >> {tmp_path / "pip.log"}\n'
                      '[ "$3" = show ] && exit 1; exit 0\n')  # pip show: the old name is absent
    python.chmod(0o755)
    return tmp_path


def _make(checkout, target: str) -> list[str]:
    """The ``pip install -e`` commands that ``make target`` ran."""
    log = checkout / "pip.log"
    log.unlink(missing_ok=True)
    proc = subprocess.run(["make", target], cwd=checkout, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    ran = log.read_text().splitlines() if log.exists() else []
    return [line for line in ran if line.startswith("-m pip install --quiet -e")]


def test_run_installs_the_runtime_only_and_test_adds_the_dev_extras(checkout):
    assert _make(checkout, RUN) == ["-m pip install --quiet -e ."]
    assert _make(checkout, RUN) == []
    assert _make(checkout, DEV) == ["-m pip install --quiet -e .[dev]"]
    assert _make(checkout, RUN) == []
    assert _make(checkout, DEV) == []


def test_after_the_dev_install_the_runtime_is_not_installed_again(checkout):
    assert _make(checkout, DEV) == ["-m pip install --quiet -e .[dev]"]
    assert _make(checkout, RUN) == []
    assert (checkout / RUN).exists()


def test_a_dev_install_does_not_make_the_atlas_out_of_date(checkout):
    """``make run``, ``make test``, ``make run``: the second run finds the atlas up to date."""
    _make(checkout, RUN)
    run_stamp = (checkout / RUN).stat().st_mtime_ns
    _make(checkout, DEV)
    assert (checkout / RUN).stat().st_mtime_ns == run_stamp


def test_a_changed_pyproject_installs_again(checkout):
    _make(checkout, DEV)
    later = (checkout / DEV).stat().st_mtime + 10
    os.utime(checkout / "pyproject.toml", (later, later))  # newer than both stamps
    assert _make(checkout, RUN) == ["-m pip install --quiet -e ."]
    assert _make(checkout, DEV) == ["-m pip install --quiet -e .[dev]"]
