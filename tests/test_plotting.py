"""`atlas plot`: the figures read the atlas and draw what it holds (inspect the Axes)."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

import atlas  # noqa: E402
from atlas.plotting import basin_map, fraction_curves, plot_atlas, trap_time_map  # noqa: E402
from tests.helpers import run_cli, write_config  # noqa: E402


@pytest.fixture(scope="module")
def sweep_tree(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("plot")
    cfg = write_config(tmp / "s.yaml", f"""\
pendulum: {{alpha: [0.1, 0.5, 2.0], omega0: [1.0, 1.5]}}
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 30}}
  theta_dot0: {{start: -4, stop: 4, num: 20}}
separatrices: {{enabled: false}}
output: {tmp / 's.h5'}
""")
    return atlas.run(atlas.load_config(cfg), quiet=True), tmp / "s.h5"


def test_basin_map_colours_cells_by_k_and_marks_critical_points(sweep_tree):
    tree, _ = sweep_tree
    ax = basin_map(tree)
    image = ax.images[0]
    k = tree["attractor"].isel(alpha=0, omega0=0).values
    np.testing.assert_array_equal(np.asarray(image.get_array()), k.reshape(k.shape[-2:]))
    labels = [line.get_label() for line in ax.lines]
    assert "attractors (2πk, 0)" in labels and "saddles ((2j+1)π, 0)" in labels
    saddles = ax.lines[labels.index("saddles ((2j+1)π, 0)")]
    np.testing.assert_allclose(saddles.get_xdata(), np.pi * np.array([-3, -1, 1, 3]))
    assert "[rad]" in ax.get_xlabel() and "[rad/s]" in ax.get_ylabel()
    plt.close("all")


def test_trap_time_map_uses_a_log_scale(sweep_tree):
    tree, _ = sweep_tree
    ax = trap_time_map(tree)
    assert isinstance(ax.images[0].norm, LogNorm)
    plt.close("all")


@pytest.mark.slow
def test_big_maps_are_coarsened_by_the_mode_of_their_labels():
    """A map wider than the figure's pixels is drawn from blocks; a block of labels takes its
    most frequent label (never an average, which could name a well no orbit reached), and
    the continuous maps keep their extremes."""
    from atlas.plotting import MAX_PIXELS, _coarsen

    rows, cols = 3 * MAX_PIXELS, 2 * MAX_PIXELS + 1
    labels = np.full((rows, cols), 2.0)
    labels[::3, :] = -2.0  # one row in three: the mean (≈ 0.67) would be no label at all
    labels[:3, :] = np.nan
    small = _coarsen(labels, "mode")
    assert small.shape == (MAX_PIXELS, 801)  # blocks of 3 × 3 cells
    assert np.all(np.isnan(small[0])) and set(np.unique(small[1:])) == {2.0}
    distance = np.arange(rows * cols, dtype=float).reshape(rows, cols)
    assert _coarsen(distance, "min")[1, 1] == distance[3, 3]
    assert _coarsen(distance, "max")[0, 0] == distance[2, 2]


def test_fraction_curves_one_per_basin_with_error_bars(sweep_tree):
    tree, _ = sweep_tree
    ax = fraction_curves(tree, max_curves=3)
    bars = [c for c in ax.containers if c.has_yerr]
    assert len(bars) == 4  # three largest basins + "other k": grid counts with bounds
    curves = {line.get_label(): line for line in ax.lines
              if line.get_label().startswith(("k =", "other k"))}
    assert len(curves) == 4  # and the exact fractions as lines
    point = tree.to_dataset(inherit=False).sel(k=0).isel(omega0=0)
    np.testing.assert_array_equal(curves["k = +0"].get_ydata(), point["basin_fraction_exact"])
    np.testing.assert_array_equal(curves["k = +0"].get_xdata(), [0.1, 0.5, 2.0])
    grid = next(c for c in bars if c.lines[0].get_color() == curves["k = +0"].get_color())
    np.testing.assert_array_equal(grid.lines[0].get_ydata(), point["basin_fraction"])
    plt.close("all")


def test_fraction_curves_along_each_swept_parameter_hold_the_others(sweep_tree):
    """A sweep over α and ω0 together: curves against ω0 at the first α, said in the title,
    read from the same variables as the single-point views."""
    tree, _ = sweep_tree
    ax = fraction_curves(tree, dim="omega0")
    k0 = next(line for line in ax.lines if line.get_label() == "k = +0")
    np.testing.assert_array_equal(k0.get_xdata(), [1.0, 1.5])
    np.testing.assert_array_equal(
        k0.get_ydata(), tree["basin_fraction_exact"].sel(k=0).isel(alpha=0).values)
    assert "alpha = 0.1" in ax.get_title()
    plt.close("all")


@pytest.mark.slow
def test_plot_atlas_writes_the_figures(sweep_tree):
    tree, path = sweep_tree
    written = plot_atlas(tree, path)
    swept = [d for d in ("alpha", "omega0", "torque") if d in tree.dims]
    assert [p.name for p in written] == ["s.png", "s_t_trap.png", "s_boundary_distance.png",
                                         *(f"s_fractions_{d}.png" for d in swept)]
    assert all(p.stat().st_size > 10_000 for p in written)


@pytest.mark.slow
def test_atlas_plot_cli_draws_separatrices(tmp_path):
    cfg = write_config(tmp_path / "c.yaml", f"""\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 40}}
  theta_dot0: {{start: -4, stop: 4, num: 30}}
output: {tmp_path / 'c.h5'}
""")
    assert run_cli("run", cfg, "--quiet").returncode == 0
    tree = atlas.open(tmp_path / "c.h5")
    ax = basin_map(tree)
    red = [ln for ln in ax.lines if ln.get_color() == "red" and len(ln.get_xdata()) > 2]
    sep = tree["separatrices"]
    n_branches = len({(int(n), str(b)) for n, b in zip(sep["saddle_n"].values,
                                                        sep["branch"].values)})
    assert len(red) == n_branches >= 4
    plt.close("all")
    proc = run_cli("plot", tmp_path / "c.h5")
    assert proc.returncode == 0 and (tmp_path / "c.png").exists()
