"""tools/peer_driven.py: a peer's clusters named by the attractor their members reach (θ
compared mod 2π), and the agreement of two labellings counted, on synthetic data whose
answers are known; the exact reference (DOP853) returns an attractor's own point to it. The
peer itself (pynamicalsys, in .venv-peers) runs only where that venv exists."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tools.peer_driven import (
    NONE,
    Agreement,
    agreement,
    exact_attractor,
    name_clusters,
    nearest_attractor,
    peer_attractors,
)

# Two attractors of P as /attractors stores them: (attractor, sample), NaN-padded; the
# second is a period-2 orbit whose points straddle θ = ±π.
THETA = np.array([[-2.4, np.nan], [3.1, -3.1]])
THETA_DOT = np.array([[0.7, np.nan], [1.8, 1.7]])


def test_a_state_is_named_by_its_nearest_attractor_point_with_theta_mod_two_pi():
    theta = np.array([-2.4 + 4 * math.pi, 3.1 - 2 * math.pi + 0.01, -3.1, 0.0, -2.4])
    theta_dot = np.array([0.7, 1.8, 1.7, 0.7, 0.7 + 0.2])
    # a lift of the first point; the second orbit's two points (one across θ = π); far away
    # from both; and 0.2 off the first point, beyond the matching radius
    assert nearest_attractor(theta, theta_dot, THETA, THETA_DOT).tolist() == [0, 1, 1,
                                                                             NONE, NONE]


def test_a_cluster_is_named_only_when_all_its_followed_members_reach_one_attractor():
    clusters = {"0": {"theta": [3.1, -3.1 + 2 * math.pi], "theta_dot": [1.8, 1.7]},
                "1": {"theta": [-2.4, -2.4 - 2 * math.pi], "theta_dot": [0.7, 0.7]},
                "2": {"theta": [-2.4, 3.1], "theta_dot": [0.7, 1.8]},   # members disagree
                "3": {"theta": [0.0], "theta_dot": [0.0]}}              # reaches neither
    names = name_clusters(clusters, THETA, THETA_DOT)
    assert names == {0: 1, 1: 0, 2: NONE, 3: NONE}
    # the peer's labels in atlas's indices; DBSCAN's noise (−1) is unlabelled
    labels = np.array([[0, 1, -1], [2, 3, 1]])
    assert peer_attractors(labels, names).tolist() == [[1, 0, NONE], [NONE, NONE, 0]]


def test_agreement_counts_each_kind_of_point_once():
    atlas_labels = np.array([0, 1, 2, 2, NONE, NONE, 1, 0])
    peer_labels = np.array([0, 1, 1, 2, 0, NONE, NONE, 2])
    got = agreement(atlas_labels, peer_labels)
    assert got == Agreement(points=8, both=5, agree=3, atlas_only_unlabelled=1,
                            peer_only_unlabelled=1, neither=1)
    assert got.share == pytest.approx(3 / 5)
    assert got.both + got.atlas_only_unlabelled + got.peer_only_unlabelled + got.neither \
        == got.points
    with pytest.raises(ValueError):
        agreement(atlas_labels, peer_labels[:-1])


# The attractors of θ̈ + 0.2θ̇ + sin θ = 1.66 cos t on P (configs/driven.yaml; atlas's RK4
# points to 4 decimals, within 1e-4 of the exact ones): the period-1 orbit, and the two
# period-2 orbits that turn once a period, one each way (winding −2 and 2).
DRIVE = (0.1, 1.0, 1.66, 1.0)
THETA_P = np.array([[-2.4077, np.nan], [-0.7219, 1.3498], [0.9537, -0.6099]])
THETA_DOT_P = np.array([[0.6773, np.nan], [-0.4621, -0.7839], [1.8486, 1.6775]])


@pytest.mark.slow
def test_the_exact_reference_keeps_an_attractor_point_on_its_attractor():
    """DOP853 started on an attractor's point (to 3 decimals) stays on it: it names that
    attractor and no other, whichever of the attractors it starts on."""
    for k in range(3):
        got = exact_attractor(THETA_P[k, 0], THETA_DOT_P[k, 0], DRIVE, THETA_P, THETA_DOT_P,
                              periods=12)
        assert got == k
    # without its attractor in the table, the orbit is named by none
    assert exact_attractor(THETA_P[2, 0], THETA_DOT_P[2, 0], DRIVE, THETA_P[:2],
                           THETA_DOT_P[:2], periods=12) == NONE


PEER_PYTHON = Path(__file__).resolve().parents[2] / ".venv-peers" / "bin" / "python"


@pytest.mark.slow
@pytest.mark.skipif(not PEER_PYTHON.exists(), reason="no .venv-peers (make bench-peers)")
def test_the_peer_names_points_started_on_the_attractors_by_those_attractors():
    """pynamicalsys, run as the tool runs it, on points started on each attractor: the
    clusters it finds are named by the attractor their points started on."""
    from argparse import Namespace

    from tools.peer_driven import grid_config, run_peer

    theta0 = np.array([THETA_P[0, 0], THETA_P[0, 0] + 0.01, *THETA_P[1], *THETA_P[2]])
    theta_dot0 = np.array([THETA_DOT_P[0, 0], THETA_DOT_P[0, 0], *THETA_DOT_P[1],
                           *THETA_DOT_P[2]])
    args = Namespace(transient=10, samples=4, eps=0.05, repeats=1, members=2)
    peer = run_peer(str(PEER_PYTHON), theta0, theta_dot0, grid_config(2), args)
    names = name_clusters(peer["clusters"], THETA_P, THETA_DOT_P)
    assert peer_attractors(peer["labels"], names).tolist() == [0, 0, 1, 1, 2, 2]
    assert len(peer["seconds"]) == len(peer["cpu_seconds"]) == 2
