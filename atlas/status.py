"""The label codes every layer shares: the ``status`` values, what each means, the fill value.

A kernel sets ``trapped``, ``unresolved``, ``nonfinite`` or ``running``; certification
against the exact basin boundaries (:mod:`atlas.boundaries.certificate`) turns a label that
lies closer than ``d_cert`` to a boundary into ``near_boundary`` or
``running_near_boundary``. Values are added, never renumbered: files of every format keep
their meaning. Written once here; the kernels, the file schema (CF ``flag_values`` /
``flag_meanings``) and the views read them from this module.
"""

from __future__ import annotations

import numpy as np

__all__ = ["IN_FILE", "TRAPPED", "UNRESOLVED", "NONFINITE", "NEAR_BOUNDARY", "RUNNING",
           "RUNNING_NEAR_BOUNDARY", "ATTRACTOR_FILL", "STATUS_MEANINGS"]

#: Trapped in the energy trap of well k; in a file, also farther than d_cert from every
#: basin boundary: certified for the exact equation.
TRAPPED = 0
#: t_max reached before any certificate held.
UNRESOLVED = 1
#: A NaN or inf state was met.
NONFINITE = 2
#: Set after labelling (never by a kernel): trapped, but closer than d_cert to a basin
#: boundary — or d_cert was not measured (NaN: no separatrices traced), which leaves every
#: label here — so certified for the RK4 map only.
NEAR_BOUNDARY = 3
#: Certified to converge to the running limit cycle (τ ≠ 0): the orbit entered the running
#: barrier's forward-invariant region. ``attractor`` keeps its fill value; the direction of
#: rotation is sign(τ).
RUNNING = 4
#: Set after labelling (never by a kernel): running, but not certified for the exact
#: equation (closer than d_cert to a basin boundary, or on another basin's side).
RUNNING_NEAR_BOUNDARY = 5

#: ``attractor`` where no well label applies (int16; also the file's _FillValue).
ATTRACTOR_FILL = int(np.iinfo(np.int16).min)

#: What each status value means, in order: the file's ``flag_meanings`` and every text.
STATUS_MEANINGS = {TRAPPED: "trapped", UNRESOLVED: "unresolved", NONFINITE: "nonfinite",
                   NEAR_BOUNDARY: "near_boundary", RUNNING: "running",
                   RUNNING_NEAR_BOUNDARY: "running_near_boundary"}

#: What each status value means in an atlas file, where labels have been certified against the
#: exact basin boundaries (from :func:`atlas.label`, ``trapped`` means trapped for the RK4 map
#: only): the file's ``status`` comment is built from these.
IN_FILE = {
    TRAPPED: "certified for the exact equation (energy trap of the RK4 map, and farther than "
             "d_cert from every basin boundary)",
    UNRESOLVED: "no certificate held before t_max",
    NONFINITE: "a NaN or inf state was met",
    NEAR_BOUNDARY: "trapped, certified for the RK4 map only: closer than d_cert to a basin "
                   "boundary, or d_cert not measured (NaN: separatrices disabled, or no "
                   "boundary traced in the window), so that no label is certified for the "
                   "exact equation",
    RUNNING: "with torque: in the running barrier of the RK4 map and farther than d_cert from "
             "every basin boundary, certified for the exact equation to converge to the "
             "running limit cycle",
    RUNNING_NEAR_BOUNDARY: "running, certified for the RK4 map only: closer than d_cert to a "
                           "basin boundary, on another basin's side, or d_cert not measured "
                           "(NaN: separatrices disabled, or no boundary traced)",
}
