"""The readers of a ``/separatrices`` node (:mod:`atlas.store.separatrices`): :func:`curves`
lays the flat list of points out as one Dataset over (curve, along) without losing, adding
or reordering a point, split where a branch left the window, as :func:`branches` does."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from atlas.store.separatrices import BRANCHES, branches, curves


def _flat(saddle_n, branch, vertex, seed=0) -> xr.Dataset:
    """A node's ``point`` table (the variables the readers use), its rows shuffled: θ and θ̇
    encode each point's (saddle, branch, vertex) so that a misplaced one shows."""
    saddle_n, branch, vertex = (np.asarray(a) for a in (saddle_n, branch, vertex))
    order = np.random.default_rng(seed).permutation(saddle_n.size)
    theta = saddle_n * np.pi + 1e-3 * vertex
    theta_dot = branch + 1e-3 * vertex
    return xr.Dataset(
        {"theta": ("point", theta[order], {"units": "rad"}),
         "theta_dot": ("point", theta_dot[order], {"units": "rad s-1"})},
        coords={"saddle_n": ("point", saddle_n[order].astype(np.int32)),
                "branch": ("point", branch[order].astype(np.int8),
                           {"flag_values": np.array([0, 1], np.int8),
                            "flag_meanings": " ".join(BRANCHES)}),
                "vertex": ("point", vertex[order].astype(np.int32))})


def _valid(c: xr.Dataset, i: int) -> np.ndarray:
    return c["vertex"].values[i] >= 0


def test_curves_are_the_points_sorted_and_split_where_the_vertex_skips():
    # saddle 1 left: vertices 0..4 then 9..11 (it left the window); saddle -1 right: 3..5
    rows = [(1, 0, v) for v in [*range(5), 9, 10, 11]] + [(-1, 1, v) for v in range(3, 6)]
    ds = _flat(*zip(*rows, strict=True))
    c = curves(ds)
    assert c.sizes == {"curve": 3, "along": 5}
    assert c["saddle_n"].values.tolist() == [-1, 1, 1]  # the order of branches()
    assert c["branch"].values.tolist() == [1, 0, 0]
    assert c["branch"].attrs["flag_meanings"] == "left right"
    assert [c["vertex"].values[i][_valid(c, i)].tolist() for i in range(3)] == [
        [3, 4, 5], [0, 1, 2, 3, 4], [9, 10, 11]]
    # the padding: NaN coordinates, vertex -1
    assert np.isnan(c["theta"].values[0, 3:]).all() and np.isnan(c["theta_dot"][2, 3:]).all()
    assert (c["vertex"].values[0, 3:] == -1).all()
    # every point once, where its (saddle, branch, vertex) says: against a plain lexsort
    s, b, v = (ds[n].values for n in ("saddle_n", "branch", "vertex"))
    ref = np.lexsort((v, b, s))
    got = np.concatenate([c["theta"].values[i][_valid(c, i)] for i in range(3)])
    np.testing.assert_array_equal(got, ds["theta"].values[ref])
    got = np.concatenate([c["theta_dot"].values[i][_valid(c, i)] for i in range(3)])
    np.testing.assert_array_equal(got, ds["theta_dot"].values[ref])
    assert c["theta"].attrs["units"] == "rad"


def test_no_points_give_no_curves():
    c = curves(_flat([], [], []))
    assert c.sizes == {"curve": 0, "along": 0}


@pytest.fixture(scope="module")
def gapped_atlas(tmp_path_factory):
    """A small default-pendulum atlas whose window, θ̇0 within ±3.55, cuts the wiggles of
    the outer branches: they leave the window and come back (gaps in ``vertex``)."""
    from tests.helpers import small_atlas

    folder = tmp_path_factory.mktemp("gapped")
    small_atlas(folder, "gapped", {"alpha": 0.1, "omega0": 1.0}, theta=("-3pi", "3pi"),
                speed=(-3.55, 3.55), num=(24, 16), t_max=200.0)
    return folder / "gapped.h5"


@pytest.mark.slow  # a small atlas with separatrices (a few seconds)
def test_curves_of_a_file_are_its_flat_list_in_order_and_draw_as_many_lines(gapped_atlas):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tree = xr.open_datatree(gapped_atlas, engine="h5netcdf")
    sep = tree["separatrices"].to_dataset(inherit=False)
    c = curves(sep)
    pieces = list(branches(sep))
    assert c.sizes["curve"] == len(pieces)
    # the window cuts branches: more curves than branches (a reader that ignored the gaps
    # would join the pieces across the outside of the window)
    assert len(pieces) > len(set(zip(sep["saddle_n"].values.tolist(),
                                     sep["branch"].values.tolist(), strict=True))) >= 4
    for i, (n, name, theta, theta_dot) in enumerate(pieces):
        keep = _valid(c, i)
        assert (int(c["saddle_n"][i]), BRANCHES[int(c["branch"][i])]) == (n, name)
        np.testing.assert_array_equal(c["theta"].values[i][keep], theta)
        np.testing.assert_array_equal(c["theta_dot"].values[i][keep], theta_dot)
        assert np.isnan(c["theta"].values[i][~keep]).all()
        assert (np.diff(c["vertex"].values[i][keep]) == 1).all()  # no skip inside a curve
    # the writer stores the points sorted by saddle, branch and vertex: the curves, end to
    # end, are the flat list itself
    flat = np.concatenate([c["theta"].values[i][_valid(c, i)] for i in range(len(pieces))])
    np.testing.assert_array_equal(flat, sep["theta"].values)
    # the one-line drawing the docs show: one line per curve, NaN left out of each
    fig, ax = plt.subplots()
    lines = ax.plot(c["theta"].T, c["theta_dot"].T, "k")
    assert len(lines) == len(pieces)
    assert [np.isfinite(line.get_xdata()).sum() for line in lines] == [
        theta.size for _, _, theta, _ in pieces]
    plt.close(fig)
