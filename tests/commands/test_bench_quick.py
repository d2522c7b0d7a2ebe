"""``atlas bench --quick`` runs in the suite: not a timing assert (the machine may be loaded),
but the command end to end, in a process of its own, writing a well-formed table: every row
of every section there with finite, positive times and rates, the labels of the compared
kernels and thread counts equal, each section printed with as many rows as the JSON holds,
and the quick run saying what it leaves out."""

from __future__ import annotations

import json
import math

import pytest

from tests.helpers import run_cli

pytestmark = pytest.mark.slow  # the whole quick bench: 15–30 s


def _positive(*values) -> bool:
    return all(isinstance(v, (int, float)) and math.isfinite(v) and v > 0 for v in values)


def test_bench_quick_writes_a_well_formed_table(tmp_path):
    out = tmp_path / "bench.json"
    proc = run_cli("bench", "--quick", "--output", out, timeout=600)
    assert proc.returncode == 0, proc.stderr
    table = proc.stdout.splitlines()
    assert table[-1] == f"wrote {out}"
    result = json.loads(out.read_text())
    assert result["quick"] is True and result["problem"]["grid"] == 128
    # the kernel rows: each timed, each compared with the default map's
    for section in ("map", "bulk"):
        rows = result[section]["rows"]
        assert len(rows) >= 4, section
        for row in rows:
            assert _positive(row["steps_per_s"], row["orbits_per_s"], row["map_s"],
                             row["ratio_to_atlas"]), (section, row)
            assert sum(row["variant"] in line for line in table) >= 1, row["variant"]
    assert result["map"]["labels_equal_straightforward"] is True
    assert result["map"]["trigfree_labels_equal_straightforward"] is True
    for row in result["torque"]["rows"]:
        assert _positive(row["wall_s"], row["orbits_per_s"], row["ratio"]), row
    assert [r["n"] for r in result["scaling"]] == [128, 256]
    for row in result["scaling"]:
        assert _positive(row["wall_s"], row["orbits_per_s"], row["ns_per_orbit"]), row
        assert row["orbits"] == row["n"] ** 2
    threads = result["threads"]["rows"]
    assert threads[0]["threads"] == 1 and all(r["same_labels"] is True for r in threads)
    assert all(_positive(r["wall_s"], r["speedup"]) for r in threads)
    (plot,) = result["plot"]["rows"]
    assert _positive(plot["run_s"], plot["cli_s"]) and plot["image"] == [256, 256]
    assert all("skipped" in row for row in result["more"].values())
    # the printed table: its sections, a row line per JSON row, the quick run's note
    for heading in ("Basin map 128²", "Bulk RK4", "Torque:", "Scaling, atlas map",
                    "Threads, atlas map 128²", "Plotting:", "Quick run (--quick)", "Summary:"):
        assert sum(line.startswith(heading) for line in table) == 1, heading
    scaling = table.index("Scaling, atlas map")
    assert all(" orbits/s " in line for line in table[scaling + 1:scaling + 3])
    assert table[scaling + 3].startswith("Threads")
