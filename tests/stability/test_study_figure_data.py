"""A study's figures draw each curve from its own variable and well: the lines' data read back
from the drawn Axes equal the study file's numbers (rest states summed over k, well k = 0
chosen by its label — not the first row —, the running cycle, the Gaussian stability, the
two fatal shocks), and the 2-D map's cells are the summed basin stability with α up and τ
across. Each drawn variable differs from every other one here, so a curve drawn from the
wrong variable or the wrong k fails."""

from __future__ import annotations

import itertools

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from atlas.cli import main  # noqa: E402
from atlas.store.study import open_study  # noqa: E402
from atlas.views.study_plot import _shock_curve, _stability_curves, _stability_map  # noqa: E402
from atlas.views.style import CURVE_SIZE, MAP_SIZE  # noqa: E402
from tests.helpers import study_config  # noqa: E402


def _study(tmp_path, pendulum: str, extra: str = ""):
    out = tmp_path / "s.h5"
    assert main(["stability", str(study_config(tmp_path / "s.yaml", pendulum, out,
                                                 extra))]) == 0
    return open_study(out)


@pytest.fixture(scope="module")
def over_torque(tmp_path_factory):
    """α = 0.2: τ across the homoclinic torque (≈ 0.49), wells −1 to 2 in the window, the
    Gaussian with σθ ≠ σθ̇."""
    return _study(tmp_path_factory.mktemp("figure-data"),
                  "alpha: 0.2, omega0: 1.0, torque: [0.0, 0.2, 0.6, 0.8]",
                  "stability: {sigma_theta: 0.3, sigma_theta_dot: 0.5}\n")


def _draw(draw, size=CURVE_SIZE):
    fig = Figure(figsize=size)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    draw(ax)
    return ax


def _curves(ax) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{label: (x, y)} of the drawn data lines, without the NaN breaks between points."""
    out = {}
    for line in ax.lines:
        x = np.asarray(line.get_xdata(), float)
        y = np.asarray(line.get_ydata(), float)
        if len(x) == 2 and x[0] == x[1]:  # a bifurcation line across the axes
            continue
        keep = np.isfinite(x)
        out[line.get_label()] = (x[keep], y[keep])
    return out


def _all_differ(values: dict[str, np.ndarray]) -> None:
    """The variables compared differ at some point (else a swap would pass unseen)."""
    for (a, u), (b, v) in itertools.combinations(values.items(), 2):
        assert not np.allclose(u, v, equal_nan=True), (a, b)


def test_the_stability_curves_are_drawn_from_their_variables(over_torque):
    ds = over_torque
    ks = list(ds["k"].values)
    assert ks[0] == -1 and 0 in ks  # k = 0 is not the first row: isel(k=0) is well −1
    want = {"rest states (all wells)": ds["basin_stability"].sum("k").values,
            "rest state k = 0": ds["basin_stability"].sel(k=0).values,
            "running cycle": ds["running_stability"].values,
            "rest state under a Gaussian kick σθ = 0.3, σθ̇ = 0.5":
                ds["gaussian_stability"].values}
    _all_differ({**want, **{f"k = {k}": ds["basin_stability"].sel(k=k).values
                            for k in ks if k != 0},
                 "gaussian error": ds["gaussian_stability_error"].values})
    drawn = _curves(_draw(_stability_curves(ds, "torque")))
    assert set(drawn) == set(want)
    for label, values in want.items():
        x, y = drawn[label]
        np.testing.assert_array_equal(x, ds["torque"].values, err_msg=label)
        np.testing.assert_array_equal(y, values, err_msg=label)


def test_the_fatal_shock_curves_are_drawn_from_their_variables(over_torque):
    ds = over_torque
    rest = ds["minimal_fatal_shock"].sel(k=0).values
    running = ds["running_fatal_shock"].values
    assert np.isfinite(running).sum() >= 2 and np.isfinite(rest).all()
    _all_differ({"rest": rest, "running": running,
                 "rest error": ds["minimal_fatal_shock_error"].values,
                 "running error": ds["running_fatal_shock_error"].values})
    drawn = _curves(_draw(_shock_curve(ds, "torque")))
    assert set(drawn) == {"of the rest states", "of the running cycle"}
    for label, values in (("of the rest states", rest), ("of the running cycle", running)):
        x, y = drawn[label]
        np.testing.assert_array_equal(x, ds["torque"].values, err_msg=label)
        np.testing.assert_array_equal(y, values, err_msg=label)


def test_the_map_cells_are_the_rest_states_stability_alpha_up_torque_across(tmp_path):
    """A 2 × 3 (α × τ) study: the mesh's cells, row by row, are Σk basin_stability at
    (α_row, τ_col); a transposed or per-well map fails."""
    ds = _study(tmp_path, "alpha: [0.1, 0.3], omega0: 1.0, torque: [0.0, 0.3, 0.6]")
    total = ds["basin_stability"].sum("k").transpose("alpha", "torque").values
    assert not np.allclose(total[0], total[1])  # the rows differ: α matters
    ax = _draw(_stability_map(ds, "torque", "alpha"), MAP_SIZE)
    (mesh,) = ax.collections
    cells = np.asarray(mesh.get_array()).reshape(total.shape)
    np.testing.assert_array_equal(cells, total)
    centres = mesh.get_coordinates().mean(axis=(0, 1))
    assert ax.get_xlim() == (0.0, 0.6) and ax.get_ylim() == (0.1, 0.3)
    assert 0.0 < centres[0] < 0.6 and 0.1 < centres[1] < 0.3
