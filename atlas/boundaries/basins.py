"""What the exact boundaries answer, shared by every implementation: which basin a point is
in (a well k, or :data:`RUNNING_SIDE` for the running basin) and the exact area fractions of a
window (:class:`ExactAreas`). The protocol that answers them is :mod:`atlas.boundaries.exact`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from atlas.status import ATTRACTOR_FILL

__all__ = ["RUNNING_SIDE", "FIND_CYCLE", "ExactAreas"]

#: The exact side of a point in the running basin (the basin of the running limit cycle): the
#: kernels' ATTRACTOR_FILL, −32768, the attractor index of an orbit that settles in no well.
#: Wells k are |k| ≤ atlas.limits.MAX_WELL = 32767, so it names no well, and it survives int16.
RUNNING_SIDE = ATTRACTOR_FILL
#: Default of ``cycle``: find the running limit cycle (:func:`atlas.physics.running.limit_cycle`).
FIND_CYCLE = object()


class ExactAreas(NamedTuple):
    """Exact area fractions of a window.

    k:             the wells whose basins meet the window (int64).
    fraction:      each well's basin area ∩ window / window area.
    error:         estimated error of each ``fraction`` (the reference's change from rtol
                   1e-12 to 1e-13, and the rounding of the coordinates at the window's
                   scale), at least 4 ulp.
    running:       the running basin's fraction (0 when there is no running limit cycle).
    running_error: the same for ``running`` (0 without a cycle).

    The fractions and ``running`` sum to 1, to their errors."""

    k: np.ndarray
    fraction: np.ndarray
    error: np.ndarray
    running: float
    running_error: float
