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


def test_digests_see_one_changed_bit_of_a_study_too(tmp_path):
    """The digests cover study files (``atlas stability``) as well as atlases: every
    variable, at its stored dtype."""
    from tools.compare_atlases import compute, digests

    path = compute("swing_stability", tmp_path, small=True)
    before = digests(path)
    assert {"/basin_stability", "/minimal_fatal_shock", "/homoclinic_torque"} <= set(before)
    with h5py.File(path, "r+") as f:
        values = f["basin_stability"][...]
        values.view("u8")[0, 0] ^= 1  # the last bit of one double
        f["basin_stability"][...] = values
    after = digests(path)
    assert [name for name in before if before[name] != after[name]] == ["/basin_stability"]
