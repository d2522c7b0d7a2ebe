"""The curves against a swept parameter mean what they show: no error bar leaves [0, 1], no
two basins share a colour, the lower panel is the measured error (grid count − exact
fraction), ±k are merged only where the window's symmetry makes their basins equal, and the
bifurcations are marked where they lie."""

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.colors import to_hex  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import atlas  # noqa: E402
from atlas.views.curves import (  # noqa: E402
    INFORMATIVE_BOUND,
    _draw_fractions,
    basin_stability,
    bifurcation_marks,
    fraction_curves,
)
from tests.helpers import write_config  # noqa: E402


def _ax():
    return Figure(figsize=(9, 5.4)).add_subplot()


def _bar_ends(ax) -> np.ndarray:
    """The y of both ends of every error bar drawn on ``ax``."""
    ends = [seg[:, 1] for c in ax.containers if c.has_yerr
            for col in c.lines[2] for seg in col.get_segments()]
    return np.concatenate(ends) if ends else np.empty(0)


def _legend(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_error_bars_only_where_no_exact_value_inside_the_unit_interval():
    """Bars only at points without an exact value (NaN), where the bound is all there is:
    clipped to [0, 1] (grid counts near 0 and 1, bounds 0.05 and 0.09), none for a bound
    of 0.5 (a 64² grid's, which once ran from −0.36 to 1.26), none at the exact points
    (bound 0.07 there, 35 times the measured 0.002); the legend says what the bars are."""
    x = np.array([0.1, 0.2, 0.3, 0.4])
    low = (np.array([np.nan, np.nan, np.nan, 0.3]), np.array([0.021, 0.03, 0.301, 0.302]),
           np.array([0.05, 0.09, 0.5, 0.07]), "k = 0", "#000000")
    high = (np.array([np.nan, np.nan, np.nan, 0.6]), np.array([0.971, 0.959, 0.6, 0.599]),
            np.array([0.05, 0.09, 0.5, 0.07]), "k = ±1", "#ff0000")
    ax = _ax()
    _draw_fractions(ax, x, [low, high], [], [], "α", "t")
    ends = _bar_ends(ax)
    assert ends.size == 8  # two bars per curve, two ends each: none at 0.5, none where exact
    assert ends.min() == 0.0 and ends.max() == 1.0  # clipped, not dropped
    xs = {float(seg[0, 0]) for c in ax.containers if c.has_yerr for col in c.lines[2]
          for seg in col.get_segments()}
    assert xs == {0.1, 0.2}
    assert any("no exact value" in t and f"< {INFORMATIVE_BOUND:g}" in t
               and "clipped to [0, 1]" in t for t in _legend(ax))


def test_no_bars_on_exact_points_and_the_legend_says_why():
    """Every point exact (to 1e-13): no error bar, however small the bound; the legend
    names the largest measured error and the largest bound, as read from the curves."""
    x = np.array([0.1, 0.2, 0.3])
    exact = np.array([0.2, 0.4, 0.6])
    grid = exact + np.array([0.0013, -0.0021, 0.0004])
    bound = np.array([0.031, 0.047, 0.012])
    ax = _ax()
    _draw_fractions(ax, x, [(exact, grid, bound, "k = 0", "#000000")], [], [], "α", "t")
    assert _bar_ends(ax).size == 0
    (note,) = [t for t in _legend(ax) if "not" in t and "bound" in t]
    assert "≤ 0.0021" in note and "≤ 0.047" in note


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """Two dampings either side of α = ω0, separatrices on (exact fractions), in a window
    symmetric about (0, 0)."""
    tmp = tmp_path_factory.mktemp("curves")
    cfg = write_config(tmp / "s.yaml", f"""\
pendulum: {{alpha: [0.5, 1.5], omega0: 1.0}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 24}}
  theta_dot0: {{start: -4, stop: 4, num: 20}}
output: {tmp / 's.h5'}
""")
    return atlas.run(atlas.load_config(cfg), quiet=True)


def _unit(below) -> float:
    """The scale of the measured-error panel, read from its label ("[10⁻³]" …)."""
    label = below.get_ylabel()
    return next((10.0 ** -p for p in range(2, 16) if f"[10⁻{str(p).translate(_SUP)}]" in label),
                1.0)


_SUP = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")


@pytest.mark.slow
def test_curves_of_a_real_sweep_are_honest(sweep):
    """On a real atlas: no bars (every point exact); one colour per curve; the lower panel is the
    measured error; ±k merged and said so (the window is symmetric), each merged curve the
    sum of the two exact fractions; α = ω0 marked and named."""
    ds = sweep.to_dataset(inherit=False)
    ax = fraction_curves(sweep, ax=_ax(), max_curves=20)
    assert _bar_ends(ax).size == 0  # every point exact: the measured error is below
    curves = {ln.get_label(): ln for ln in ax.lines if ln.get_label().startswith("k =")}
    colours = [to_hex(ln.get_color()) for ln in curves.values()]
    assert len(set(colours)) == len(colours) >= 3
    below = ax.figure.axes[-1]
    residual = next(ln for ln in below.lines
                    if to_hex(ln.get_color()) == to_hex(curves["k = 0"].get_color()))
    k0 = ds.sel(k=0)
    np.testing.assert_allclose(residual.get_ydata() * _unit(below),
                               k0["basin_fraction"] - k0["basin_fraction_exact"],
                               rtol=1e-12, atol=1e-15)
    assert "±k merged" in ax.get_title() and "k = ±1" in curves
    np.testing.assert_allclose(curves["k = ±1"].get_ydata(),
                               ds["basin_fraction_exact"].sel(k=[-1, 1]).sum("k"), rtol=1e-12)
    assert any(t.get_text().startswith("α = ω0") for t in ax.texts)
    assert [ln.get_xdata()[0] for ln in ax.lines if ln.get_linestyle() == ":"] == [1.0]


def _fraction_tree(theta0, torque=0.0) -> xr.DataTree:
    """An α sweep of two points and wells −1, 0, 1 whose fractions differ for ±k."""
    f = np.array([[0.2, 0.5, 0.3], [0.25, 0.45, 0.3]])
    ds = xr.Dataset({"basin_fraction_exact": (("alpha", "k"), f),
                     "basin_fraction": (("alpha", "k"), f + 0.001),
                     "basin_fraction_grid_error_bound": (("alpha", "k"), np.full((2, 3), 0.02))},
                    coords={"alpha": [0.1, 0.2], "k": [-1, 0, 1], "omega0": 1.0,
                            "torque": torque, "theta0": theta0,
                            "theta_dot0": np.linspace(-4, 4, 5)})
    return xr.DataTree(dataset=ds)


@pytest.mark.parametrize("theta0, torque", [(np.linspace(-2 * np.pi, 3 * np.pi, 6), 0.0),
                                            (np.linspace(-np.pi, np.pi, 6), 0.1)],
                         ids=["shifted window", "torque"])
def test_k_and_minus_k_stay_apart_without_the_symmetry(theta0, torque):
    """A window not centred on (0, 0), or a torque (which breaks the point reflection): k
    and −k are curves of their own, with their own values."""
    ax = fraction_curves(_fraction_tree(theta0, torque), ax=_ax())
    curves = {ln.get_label(): ln for ln in ax.lines if ln.get_label().startswith("k =")}
    assert set(curves) == {"k = −1", "k = 0", "k = +1"} and "merged" not in ax.get_title()
    np.testing.assert_array_equal(curves["k = −1"].get_ydata(), [0.2, 0.25])


def test_k_and_minus_k_merge_in_a_symmetric_window():
    ax = fraction_curves(_fraction_tree(np.linspace(-np.pi, np.pi, 6)), ax=_ax())
    curves = {ln.get_label(): ln for ln in ax.lines if ln.get_label().startswith("k =")}
    assert set(curves) == {"k = 0", "k = ±1"} and "±k merged" in ax.get_title()
    np.testing.assert_allclose(curves["k = ±1"].get_ydata(), [0.5, 0.55], rtol=1e-15)


def test_the_smaller_basins_are_thin_single_lines_never_one_sum():
    """Beyond max_curves each basin is one thin grey line of its own size, none summed."""
    x = np.array([1.0, 2.0])
    others = [np.array([0.01, 0.02]), np.array([0.015, 0.0])]
    big = (np.array([0.5, 0.6]), np.array([0.5, 0.6]), np.full(2, 0.5), "k = 0", "#00aa00")
    ax = _ax()
    _draw_fractions(ax, x, [big], others, [], "α", "t")
    thin = [ln for ln in ax.lines if ln.get_linewidth() < 1 and ln.get_linestyle() == "-"
            and len(ln.get_xdata())]
    assert len(thin) == 2 and max(ln.get_ydata().max() for ln in thin) == 0.02


def test_each_curve_has_a_marker_shape_of_its_own():
    """Three curves in one colour (as near as wells of one parity can be): their grid
    counts, their measured errors and their legend entries (line and marker) tell them
    apart by shape."""
    x = np.array([1.0, 2.0])
    curves = [(np.array([v, v]), np.array([v, v]), np.full(2, 0.5), f"k = ±{j}", "#555500")
              for j, v in enumerate((0.5, 0.3, 0.1))]
    ax = _ax()
    _draw_fractions(ax, x, curves, [], [], "α", "t")
    dots = {ln.get_ydata()[0]: ln.get_marker() for ln in ax.lines
            if ln.get_linestyle() == "None" and len(ln.get_xdata()) == 2}
    assert len(set(dots.values())) == 3
    residuals = [ln.get_marker() for ln in ax.figure.axes[-1].lines
                 if ln.get_marker() not in ("None", "")]
    assert sorted(residuals) == sorted(dots.values())
    handles = dict(zip(_legend(ax), ax.get_legend().legend_handles))
    for j, v in enumerate((0.5, 0.3, 0.1)):
        handle = handles[f"k = ±{j}"]
        assert handle.get_marker() == dots[v] and handle.get_linestyle() == "-"


def _torque_ds(torque=(0.06, 0.26, 0.46, 0.66, 0.86, 0.96), **extra) -> xr.Dataset:
    return xr.Dataset({**extra}, coords={"torque": np.asarray(torque), "omega0": 1.0,
                                         "alpha": 0.05})


def test_bifurcations_are_read_from_the_file_or_passed_in():
    """τ_c from a study file's homoclinic_torque, else as passed in by the command layer;
    τ = ω0² only inside the swept range (here ω0² = 1 > 0.96: not drawn)."""
    marks = bifurcation_marks(_torque_ds(homoclinic_torque=0.1307), "torque")
    assert [v for v, _ in marks] == [0.1307] and "homoclinic" in marks[0][1]
    assert bifurcation_marks(_torque_ds(), "torque") == []
    assert [v for v, _ in bifurcation_marks(_torque_ds(), "torque", 0.2)] == [0.2]
    wide = xr.Dataset(coords={"torque": [0.5, 1.2], "omega0": 1.0})
    assert [v for v, _ in bifurcation_marks(wide, "torque")] == [1.0]


def test_basin_stability_marks_the_homoclinic_torque_and_keeps_bars_in_range():
    """A torque sweep drawn with the homoclinic torque passed in: marked; bars only where
    there is no exact value (the running basin's first three points), in [0, 1] (running
    near 0, bound 0.05: clipped; bound 0.4: none), none on the exact rest states; the rest
    states and the running basin in two colours; the lower panel their measured errors."""
    torque = np.array([0.06, 0.11, 0.16, 0.21])
    rest = np.array([[0.98, 0.0], [0.97, 0.01], [0.7, 0.05], [0.5, 0.1]])
    running_exact = 1 - rest.sum(axis=1)
    ds = _torque_ds(
        torque,
        basin_fraction_exact=(("torque", "k"), rest),
        basin_fraction=(("torque", "k"), rest + 0.001),
        basin_fraction_grid_error_bound=(("torque", "k"), np.full((4, 2), 0.025)),
        running_fraction_exact=("torque", np.r_[np.full(3, np.nan), running_exact[3]]),
        running_fraction=("torque", running_exact - 0.002),
        running_fraction_grid_error_bound=("torque", [0.05, 0.05, 0.05, 0.4]),
    ).assign_coords(k=[0, 1])
    ax = basin_stability(xr.DataTree(dataset=ds), ax=_ax(), homoclinic_torque=0.13)
    ends = _bar_ends(ax)
    # running 0.018, 0.018, 0.248 ± 0.05: the first two clipped at 0
    np.testing.assert_allclose(np.sort(ends), [0.0, 0.0, 0.068, 0.068, 0.198, 0.298])
    exact = {ln.get_label(): ln for ln in ax.lines if ln.get_label().endswith("exact area")}
    assert to_hex(exact["rest states, exact area"].get_color()) != to_hex(
        exact["running, exact area"].get_color())
    assert [ln.get_xdata()[0] for ln in ax.lines if ln.get_linestyle() == ":"] == [0.13]
    below = ax.figure.axes[-1]
    residuals = {to_hex(ln.get_color()): ln.get_ydata() for ln in below.lines
                 if len(ln.get_xdata()) == 4}
    np.testing.assert_allclose(residuals[to_hex(exact["rest states, exact area"].get_color())],
                               2.0)
    np.testing.assert_allclose(residuals[to_hex(exact["running, exact area"].get_color())],
                               [np.nan] * 3 + [-2.0])
    assert "[10⁻³]" in below.get_ylabel()


def test_exact_lines_break_at_a_bifurcation():
    """A line of exact values never joins two points that a bifurcation separates (a mark's
    value, or the bracket of the homoclinic torque): the jump stays a jump."""
    from atlas.views.curves import _broken

    x = np.array([0.06, 0.11, 0.16, 0.21, 1.1])
    y = np.array([1.0, 1.0, 0.48, 0.40, 0.0])
    bx, by = _broken(x, y, [(1.0, "τ = ω0²: saddle-node"), (0.5, "α = ω0: critical damping")],
                     onset=(0.11, 0.16))
    gaps = np.flatnonzero(np.isnan(bx))
    assert np.isnan(by[gaps]).all() and bx.size == x.size + 2
    assert [bx[g - 1] for g in gaps] == [0.11, 0.21] and [bx[g + 1] for g in gaps] == [0.16, 1.1]
    same = _broken(x, y, [], None)
    assert np.array_equal(same[0], x) and np.array_equal(same[1], y)
