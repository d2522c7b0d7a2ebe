"""The shipped configs give the same arrays, bit for bit, as the code that pinned them (the
restructure of "the model as an argument" must change nothing users see).

Each of ``configs/default.yaml``, ``swing.yaml``, ``swing_torque.yaml`` (grid runs) and
``swing_stability.yaml`` (a study) is run on a small grid (``tools.compare_atlases.shrunk``:
48², every sixth torque, a study of 11 torques: the same code paths), and the sha256 of every
variable of every group is compared with ``identity_small.json``, written by the code before
the restructure (the full-size digests are ``tools/identity.json``: ``python -m
tools.compare_atlases --check``). The bytes are those of x86-64 with FMA, as the kernels' own
pins (tests/kernels/test_torque_kernels.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.helpers import needs_fma
from tools.compare_atlases import SHIPPED, compute, digests

PINS = json.loads((Path(__file__).with_name("identity_small.json")).read_text())


@needs_fma
@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_the_shipped_configs_give_the_pinned_arrays(name, tmp_path):
    now = digests(compute(name, tmp_path, small=True))
    pinned = PINS[name]
    assert sorted(set(pinned) - set(now)) == [], "arrays missing"
    changed = sorted(var for var, digest in pinned.items() if now[var] != digest)
    assert changed == [], f"{name}: {len(changed)} arrays changed: {changed[:8]}"


def test_the_fma_gate_sees_what_the_cpu_reports():
    """The pins' gate (tests.helpers.host_has_fma, LLVM's view) agrees with the kernel's own
    list of CPU flags on Linux, so a host without FMA skips the pins instead of failing."""
    from tests.helpers import host_has_fma

    cpuinfo = Path("/proc/cpuinfo")
    if not cpuinfo.exists():
        pytest.skip("no /proc/cpuinfo (not Linux)")
    flags = next(line for line in cpuinfo.read_text().splitlines() if line.startswith("flags"))
    assert host_has_fma() == ("fma" in flags.split(":", 1)[1].split())
