"""``atlas info --check FILE`` reads back every stored chunk: a chunk damaged on disk (one bit
flipped in its compressed bytes), which plain ``atlas info`` passes because it reads a few
arrays only, is named (its group and variable) in one line, exit status 2, the file left as it
was; a sound file gets a line saying what was read."""

from __future__ import annotations

import shutil

import h5py
import numpy as np
import pytest

import atlas
from tests.commands.test_fuzz import cli


def _compressed_chunks(path) -> dict[str, tuple[int, int]]:
    """{HDF5 path of a chunked, compressed dataset: (byte offset, size) of its first stored
    chunk}."""
    found = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.chunks and obj.compression:
            info = obj.id.get_chunk_info(0)
            found[name] = (info.byte_offset, info.size)

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return found


def _flip_bit(path, name: str, offset: int, size: int) -> None:
    """Flip one bit of the ``size`` bytes at ``offset`` (a stored chunk of dataset ``name``),
    the first from the middle on whose flip h5py itself cannot read ``name`` (a few bits of a
    deflate stream, its last byte's padding say, change nothing that is read)."""
    data = path.read_bytes()
    for i in sorted(range(size), key=lambda i: abs(i - size // 2)):
        bad = bytearray(data)
        bad[offset + i] ^= 0x10
        path.write_bytes(bytes(bad))
        try:
            with h5py.File(path, "r") as f:
                f[name][...]
        except OSError:
            return
    raise AssertionError(f"no single flipped bit in {name}'s chunk is detected")


def _one_line(code: int, err: str) -> str:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("atlas: error: ") and "Traceback" not in err
    return lines[0]


@pytest.fixture(scope="module")
def traced_atlas(tmp_path_factory):
    """A small atlas with separatrices (groups beside the root to damage too)."""
    from tests.helpers import small_atlas

    tmp = tmp_path_factory.mktemp("check")
    small_atlas(tmp, "traced", {"alpha": 0.1, "omega0": 1.0}, theta=("-pi", "pi"),
                speed=(-3.0, 3.0), num=(16, 12), t_max=200.0).close()
    return tmp / "traced.h5"


def test_a_sound_file_passes_and_says_what_was_read(traced_atlas):
    code, err = cli("info", "--check", traced_atlas)
    assert code == 0, err
    from atlas.store.readback import read_back

    done = read_back(traced_atlas)
    assert done.groups >= 3 and done.variables > 20 and done.nbytes > 16 * 12 * 8


def test_check_names_a_damaged_chunk_that_plain_info_passes(small_atlas_file, tmp_path):
    """t_trap's first chunk with one bit flipped: plain info exits 0 (it never reads t_trap;
    reading it later fails), --check names it."""
    bad = tmp_path / "bad.h5"
    shutil.copyfile(small_atlas_file, bad)
    _flip_bit(bad, "t_trap", *_compressed_chunks(bad)["t_trap"])
    before = bad.read_bytes()
    assert cli("info", bad)[0] == 0
    with pytest.raises(OSError):
        atlas.open(bad)["t_trap"].values  # noqa: B018 (the read that fails later)
    line = _one_line(*cli("info", "--check", bad))
    assert f"{bad}: damaged data in group /, variable t_trap: a stored chunk" in line
    assert bad.read_bytes() == before


def test_every_compressed_variable_is_read_back(traced_atlas, tmp_path):
    """A bit flipped in the first chunk of each compressed dataset (the maps; the groups'
    small arrays are stored uncompressed, where a changed byte is a valid number that no
    read can tell), one at a time: --check names that group and variable each time."""
    chunks = _compressed_chunks(traced_atlas)
    assert {"attractor", "status", "t_trap", "boundary_distance"} <= set(chunks)
    for name, (offset, size) in chunks.items():
        bad = tmp_path / f"bad-{name.replace('/', '_')}.h5"
        shutil.copyfile(traced_atlas, bad)
        _flip_bit(bad, name, offset, size)
        group, _, variable = name.rpartition("/")
        code, err = cli("info", "--check", bad)
        assert f"group /{group}, variable {variable}:" in _one_line(code, err), (name, err)


def test_a_damaged_zarr_chunk_is_named(tmp_path):
    """The same in a Zarr store: t_trap's stored chunk overwritten with other bytes."""
    pytest.importorskip("zarr")
    from tests.helpers import SMALL, write_config

    store = tmp_path / "z.zarr"
    code, err = cli("run", write_config(tmp_path / "z.yaml", SMALL.format(sep="false",
                                                                          output=store)),
                    "--quiet")
    assert code == 0, err
    assert cli("info", "--check", store)[0] == 0
    chunk = next(p for p in sorted((store / "t_trap").rglob("*"))
                 if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(np.random.default_rng(1).bytes(chunk.stat().st_size))
    line = _one_line(*cli("info", "--check", store))
    assert "group /, variable t_trap: a stored chunk" in line
