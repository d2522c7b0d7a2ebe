"""Are two atlas (or study) files the same arrays? Every variable of every group, dtype,
shape and values (NaN equal to NaN), compared exactly (attributes are not compared: a run's
time, path and versions differ by design). Used to check that a restructure leaves the
shipped configs' files bit for bit:

    python -m tools.compare_atlases OLD.h5 NEW.h5     # exit 0: the same arrays
    python -m tools.compare_atlases --check           # the shipped configs, run now, against
                                                      # the digests in tools/identity.json
    python -m tools.compare_atlases --pin             # write those digests (the code before a
                                                      # restructure; minutes)

A digest is the sha256 of a variable's dtype, shape and bytes (:func:`digests`). The shipped
configs are :data:`SHIPPED`: the grid runs of default, swing and swing_torque and the study of
swing_stability, at their full size; ``tests/test_identity.py`` pins the same configs on small
grids in the suite (:func:`shrunk`). The bytes are those of an x86-64 host with FMA, as the
kernels' own pins (tests/kernels/test_torque_kernels.py).
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

REPO = Path(__file__).resolve().parents[1]
#: The digests of the shipped configs' files at full size (``--pin`` writes them).
PINS = REPO / "tools" / "identity.json"
#: The shipped configs whose every array a restructure must leave bit for bit: grid runs,
#: and one study (``atlas stability``).
SHIPPED = {"default": "run", "swing": "run", "swing_torque": "run",
           "swing_stability": "study"}


def differences(a: str, b: str) -> list[str]:
    """One line per variable that is missing from ``b`` or differs (dtype or values)."""
    with xr.open_datatree(a, engine="h5netcdf") as old, \
            xr.open_datatree(b, engine="h5netcdf") as new:
        return _differences(old, new)


def _values(var: xr.Variable) -> np.ndarray:
    return np.asarray(var.values)


def _differences(old: xr.DataTree, new: xr.DataTree) -> list[str]:
    found = []
    for node in old.subtree:
        other = new[node.path] if node.path != "/" else new
        for name, var in node.dataset.variables.items():
            twin = other.dataset.variables.get(name)
            if twin is None:
                found.append(f"{node.path} {name}: missing")
                continue
            x, y = _values(var), _values(twin)
            same = x.dtype == y.dtype and x.shape == y.shape and (
                np.array_equal(x, y, equal_nan=True) if x.dtype.kind in "fc"
                else np.array_equal(x, y))
            if not same:
                found.append(f"{node.path} {name}: differs")
    return found


def digests(path: str | Path) -> dict[str, str]:
    """``{"GROUP/NAME": sha256}`` of every variable of every group of the file at ``path``,
    as stored (no CF decoding: fill values and integer dtypes as on disk), over its dtype,
    shape and bytes."""
    found = {}
    with xr.open_datatree(path, engine="h5netcdf", decode_cf=False) as tree:
        for node in tree.subtree:
            for name, var in node.dataset.variables.items():
                values = np.ascontiguousarray(_values(var))
                h = hashlib.sha256(f"{values.dtype.str}{values.shape}".encode())
                h.update(values.tobytes() if values.dtype.kind != "O" else
                         "\x1f".join(map(str, values.ravel())).encode())
                found[f"{node.path.rstrip('/')}/{name}"] = h.hexdigest()
    return found


def shrunk(name: str, output: Path, *, side: int = 48, points: int = 11, every: int = 6
           ) -> object:
    """The validated config of ``configs/NAME.yaml`` writing to ``output``, on a small grid
    (``side`` × ``side`` orbits), a parameter list of a grid run taken at every ``every``-th
    value and a study's ranges at ``points`` values: the same code paths as the shipped
    config, in seconds."""
    import atlas
    from atlas.pipeline.config import load_config

    study = SHIPPED[name] == "study"
    data = load_config(REPO / "configs" / f"{name}.yaml", study=study).model_dump(mode="json")
    for axis in ("theta0", "theta_dot0"):
        if not study:
            data["grid"][axis]["num"] = side
    for key, value in data["pendulum"].items():
        if study and isinstance(value, dict) and "num" in value:
            value["num"] = points
        elif not study and isinstance(value, list):
            data["pendulum"][key] = value[::every]
    data["output"] = str(output)
    return atlas.Config.model_validate(data, context={"study": study})


def compute(name: str, folder: Path, *, small: bool = False) -> Path:
    """Run the shipped config ``name`` (a grid run or a study, :data:`SHIPPED`) into
    ``folder``, at full size or :func:`shrunk`; the file's path."""
    output = Path(folder) / f"{name}.h5"
    if SHIPPED[name] == "study":
        import yaml

        from atlas.commands.stability import run_study

        config = REPO / "configs" / f"{name}.yaml"
        if small:
            config = Path(folder) / f"{name}.yaml"
            cfg = shrunk(name, output)
            config.write_text(yaml.safe_dump(cfg.model_dump(mode="json", exclude_none=True)))
        run_study(config, output=output)
        return output
    import atlas
    from atlas.pipeline.config import load_config

    cfg = (shrunk(name, output) if small else
           load_config(REPO / "configs" / f"{name}.yaml", output=output))
    atlas.run(cfg, quiet=True).close()
    return output


def _pinned(small: bool) -> dict[str, dict[str, str]]:
    with tempfile.TemporaryDirectory() as folder:
        return {name: digests(compute(name, Path(folder), small=small)) for name in SHIPPED}


def main(argv: list[str]) -> int:
    if argv == ["--pin"]:
        PINS.write_text(json.dumps(_pinned(small=False), indent=1, sort_keys=True) + "\n")
        print(f"wrote {PINS}")
        return 0
    if argv == ["--check"]:
        pins, now = json.loads(PINS.read_text()), _pinned(small=False)
        found = [f"{name} {var}: {'missing' if var not in now[name] else 'differs'}"
                 for name, pinned in pins.items() for var, digest in pinned.items()
                 if now[name].get(var) != digest]
    elif len(argv) == 2:
        found = differences(*argv)
    else:
        print("usage: python -m tools.compare_atlases OLD.h5 NEW.h5 | --check | --pin",
              file=sys.stderr)
        return 2
    for line in found:
        print(line)
    print(f"{len(found)} variables differ")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
