"""Are two atlas files the same arrays? Every variable of every group, dtype and values (NaN
equal to NaN), compared exactly (attributes are not compared: a run's time, path and versions
differ by design). Used to check that a restructure leaves the default atlas bit for bit:

    python -m tools.compare_atlases OLD.h5 NEW.h5     # exit 0: the same arrays
"""

from __future__ import annotations

import sys

import numpy as np
import xarray as xr


#: Attributes that differ between two runs of one config by design.
def differences(a: str, b: str) -> list[str]:
    """One line per variable that is missing from ``b`` or differs (dtype or values)."""
    with xr.open_datatree(a, engine="h5netcdf") as old, \
            xr.open_datatree(b, engine="h5netcdf") as new:
        return _differences(old, new)


def _differences(old: xr.DataTree, new: xr.DataTree) -> list[str]:
    found = []
    for node in old.subtree:
        other = new[node.path] if node.path != "/" else new
        for name, var in node.dataset.variables.items():
            twin = other.dataset.variables.get(name)
            if twin is None:
                found.append(f"{node.path} {name}: missing")
                continue
            x, y = var.values, twin.values
            same = x.dtype == y.dtype and x.shape == y.shape and (
                np.array_equal(x, y, equal_nan=True) if x.dtype.kind in "fc"
                else np.array_equal(x, y))
            if not same:
                found.append(f"{node.path} {name}: differs")
    return found


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: python -m tools.compare_atlases OLD.h5 NEW.h5", file=sys.stderr)
        return 2
    found = differences(*argv)
    for line in found:
        print(line)
    print(f"{len(found)} variables differ")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
