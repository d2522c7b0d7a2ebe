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

from tools.compare_atlases import SHIPPED, compute, digests

PINS = json.loads((Path(__file__).with_name("identity_small.json")).read_text())


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_the_shipped_configs_give_the_pinned_arrays(name, tmp_path):
    now = digests(compute(name, tmp_path, small=True))
    pinned = PINS[name]
    assert sorted(set(pinned) - set(now)) == [], "arrays missing"
    changed = sorted(var for var, digest in pinned.items() if now[var] != digest)
    assert changed == [], f"{name}: {len(changed)} arrays changed: {changed[:8]}"
