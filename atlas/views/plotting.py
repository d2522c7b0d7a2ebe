"""``atlas plot``: every figure of an atlas file, written as PNGs next to it (or into
another folder, as SVG or PDF, at another resolution: :func:`plot_file`'s ``outdir``,
``fmt``, ``dpi``).

The figures are those of :mod:`atlas.views.maps` (basin map, trapping time, boundary
distance of the first parameter point; of a parameter atlas, the basin maps of all its
points as small multiples, :mod:`atlas.views.multiples`, and with ``--point``/``--alpha``/
``--omega0``/``--torque`` the three maps of the points chosen) and :mod:`atlas.views.curves`
(basin fractions per swept parameter; basin stability against a swept torque). Everything
drawn is read first, the maps band by band and coarsened (:mod:`atlas.views.coarsen`), so
that the memory needed is bounded whatever the size of the map; then the figures are drawn,
on Linux in forked processes (:mod:`atlas.views.forked`) of which one imports matplotlib
while this one reads.
The figure functions are re-exported here: ``from atlas.views.plotting import basin_map``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from atlas.errors import AtlasError
from atlas.layout import parameter_names, points
from atlas.store.outputs import check_output, figure_metadata
from atlas.views.coarsen import read_maps, workers
from atlas.views.curves import CURVE_FIGURES, basin_stability, fraction_curves
from atlas.views.maps import MAP_FIGURES, basin_map, boundary_distance_map, trap_time_map
from atlas.views.multiples import draw_multiples, multiples_scene, multiples_size
from atlas.views.selectors import choose_points, point_index, point_suffix
from atlas.views.style import CURVE_SIZE, MAP_SIZE, PNG_OPTIONS, STYLE
from atlas.views.uncertainty import draw_uncertainty, has_uncertainty, uncertainty_scene

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["plot_atlas", "plot_file", "basin_map", "trap_time_map", "boundary_distance_map",
           "fraction_curves", "basin_stability", "read_maps"]


def _figure_jobs(tree: xr.DataTree, path: Path, outdir: Path | None = None,
                 fmt: str = "png", dpi: float | None = None,
                 chosen: list[dict] | None = None) -> list[tuple]:
    """The figures of ``tree`` (the atlas at ``path``) to write as ``<outdir>/<path's
    stem><figure>.<fmt>`` (``outdir`` by default the folder of ``path``), read: (figure
    path, size [in], drawer, scene, dpi) each, every scene read from the tree (the maps band
    by band). A parameter atlas's basin figure is its small multiples
    (:mod:`atlas.views.multiples`); ``chosen`` (points of :func:`atlas.layout.points`): only
    the three maps of each, named by its swept values (``NAME_alpha_0.5_t_trap.png``)."""
    path = Path(path)
    folder = path.parent if outdir is None else Path(outdir)
    ds = tree.to_dataset(inherit=False)

    def out(suffix: str) -> Path:
        return folder / f"{path.stem}{suffix}.{fmt}"

    stored = [name for name in ("basin", "t_trap", "boundary_distance")  # what the model
              if (name if name != "basin" else "attractor") in ds]  # stores of the three

    def map_jobs(prefix: str, index: dict, basin: bool = True) -> list[tuple]:
        read = [name for name in stored if basin or name != "basin"]
        maps = read_maps(tree, *read, **index)
        return [(out(prefix + suffix), MAP_SIZE, MAP_FIGURES[name][1],
                 MAP_FIGURES[name][0](tree, maps, **index), dpi)
                for name, suffix, map_name in (("basin", "", "basin"),
                                               ("trap_time", "_t_trap", "t_trap"),
                                               ("boundary_distance", "_boundary_distance",
                                                "boundary_distance"))
                if map_name in read]

    if chosen is not None:
        return [job for point in chosen
                for job in map_jobs(point_suffix(ds, point), point_index(ds, point))]
    whole = len(points(ds)) > 1  # a parameter atlas: every point's basins, small multiples
    jobs = map_jobs("", {}, basin=not whole)
    if whole:
        scene = multiples_scene(tree)
        jobs.insert(0, (out(""), multiples_size(len(scene["panels"])), draw_multiples,
                        scene, dpi))
    if has_uncertainty(ds):  # a driven pendulum's: f(ε) and its fit
        jobs.append((out("_uncertainty"), CURVE_SIZE, draw_uncertainty,
                     uncertainty_scene(tree), dpi))
    fractions, stability = CURVE_FIGURES["fractions"], CURVE_FIGURES["basin_stability"]
    swept = tree.to_dataset(inherit=False).dims
    exact = "basin_fraction_exact" in ds  # the curves draw the exact fractions
    for dim in (name for name in parameter_names(tree) if name in swept and exact):
        jobs.append((out(f"_fractions_{dim}"), CURVE_SIZE, fractions[1],
                     fractions[0](tree, dim), dpi))
        if dim == "torque":
            jobs.append((out("_basin_stability"), CURVE_SIZE, stability[1],
                         stability[0](tree, dim), dpi))
    return jobs


def _draw_figure(out: Path, size: tuple[float, float], draw, scene: dict,
                 dpi: float | None = None) -> Path:
    """Draw ``scene`` (``draw(ax, **scene)``) into a figure of ``size`` [in] of its own (no
    pyplot), laid out tight, and write it to ``out`` in the format its suffix names (PNG for
    a file object) at ``dpi`` [pixels per inch] (default: the style's ``savefig.dpi``, 150;
    for SVG and PDF it only sets the resolution of the embedded basin-map images)."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    dpi = STYLE["savefig.dpi"] if dpi is None else dpi
    with matplotlib.rc_context(STYLE):
        # laid out at the resolution it is saved at, so that the text the layout measures
        # is measured once (matplotlib caches it per renderer and resolution)
        fig = Figure(figsize=size, dpi=dpi)
        FigureCanvasAgg(fig)
        draw(fig.add_subplot(), **scene)
        fig.tight_layout()
        # laid out once: without this, savefig would draw the figure once more first
        # (for tight_layout's placeholder engine) before drawing it into the PNG
        fig.set_layout_engine(None)
        suffix = Path(out).suffix.lower() if isinstance(out, (str, Path)) else ".png"
        fig.savefig(out, dpi=dpi, metadata=figure_metadata(suffix, "atlas plot"),
                    **({"pil_kwargs": PNG_OPTIONS} if suffix == ".png" else {}))
    return out


