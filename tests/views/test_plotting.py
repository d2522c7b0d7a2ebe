"""`atlas plot`: the figures read the atlas and draw what it holds (inspect the Axes)."""

import errno
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

import atlas  # noqa: E402
from atlas.views.plotting import basin_map, fraction_curves, plot_atlas, trap_time_map  # noqa: E402
from atlas.views.style import SEPARATRIX_COLOR  # noqa: E402
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
    from atlas.views.coarsen import MAX_PIXELS, coarsen_blocks

    rows, cols = 3 * MAX_PIXELS, 2 * MAX_PIXELS + 1
    labels = np.full((rows, cols), 2.0)
    labels[::3, :] = -2.0  # one row in three: the mean (≈ 0.67) would be no label at all
    labels[:3, :] = np.nan
    small = coarsen_blocks(labels, "mode")
    assert small.shape == (MAX_PIXELS, 801)  # blocks of 3 × 3 cells
    assert np.all(np.isnan(small[0])) and set(np.unique(small[1:])) == {2.0}
    distance = np.arange(rows * cols, dtype=float).reshape(rows, cols)
    assert coarsen_blocks(distance, "min")[1, 1] == distance[3, 3]
    assert coarsen_blocks(distance, "max")[0, 0] == distance[2, 2]


def _old_basin_labels(attractor, status):
    """The image the basin map drew before streaming: k where trapped or near_boundary, the
    running basin as kmax + 1, NaN for no label."""
    from atlas.kernels import NEAR_BOUNDARY, RUNNING, RUNNING_NEAR_BOUNDARY, TRAPPED

    k = attractor.astype(float)
    k[~np.isin(status, (TRAPPED, NEAR_BOUNDARY))] = np.nan
    finite = k[np.isfinite(k)]
    kmax = int(finite.max()) if finite.size else 0
    k[(status == RUNNING) | (status == RUNNING_NEAR_BOUNDARY)] = kmax + 1
    return k


@pytest.mark.parametrize("chunked", ["preferred", "dask", "decoded"])
def test_streamed_coarsening_equals_the_whole_array(monkeypatch, chunked):
    """The maps are read in bands of whole blocks and reduced by compiled kernels: the result
    equals ``coarsen_blocks`` of the whole array, edge blocks (53 × 40 cells in blocks of 8 × 6)
    and ties (the smallest k wins; the running basin, the largest label, loses) included;
    chunks known from the file's encoding or from dask, and labels decoded to float (NaN
    where the file has its fill value) as plain xarray would read them."""
    from atlas.views import coarsen
    from atlas.views.coarsen import _read_extreme, _read_labels, coarsen_blocks

    monkeypatch.setattr(coarsen, "MAX_PIXELS", 7)
    monkeypatch.setattr(coarsen, "BAND_CELLS", 500)
    rng = np.random.default_rng(14)
    shape = (53, 40)
    attractor = rng.integers(-2, 3, shape).astype(np.int16)
    status = rng.choice(np.array([0, 0, 0, 1, 2, 3, 4, 5], np.int8), shape)
    status[:8, :6] = 1  # a block without a label
    status[8:16, :6] = 4  # a running block
    attractor[status % 3 != 0] = -32768  # the fill where not trapped (status 0 or 3)
    t = rng.exponential(10.0, shape).astype(np.float32)
    t[rng.random(shape) < 0.2] = 0.0
    t[rng.random(shape) < 0.2] = np.nan
    t[:8, 6:12] = np.nan
    ds = xr.Dataset({"attractor": (("theta_dot0", "theta0"), attractor),
                     "status": (("theta_dot0", "theta0"), status),
                     "t_trap": (("theta_dot0", "theta0"), t)})
    if chunked == "dask":
        ds = ds.chunk({"theta_dot0": 5})
    elif chunked == "decoded":
        ds["attractor"] = ds["attractor"].where(ds["attractor"] != -32768).astype(np.float32)
        ds["attractor"].encoding["preferred_chunks"] = {"theta_dot0": 5, "theta0": 40}
    else:
        for name in ds.data_vars:
            ds[name].encoding["preferred_chunks"] = {"theta_dot0": 5, "theta0": 40}
    reads = []
    read = coarsen._read_rows
    monkeypatch.setattr(coarsen, "_read_rows",
                        lambda da, r0, r1: reads.append((r0, r1)) or read(da, r0, r1))

    image, kmin, kmax, running = _read_labels(ds)
    expected = coarsen_blocks(_old_basin_labels(attractor, status), "mode")
    assert image.shape == expected.shape == (7, 7)
    np.testing.assert_array_equal(image, expected)
    assert (kmin, kmax, running) == (-2, 2, True)
    assert np.isnan(image[0, 0]) and image[1, 0] == kmax + 1
    assert sorted(set(reads)) == [(0, 40), (40, 53)]  # lcm(8 rows, 5-row chunks) = 40
    for how in ("max", "min"):
        image, lo, hi = _read_extreme(ds, "t_trap", how)
        np.testing.assert_array_equal(image, coarsen_blocks(t.astype(float), how))
        positive = t[np.isfinite(t) & (t > 0)]
        assert (lo, hi) == (positive.min(), positive.max())


