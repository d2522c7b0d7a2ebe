"""One writer per output (atlas.pipeline.lock): the lock refuses a second writer, and its file
is gone when the writer is done, without opening a window for two writers at once."""

from __future__ import annotations

import os

import pytest

from atlas.pipeline import lock
from atlas.pipeline.lock import OutputLocked, lock_path, output_lock


def test_the_lock_refuses_a_second_writer_and_leaves_nothing(tmp_path):
    out = tmp_path / "x.h5"
    with output_lock(out):
        assert lock_path(out).exists()
        with pytest.raises(OutputLocked, match=f"pid {os.getpid()}"):
            with output_lock(out):  # flock: two opens of one file conflict, even in a process
                pass
    assert sorted(tmp_path.iterdir()) == []
    with pytest.raises(RuntimeError):
        with output_lock(out):
            raise RuntimeError("a failed run")
    assert sorted(tmp_path.iterdir()) == []


def test_a_lock_file_removed_under_a_waiting_run_is_not_taken(tmp_path, monkeypatch):
    """Run B opened the lock file just before its holder A removed it and let go; run C has
    since made and locked a new one. B's flock on the removed file succeeds, but B must see
    that the path now names C's file, and be refused: two writers otherwise."""
    out = tmp_path / "x.h5"
    path = lock_path(out)
    path.write_text("")
    early = os.open(path, os.O_RDWR)  # B's open, before A's removal
    path.unlink()  # A is done
    real_open, opens = os.open, []

    def open_(*args, **kwargs):  # B's first open is the early one
        opens.append(args[0])
        return early if len(opens) == 1 else real_open(*args, **kwargs)

    with output_lock(out):  # C
        monkeypatch.setattr(lock.os, "open", open_)
        with pytest.raises(OutputLocked):
            with output_lock(out):  # B
                pass
    assert len(opens) == 2  # B started over with the file at the path
    assert not path.exists()
