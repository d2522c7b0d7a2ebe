"""tools/compare_atlases.py finds a changed value and nothing in an identical copy."""

from __future__ import annotations

import shutil

import h5py

from tools.compare_atlases import differences


def test_a_copy_is_the_same_and_one_changed_label_is_found(small_atlas_file, tmp_path):
    copy = tmp_path / "copy.h5"
    shutil.copy(small_atlas_file, copy)
    assert differences(str(small_atlas_file), str(copy)) == []
    with h5py.File(copy, "r+") as f:
        f["t_trap"][0, 0] = f["t_trap"][0, 0] + 1.0
    assert differences(str(small_atlas_file), str(copy)) == ["/ t_trap: differs"]
