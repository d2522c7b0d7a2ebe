"""The file's words for the labels: written once (atlas.status), and true of the arrays."""

from __future__ import annotations

import numpy as np

import atlas
from atlas.models.pendulum.description import MAP_VARIABLES
from atlas.status import ATTRACTOR_FILL, IN_FILE, NEAR_BOUNDARY, STATUS_MEANINGS, TRAPPED


def test_the_status_flags_are_those_of_the_status_module():
    flags = MAP_VARIABLES["status"].attrs
    assert list(flags["flag_values"]) == list(STATUS_MEANINGS)
    assert flags["flag_meanings"].split() == list(STATUS_MEANINGS.values())
    for code, name in STATUS_MEANINGS.items():
        assert f"{name}: {IN_FILE[code]}" in flags["comment"]


def test_the_attractor_is_filled_exactly_where_no_well_label_applies(swing_atlas):
    """What the ``attractor`` comment says, checked on a swing atlas (running orbits, wells,
    near-boundary labels): k wherever the status names a well, the fill value elsewhere."""
    ds = atlas.open(swing_atlas).to_dataset(inherit=False)
    k, status = ds["attractor"].values, ds["status"].values
    well = np.isin(status, [TRAPPED, NEAR_BOUNDARY])
    assert well.any() and (~well).any()
    assert np.all(k[well] != ATTRACTOR_FILL) and np.all(k[~well] == ATTRACTOR_FILL)
    assert "unresolved" in MAP_VARIABLES["attractor"].attrs["comment"]