def _whole_maps(point):
    """The images of the maps of one parameter point (a Dataset loaded whole) coarsened in
    memory, as the figures drew them before streaming."""
    from atlas.views.coarsen import coarsen_blocks

    k = coarsen_blocks(_old_basin_labels(point["attractor"].values, point["status"].values), "mode")
    t = point["t_trap"].values.astype(float)
    lo = t[np.isfinite(t) & (t > 0)].min()
    return (np.ma.masked_invalid(k), coarsen_blocks(np.where(t > 0, t, lo / 2), "max"),
            np.ma.masked_invalid(coarsen_blocks(point["boundary_distance"].values.astype(float),
                                          "min")))


@pytest.mark.parametrize("band_cells,band_rows", [(60, 3), (600, 20)])
def test_a_big_map_is_drawn_from_bands_never_read_whole(sweep_tree, monkeypatch, tmp_path,
                                                         band_cells, band_rows):
    """``plot_atlas`` of an atlas opened lazily, as ``atlas plot`` does: with MAX_PIXELS 8 the
    30 × 20 maps are coarsened in blocks of 3 × 4 cells, read a band at a time (one block
    row, or the file's whole 20-row chunk), their stored chunks inflated here, and the images
    are those of the whole arrays coarsened in memory; the maps are never loaded. Another
    parameter point reads its own chunks."""
    from atlas.store import hdf5 as store
    from atlas.views import coarsen, plotting

    _, path = sweep_tree
    monkeypatch.setattr(coarsen, "MAX_PIXELS", 8)
    monkeypatch.setattr(coarsen, "BAND_CELLS", band_cells)
    sizes, inflated = [], []
    read, inflate = coarsen._read_rows, store.StoredRows._inflate
    monkeypatch.setattr(coarsen, "_read_rows",
                        lambda source, r0, r1: sizes.append((r1 - r0) * source.shape[1]) or
                        read(source, r0, r1))
    monkeypatch.setattr(store.StoredRows, "_inflate",
                        lambda self, *args: inflated.append(1) or inflate(self, *args))
    figures = []
    monkeypatch.setattr(plt.Figure, "savefig", lambda fig, *a, **k: figures.append(fig))
    tree, whole = atlas.open(path), atlas.open(path)
    try:
        plotting.plot_atlas(tree, tmp_path / "lazy.h5")
        # read: attractor and status of all 6 points (the small multiples), t_trap and
        # boundary_distance of the first
        assert max(sizes) == band_rows * 30 and len(sizes) == 14 * -(-20 // band_rows)
        assert inflated  # the stored chunks, inflated here
        assert not tree["attractor"].variable._in_memory
        whole = whole.load().to_dataset(inherit=False)
        drawn = [fig.axes[0].images[0].get_array() for fig in figures[:3]]
        for image, expected in zip(drawn, _whole_maps(whole.isel(alpha=0, omega0=0))):
            assert image.shape == (7, 8)
            np.testing.assert_array_equal(image, expected)
        maps = plotting.read_maps(tree, alpha=-1, omega0=1)
        assert not tree["attractor"].variable._in_memory
    finally:
        tree.close()
        whole.close()
    other = whole.isel(alpha=2, omega0=1)
    k, _, d = _whole_maps(other)
    np.testing.assert_array_equal(np.ma.masked_invalid(maps["basin"][0]), k)
    np.testing.assert_array_equal(np.ma.masked_invalid(maps["boundary_distance"][0]), d)
    t_trap = other["t_trap"].values.astype(float)  # before the figure's log scale
    np.testing.assert_array_equal(maps["t_trap"][0], coarsen.coarsen_blocks(t_trap, "max"))


def test_a_damaged_chunk_of_a_coarsened_map_is_one_line(sweep_tree, monkeypatch, tmp_path):
    """A chunk that does not inflate is read again through HDF5, which reports it: `atlas
    plot` exits 2 with one line and writes no figure."""
    import io
    import shutil
    from contextlib import redirect_stderr

    import h5py

    from atlas.cli import main
    from atlas.views import coarsen

    _, path = sweep_tree
    bad = shutil.copyfile(path, tmp_path / "bad.h5")
    with h5py.File(bad, "r") as f:
        chunk = f["t_trap"].id.get_chunk_info_by_coord((0, 0, 0, 0))  # the drawn point
    with open(bad, "r+b") as f:
        f.seek(chunk.byte_offset + chunk.size // 2)
        f.write(b"\xff" * 16)
    monkeypatch.setattr(coarsen, "MAX_PIXELS", 8)
    err = io.StringIO()
    with redirect_stderr(err):
        assert main(["plot", str(bad)]) == 2
    assert err.getvalue().count("\n") == 1 and "damaged data" in err.getvalue()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.h5"]
    plt.close("all")


def test_fraction_curves_one_per_basin_with_grid_counts(sweep_tree):
    """The largest basins get a curve each (±k merged: the window is symmetric, no torque),
    the exact fractions as lines and the grid counts as dots of the same colour; the other
    basins are thin grey lines, one each."""
    tree, _ = sweep_tree
    ax = fraction_curves(tree, max_curves=3)
    curves = {line.get_label(): line for line in ax.lines
              if line.get_label().startswith("k =")}
    assert len(curves) == 3 and "k = 0" in curves and "±k merged" in ax.get_title()
    point = tree.to_dataset(inherit=False).isel(omega0=0)
    np.testing.assert_array_equal(curves["k = 0"].get_ydata(),
                                  point["basin_fraction_exact"].sel(k=0))
    np.testing.assert_array_equal(curves["k = 0"].get_xdata(), [0.1, 0.5, 2.0])
    dots = next(ln for ln in ax.lines if ln.get_marker() == "o" and ln.get_color()
                == curves["k = 0"].get_color())
    np.testing.assert_array_equal(dots.get_ydata(), point["basin_fraction"].sel(k=0))
    groups = {abs(int(k)) for k in point["k"].values}
    thin = [ln for ln in ax.lines if ln.get_linewidth() < 1 and ln.get_linestyle() == "-"
            and len(ln.get_xdata())]
    assert len(thin) == len(groups) - 3
    plt.close("all")


def test_fraction_curves_along_each_swept_parameter_hold_the_others(sweep_tree):
    """A sweep over α and ω0 together: curves against ω0 at the first α, said in the title,
    read from the same variables as the single-point views."""
    tree, _ = sweep_tree
    ax = fraction_curves(tree, dim="omega0")
    k0 = next(line for line in ax.lines if line.get_label() == "k = 0")
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
    red = [ln for ln in ax.lines if ln.get_color() == SEPARATRIX_COLOR
           and len(ln.get_xdata()) > 2]
    sep = tree["separatrices"]
    n_branches = len({(int(n), str(b)) for n, b in zip(sep["saddle_n"].values,
                                                        sep["branch"].values)})
    assert len(red) == n_branches >= 4
    plt.close("all")
    proc = run_cli("plot", tmp_path / "c.h5")
    assert proc.returncode == 0 and (tmp_path / "c.png").exists()


@pytest.mark.slow
def test_atlas_plot_draws_in_other_processes_what_plot_atlas_draws(sweep_tree, tmp_path):
    """`atlas plot` reads the file here and draws in forked processes (plot_file; five figures
    of an α × ω0 sweep in two or more processes): the PNGs are byte for byte those that
    plot_atlas draws in this process."""
    from atlas.cli import main

    _, path = sweep_tree
    here, there = tmp_path / "here", tmp_path / "there"
    here.mkdir()
    there.mkdir()
    tree = atlas.open(shutil.copy(path, here / "s.h5"))
    try:
        expected = plot_atlas(tree, here / "s.h5")
    finally:
        tree.close()
    assert main(["plot", str(shutil.copy(path, there / "s.h5"))]) == 0
    assert len(expected) == 5
    for png in expected:
        assert (there / png.name).read_bytes() == png.read_bytes(), png.name


def _failing_savefig(save, fails: str, error: Exception):
    """``save`` (Figure.savefig), raising ``error`` for the PNG whose name ends in ``fails``."""

    def savefig(fig, out, *args, **kwargs):
        if str(out).endswith(fails):
            raise error
        return save(fig, out, *args, **kwargs)

    return savefig


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks on Linux only")
def test_a_figure_that_fails_in_a_drawing_process_fails_atlas_plot(sweep_tree, tmp_path,
                                                                   monkeypatch):
    """A failure in a drawing process is atlas plot's: a full disk is one line and exit 1, as
    when the figures were drawn in this process; any other exception is raised here, with the
    drawing process's traceback as its cause."""
    import io
    from contextlib import redirect_stderr

    from atlas.cli import main

    _, path = sweep_tree
    bad = shutil.copy(path, tmp_path / "s.h5")
    png, save = tmp_path / "s_t_trap.png", plt.Figure.savefig
    monkeypatch.setattr(plt.Figure, "savefig", _failing_savefig(
        save, "_t_trap.png", OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(png))))
    err = io.StringIO()
    with redirect_stderr(err):
        assert main(["plot", str(bad)]) == 1
    assert err.getvalue() == f"atlas: error: {png}: {os.strerror(errno.ENOSPC)}\n"
    monkeypatch.setattr(plt.Figure, "savefig", _failing_savefig(
        save, "_boundary_distance.png", ValueError("no colour for this")))
    with pytest.raises(ValueError, match="no colour for this") as raised:
        main(["plot", str(bad)])
    assert "savefig" in str(raised.value.__cause__)  # where it was raised, over there


@pytest.mark.parametrize("figure", ["basin", "trap_time", "boundary_distance"])
@pytest.mark.parametrize("which", ["untilted", "torque"])
def test_nothing_is_cut_off_at_a_maps_edge(sweep_tree, swing_atlas, which, figure):
    """The PNGs atlas plot writes: a margin of white all round, so no label, tick or legend
    text runs off the figure (the torque basin map's colour-bar label is the longest), and
    the figure is not empty."""
    import io

    from atlas.views import plotting
    from atlas.views.maps import MAP_FIGURES
    from atlas.views.style import MAP_SIZE

    tree = sweep_tree[0] if which == "untilted" else atlas.open(swing_atlas)
    read, draw = MAP_FIGURES[figure]
    png = io.BytesIO()
    plotting._draw_figure(png, MAP_SIZE, draw, read(tree))
    png.seek(0)
    image = plt.imread(png)[..., :3]
    white = np.all(image > 0.99, axis=-1)
    assert white.mean() < 0.9  # something is drawn
    for border in (white[:3], white[-3:], white[:, :3], white[:, -3:]):
        assert border.all()
