"""Which cells of a label matrix carry a label: the one convention of :mod:`atlas.fractal`.

A matrix of basin labels may have cells with no label: an atlas's fill value −32768
(:data:`atlas.status.ATTRACTOR_FILL`) where an orbit was unresolved or non-finite. By default
a cell is unlabelled where it holds ``fill`` (that value); a boolean ``mask`` (True:
unlabelled) says so explicitly instead. Other negative values are labels like any other: the
undriven pendulum's wells k are negative on the left, and Attractors.jl's −1 (an orbit that
diverged) is a basin of its own there. Each measure then either takes the unlabelled cells as
one more basin (``unlabelled="basin"``, what Attractors.jl does: its functions count every
distinct integer as a basin) or leaves them out (``unlabelled="exclude"``).
"""

from __future__ import annotations

import numpy as np

from atlas.status import ATTRACTOR_FILL

__all__ = ["FILL", "UNLABELLED_MODES", "labelled_matrix", "unlabelled_cells"]

#: The value of a cell with no label, by default: atlas's fill value.
FILL = ATTRACTOR_FILL

#: The two treatments of unlabelled cells.
UNLABELLED_MODES = ("basin", "exclude")


def unlabelled_cells(labels, mask=None, fill: int | None = FILL) -> np.ndarray:
    """True where a cell of ``labels`` has no label: ``mask`` if given, else where the cell
    holds ``fill`` (None: every cell is labelled)."""
    labels = np.asarray(labels)
    if mask is not None:
        missing = np.asarray(mask, bool)
        if missing.shape != labels.shape:
            raise ValueError(f"mask of shape {missing.shape} for labels of shape "
                             f"{labels.shape}")
        return missing
    if fill is None:
        return np.zeros(labels.shape, bool)
    return labels == fill


def labelled_matrix(labels, mask=None, unlabelled: str = "basin", fill: int | None = FILL
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``labels`` as a 2-D array of codes 0 … K−1 (one per distinct basin) and the boolean
    array of the cells that count (all of them with ``unlabelled="basin"``, where every
    unlabelled cell gets one common code; the labelled ones with ``"exclude"``).

    ``mask``, ``fill``: which cells are unlabelled (:func:`unlabelled_cells`)."""
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ValueError(f"labels must be a 2-D matrix, not of shape {labels.shape}")
    if not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"labels must be integers, not {labels.dtype}")
    if unlabelled not in UNLABELLED_MODES:
        raise ValueError(f"unlabelled must be one of {UNLABELLED_MODES}, not {unlabelled!r}")
    missing = unlabelled_cells(labels, mask, fill)
    values = np.where(missing, np.iinfo(np.int64).min, labels.astype(np.int64))
    _, codes = np.unique(values, return_inverse=True)
    codes = codes.reshape(labels.shape)
    counted = np.ones(labels.shape, bool) if unlabelled == "basin" else ~missing
    return codes, counted