def plot_atlas(tree: xr.DataTree, path: Path, chosen: list[dict] | None = None
               ) -> list[Path]:
    """Write the figures of the atlas stored at ``path`` next to it (``chosen``: only the
    maps of these points, as :func:`_figure_jobs`); returns the PNG paths.

    Everything drawn is read before the first PNG is written (a file that cannot be read
    leaves none): the maps of the drawn parameter point band by band, coarsened to the
    figure's pixels (:func:`read_maps`), so that the memory needed is bounded whatever the
    size of the map, and what else each figure shows."""
    return [_draw_figure(*job) for job in _figure_jobs(tree, path, chosen=chosen)]


def plot_file(path: str | Path, outdir: str | Path | None = None, fmt: str = "png",
              dpi: float | None = None, selectors: dict | None = None) -> list[Path]:
    """``atlas plot``: :func:`plot_atlas` of the atlas file at ``path``, opened and closed
    here; the figures are written into ``outdir`` (default: next to the file) in format
    ``fmt`` (a suffix matplotlib writes: png, svg, pdf) at ``dpi`` [pixels per inch; default
    150]; ``selectors`` (``point``, ``alpha``, ``omega0``, ``torque``: lists, as
    :func:`atlas.views.selectors.choose_points` takes them): only the maps of the points
    they choose.

    A figure is written only where nothing is or a figure atlas wrote
    (:func:`atlas.store.outputs.check_output`): never over the atlas itself or another file.

    On Linux the figures are drawn by forked processes (:class:`atlas.views.forked.ForkedJobs`):
    one is started first and imports matplotlib (:func:`_warm_up`) while this one opens and
    reads the file, then draws the figures with forks of itself, on every core at once (one
    process per core and one more, so that a figure that finishes first does not leave a core
    idle: three for the three maps on 2 cores). Elsewhere (no safe ``fork``) they are drawn
    here, after reading."""
    from atlas.store.study import is_study_file

    if is_study_file(path):  # a stability study: its own figures
        from atlas.views.study_plot import plot_study

        if selectors and any(selectors.values()):
            raise AtlasError(f"{path}: a stability study; --point, --alpha, --omega0 and "
                             "--torque choose the maps of an atlas file")

        return plot_study(path, outdir, fmt, dpi)
    from atlas.views.forked import ForkedJobs, can_fork

    drawers = ForkedJobs.start(_warm_up, _draw_job, workers() + 1) if can_fork() else None
    try:
        from atlas.store.reader import (
            open_atlas,  # imported after the fork: xarray, h5py only here
        )

        tree = open_atlas(path)
        try:
            chosen = choose_points(tree.to_dataset(inherit=False), **(selectors or {}))
            jobs = _figure_jobs(tree, path, outdir, fmt, dpi, chosen)
        finally:
            tree.close()
        for job in jobs:  # before any figure is written
            check_output(job[0], "figure", inputs=(path,), option="--outdir",
                         command="atlas plot")
        if outdir is not None:
            Path(outdir).mkdir(parents=True, exist_ok=True)
        if drawers is None:
            return [_draw_job(job) for job in jobs]
        drawers.run(jobs)
        return [job[0] for job in jobs]
    finally:
        if drawers is not None:
            drawers.close()


def _draw_job(job: tuple) -> Path:
    """:func:`_draw_figure` of one of :func:`_figure_jobs`."""
    return _draw_figure(*job)


def _warm_up() -> None:
    """Import what drawing needs and draw a small figure with a legend, a log colour bar and
    a PNG of it, so that every drawing process forked after this finds matplotlib, the fonts,
    the mathtext parser and the PNG writer ready. The colour bar spans 1e-16 to 1e4, so the
    labels 10^k of the log colour bars (trapping times, boundary distances) are parsed here
    once, while the reader is still reading, rather than in each figure."""
    import io

    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm

    def draw(ax):
        ax.plot([0.0, 1.0], label="θ̇0 [rad/s]")
        ax.legend()
        ax.figure.colorbar(ScalarMappable(LogNorm(1e-16, 1e4)), ax=ax)

    _draw_figure(io.BytesIO(), (2, 2), draw, {})
