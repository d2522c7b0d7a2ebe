"""The basin map as a palette PNG, one pixel per grid point: the picture both pages embed
(:mod:`atlas.views.page`, :mod:`atlas.views.page_described`), each label k in its colour of
every figure (:func:`atlas.views.style.well_colour`)."""

from __future__ import annotations

import base64
import io

import numpy as np

from atlas.views.style import NO_LABEL_COLOR, RUNNING_COLOR_HEX, well_colour

__all__ = ["labelled_wells", "map_png"]


def _rgb(colour: str) -> list[int]:
    """"#rrggbb" as [r, g, b]."""
    return [int(colour[i:i + 2], 16) for i in (1, 3, 5)]


def labelled_wells(attractor: np.ndarray, status: np.ndarray, kinds: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(where a well label is stored, the wells k that occur there, ascending); ``kinds``:
    the file's model's :meth:`~atlas.models.base.Model.status_kinds`."""
    labelled = kinds[status.astype(np.int64) + 128] == 1
    return labelled, np.unique(attractor[labelled]).astype(int)


def map_png(attractor: np.ndarray, status: np.ndarray, wells: np.ndarray,
            kinds: np.ndarray, colours: dict[int, str] | None = None) -> str:
    """The basin map as a palette PNG data URI, one pixel per grid point, the velocity
    upward: the i-th well of ``wells`` in palette entry i
    (:func:`atlas.views.style.well_colour`, as the page's key), no label white, running in
    the running basin's grey (which status is which: ``kinds``, as
    :func:`labelled_wells`); ``colours``: a label's own colour where the model gives one
    (a driven pendulum's attractors: :func:`atlas.views.style.attractor_colours`). At most
    254 wells fit a palette; the rest (never met in
    practice) share the last well's entry."""
    from PIL import Image

    labelled, _ = labelled_wells(attractor, status, kinds)
    wells = wells[:254]
    where = np.clip(np.searchsorted(wells, attractor), 0, max(len(wells) - 1, 0))
    index = np.where(labelled, where, len(wells)).astype(np.uint8)
    index[kinds[status.astype(np.int64) + 128] == 2] = len(wells) + 1
    image = Image.fromarray(index[::-1], mode="P")
    colours = colours or {}
    palette = ([v for k in wells for v in _rgb(colours.get(int(k)) or well_colour(k))]
               + _rgb(NO_LABEL_COLOR)
               + _rgb(RUNNING_COLOR_HEX))
    image.putpalette(palette)
    buffer = io.BytesIO()
    image.save(buffer, format="PNG", optimize=True)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode()
