"""``atlas plot``: every figure of an atlas file, written as PNGs next to it.

The figures are those of :mod:`atlas.views.maps` (basin map, trapping time, boundary
distance of the first parameter point) and :mod:`atlas.views.curves` (basin fractions per
swept parameter; basin stability against a swept torque). Everything drawn is read first, the
maps band by band and coarsened (:mod:`atlas.views.coarsen`), so that the memory needed is
bounded whatever the size of the map; then the figures are drawn, on Linux in forked
processes (:mod:`atlas.views.forked`) of which one imports matplotlib while this one reads.
The figure functions are re-exported here: ``from atlas.views.plotting import basin_map``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from atlas.layout import PARAMETERS
from atlas.views.coarsen import read_maps, workers
from atlas.views.curves import CURVE_FIGURES, basin_stability, fraction_curves
from atlas.views.maps import MAP_FIGURES, basin_map, boundary_distance_map, trap_time_map
from atlas.views.style import CURVE_SIZE, MAP_SIZE, PNG_OPTIONS, STYLE

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["plot_atlas", "plot_file", "basin_map", "trap_time_map", "boundary_distance_map",
           "fraction_curves", "basin_stability", "read_maps"]


def _figure_jobs(tree: xr.DataTree, path: Path) -> list[tuple]:
    """The figures of ``tree`` to write next to ``path``, read: (PNG path, size [in], drawer,
    scene) each, every scene read from the tree (the maps band by band)."""
    path = Path(path)
    maps = read_maps(tree)
    jobs = [(path.with_name(path.stem + suffix + ".png"), MAP_SIZE, MAP_FIGURES[name][1],
             MAP_FIGURES[name][0](tree, maps))
            for name, suffix in (("basin", ""), ("trap_time", "_t_trap"),
                                 ("boundary_distance", "_boundary_distance"))]
    fractions, stability = CURVE_FIGURES["fractions"], CURVE_FIGURES["basin_stability"]
    swept = tree.to_dataset(inherit=False).dims
    for dim in (name for name in PARAMETERS if name in swept):
        jobs.append((path.with_name(f"{path.stem}_fractions_{dim}.png"), CURVE_SIZE,
                     fractions[1], fractions[0](tree, dim)))
        if dim == "torque":
            jobs.append((path.with_name(f"{path.stem}_basin_stability.png"), CURVE_SIZE,
                         stability[1], stability[0](tree, dim)))
    return jobs


def _draw_figure(out: Path, size: tuple[float, float], draw, scene: dict) -> Path:
    """Draw ``scene`` (``draw(ax, **scene)``) into a figure of ``size`` [in] of its own (no
    pyplot), laid out tight, and write it to ``out`` (PNG)."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with matplotlib.rc_context(STYLE):
        # laid out at the resolution it is saved at, so that the text the layout measures
        # is measured once (matplotlib caches it per renderer and resolution)
        fig = Figure(figsize=size, dpi=STYLE["savefig.dpi"])
        FigureCanvasAgg(fig)
        draw(fig.add_subplot(), **scene)
        fig.tight_layout()
        # laid out once: without this, savefig would draw the figure once more first
        # (for tight_layout's placeholder engine) before drawing it into the PNG
        fig.set_layout_engine(None)
        fig.savefig(out, pil_kwargs=PNG_OPTIONS)
    return out


def plot_atlas(tree: xr.DataTree, path: Path) -> list[Path]:
    """Write the figures of the atlas stored at ``path`` next to it; returns the PNG paths.

    Everything drawn is read before the first PNG is written (a file that cannot be read
    leaves none): the maps of the drawn parameter point band by band, coarsened to the
    figure's pixels (:func:`read_maps`), so that the memory needed is bounded whatever the
    size of the map, and what else each figure shows."""
    return [_draw_figure(*job) for job in _figure_jobs(tree, path)]


def plot_file(path: str | Path) -> list[Path]:
    """``atlas plot``: :func:`plot_atlas` of the atlas file at ``path``, opened and closed
    here.

    On Linux the figures are drawn by forked processes (:class:`atlas.views.forked.ForkedJobs`):
    one is started first and imports matplotlib (:func:`_warm_up`) while this one opens and
    reads the file, then draws the figures with forks of itself, on every core at once (one
    process per core and one more, so that a figure that finishes first does not leave a core
    idle: three for the three maps on 2 cores). Elsewhere (no safe ``fork``) they are drawn
    here, after reading."""
    from atlas.views.forked import ForkedJobs, can_fork

    drawers = ForkedJobs.start(_warm_up, _draw_job, workers() + 1) if can_fork() else None
    try:
        from atlas.store.reader import (
            open_atlas,  # imported after the fork: xarray, h5py only here
        )

        tree = open_atlas(path)
        try:
            jobs = _figure_jobs(tree, path)
        finally:
            tree.close()
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
