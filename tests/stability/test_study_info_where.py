"""`atlas info` of a 2-D study says where the rest states' basin stability is lowest and
highest (issue 43, 10): on an α × τ map whose values all differ, the printed points are the
arg-min and arg-max of the stored total, found here by xarray (and the printed values are
theirs), so that a transposed index or swapped coordinates would fail."""

from __future__ import annotations

import io
import re
from contextlib import redirect_stdout

import numpy as np
import pytest

from atlas.cli import main
from atlas.store.study import open_study
from tests.helpers import study_config


@pytest.mark.slow
def test_the_2d_info_names_the_points_of_the_extremes(tmp_path):
    cfg = study_config(tmp_path / "m.yaml",
                       "alpha: [0.05, 0.12, 0.2], omega0: 1.0, torque: [0.45, 0.6, 0.75, 0.9]",
                       tmp_path / "m.h5")
    assert main(["stability", str(cfg)]) == 0
    ds = open_study(tmp_path / "m.h5")
    total = ds["basin_stability"].sum("k", skipna=False)
    assert np.unique(np.round(total.values, 8)).size == total.size  # every value differs
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["info", str(tmp_path / "m.h5")]) == 0
    for word, pick in (("lowest", total.argmin), ("highest", total.argmax)):
        index = pick(...)
        at = {d: float(ds[d][int(i)]) for d, i in index.items()}
        line = next(line for line in out.getvalue().splitlines() if f", {word}:" in line)
        value, where = re.search(rf"{word}: ([\d.]+) ± \S+ at (.*) \(exact", line).groups()
        printed = dict(part.split(" = ") for part in where.split(", "))
        assert {d: float(v) for d, v in printed.items()} == pytest.approx(at, abs=1e-12)
        assert float(value) == pytest.approx(float(total.isel(index)), abs=1e-10)
