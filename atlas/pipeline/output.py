"""What an output path may be: the policy a run checks before it creates anything.

A run writes its atlas at ``cfg.output`` in the format the path asks for
(:func:`atlas.store.formats.format_for`). Before anything is made (the lock, the partial
folder) it refuses, with one line each: the config file being run as the output, whatever
``--force`` says; an existing file or store that atlas did not write, unless ``--force``
(:func:`check_output_target`; an atlas file may be written over: that is how a changed config
is run again); a directory where the format writes a file; a folder that is not a directory
or not writable; a disk without room for the labels (:func:`check_output_path`, an estimate
from the grid's size, :func:`label_bytes`).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from atlas.errors import AtlasError, OutputInTheWay
from atlas.layout import Layout
from atlas.models.pendulum.description import PENDULUM
from atlas.store.formats import format_for
from atlas.store.outputs import check_suffix
from atlas.store.reader import is_atlas_file

__all__ = ["check_output_target", "check_output_path", "label_bytes", "human_size",
           "BYTES_PER_ORBIT"]

#: Bytes one orbit of the pendulum takes on disk at most: every per-orbit variable of the
#: file uncompressed, from their stored dtypes (attractor int16 + status int8 + t_trap
#: float32 + boundary_distance float32 = 11 bytes; compression only lowers it). Another
#: model's: :attr:`atlas.models.base.Model.bytes_per_orbit`.
BYTES_PER_ORBIT = PENDULUM.bytes_per_orbit


def check_output_target(output, config=None, *, force: bool = False) -> None:
    """Refuse an output path that holds something a run must not write over:

    * the config file being run (``atlas run c.yaml -o c.yaml``), whatever ``force`` says;
    * a name without an atlas format's suffix (``atlas run c.yaml -o q.png``: ``atlas plot``
      would write the basin map over the atlas), whatever ``force`` says
      (:func:`atlas.store.outputs.check_suffix`);
    * an existing file (or Zarr store) that atlas did not write, unless ``force``.

    An atlas file at the output (a finished run of this or another config) may be written
    over: that is how a changed config is run again. Raises
    :class:`~atlas.errors.OutputInTheWay` (exit status 2)."""
    output = Path(output)
    if config is not None and output.exists():
        try:
            same = os.path.samefile(output, config)
        except OSError:
            same = False
        if same:
            raise OutputInTheWay(f"{output}: the output path is the config file being run; "
                                 "name another output with -o")
    if not output.is_dir():  # a directory is refused as such (check_output_path)
        check_suffix(output, "atlas")
    if force or not output.exists():
        return
    fmt = format_for(output)
    if output.is_dir() and not fmt.recognises(output):
        return  # not a store: check_output_path refuses a directory with its own line
    if not is_atlas_file(output):
        what = "Zarr store" if output.is_dir() else "file"
        raise OutputInTheWay(f"{output}: an existing {what} that atlas did not write is in "
                             "the way; run with --force to write over it, or name another "
                             "output with -o")


def check_output_path(output: Path, layout: Layout) -> None:
    """Refuse an output that cannot be written or would not fit, before anything is made:
    a directory (unless a store of the folder format the path asks for), an output folder
    that is not a directory or not writable, a disk with less room than the labels of
    ``layout`` may take."""
    fmt = format_for(output)
    if output.is_dir() and not (fmt.folder and fmt.recognises(output)):
        raise AtlasError(f"{output}: the output path is a directory")
    existing = next(p for p in (output.parent, *output.parent.parents) if p.exists())
    if not existing.is_dir():
        raise AtlasError(f"{output}: the output folder {existing} is not a directory")
    if not os.access(existing, os.W_OK):
        raise AtlasError(f"{output}: the output folder {existing} is not writable")
    need = label_bytes(layout)
    free = shutil.disk_usage(existing).free
    if need > free:
        raise AtlasError(f"{output}: the output may need up to {human_size(need)} but only "
                         f"{human_size(free)} is free on that disk")


def label_bytes(layout: Layout) -> int:
    """Bytes the labels of ``layout`` take on disk at most: its orbits (every parameter point)
    × the bytes of one orbit (:data:`BYTES_PER_ORBIT` for the pendulum)."""
    return (layout.n_params * layout.x0.size * layout.v0.size
            * layout.model.bytes_per_orbit)


def human_size(n_bytes: float) -> str:
    """A size in bytes for people: "4.4 GB" (decimal units)."""
    for unit in ("B", "KB", "MB", "GB"):
        if n_bytes < 1000:
            return f"{n_bytes:.3g} {unit}"
        n_bytes /= 1000
    return f"{n_bytes:.3g} TB"
