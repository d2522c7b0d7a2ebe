"""An atlas in memory: :func:`atlas.basins` (``atlas.run(cfg, output=None)``) computes a
config's atlas and returns it as an :class:`xarray.DataTree` without writing anything.

The computation is the sweep's own (:mod:`atlas.pipeline.sweep`: the separatrices, the exact
boundaries and areas, the tiles labelled and certified on the config's backend and scheduler,
the summary from the tiles' tallies); only where the tiles go differs. A file run hands them
to a partial run on disk (:class:`atlas.store.partial.TileStore`) and its format assembles the
file; here :class:`MemoryTiles` keeps them and assembles the same tree in memory: the same
variables with the stored dtypes, fill values and CF attributes (the model's
:attr:`~atlas.models.base.Model.map_variables`), the same groups and root attributes, so the
arrays equal those of ``atlas.open`` of the file a run of the config writes (tested). What a
file adds is the disk: no lock, no partial run to resume, nothing to clean up.

The whole map is held in memory: 11 bytes an orbit (int16 + int8 + 2 × float32), about
2.9 MB for the default 512² grid; a grid that does not fit belongs in a file run.
"""

from __future__ import annotations

import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.errors import AtlasError
from atlas.layout import Layout
from atlas.models.registry import planner
from atlas.pipeline import progress
from atlas.pipeline.config import Config
from atlas.pipeline.identity import file_attrs, run_identity
from atlas.pipeline.schedule import resolve
from atlas.pipeline.sweep import Phases, finish_tiles, layout_of
from atlas.pipeline.sweep import run as run_to_file
from atlas.store.schema import SCHEMA, map_variables, summary_tree

__all__ = ["basins", "run", "MemoryTiles", "IN_MEMORY"]

#: What :class:`MemoryTiles` calls its place in log lines (where a file run names its
#: partial folder).
IN_MEMORY = Path("<in memory>")


class MemoryTiles:
    """The tiles of a run kept in memory: what the sweep asks of a partial run
    (:class:`atlas.store.partial.TileStore`: ``layout``, ``manifest``, ``todo``, ``write``,
    ``read_tally``, ``finalize``), with no file behind it. :meth:`finalize` leaves the atlas
    in :attr:`tree`."""

    #: A format that takes no parallel writes: a Dask worker sends its tiles back here.
    tile_run = SimpleNamespace(name="memory", parallel_tile_writes=False)
    path = IN_MEMORY

    def __init__(self, layout: Layout, attrs: dict):
        self.layout = layout
        self.manifest = {"attrs": attrs}
        shape = (*layout.parameter_shape, layout.v0.size, layout.x0.size)
        self.maps = {name: np.full(shape, var.padding, var.dtype)
                     for name, var in map_variables(layout).items()}
        self.tallies: dict[int, dict] = {}
        self.tree: xr.DataTree | None = None

    def todo(self) -> np.ndarray:
        return np.setdiff1d(np.arange(self.layout.n_tiles), list(self.tallies))

    def write(self, index: int, values: dict, tally: dict) -> None:
        """Keep tile ``index``: each map variable's rows (shaped (rows, columns)), and its
        tally."""
        params, rows = self.layout.tile(index)
        for name, array in self.maps.items():
            array[(*params, rows)] = values[name]
        self.tallies[index] = tally

    def read_tally(self, index: int) -> dict:
        return self.tallies[index]

    def finalize(self, output, groups: dict[str, xr.Dataset], root_vars: xr.Dataset,
                 attrs: dict) -> None:
        """Assemble the atlas as a file's format does (the summary, the groups, the
        attributes, the basin map with its stored dtypes and CF attributes) into
        :attr:`tree`."""
        layout = self.layout
        tree = summary_tree(layout, root_vars, groups, {
            **self.manifest["attrs"], "atlas_schema": SCHEMA, "complete": np.int8(1), **attrs})
        root = tree.to_dataset(inherit=False)
        variables = map_variables(layout)
        for name, var in variables.items():
            fill = {} if var.fill is None else {"_FillValue": var.dtype(var.fill)}
            root[name] = (layout.dims, self.maps[name], {**var.attrs, **fill})
        tree.dataset = root[[*variables, *root_vars.data_vars]]
        self.tree = tree

    def set_aside(self, index: int) -> None:  # pragma: no cover (memory is never damaged)
        raise AssertionError("a tile held in memory cannot be damaged")


def basins(cfg: Config, *, backend: str | None = None, quiet: bool = False) -> xr.DataTree:
    """The atlas of ``cfg`` as a DataTree, computed in memory and written nowhere
    (``cfg.output`` is ignored): the same arrays, dtypes, groups and attributes as
    ``atlas.open`` of the file that :func:`atlas.run` writes for ``cfg``, from the same
    computation (:mod:`atlas.pipeline.sweep`). ``backend`` overrides
    ``execution.backend`` ('cpu', 'cuda' or 'dask'); ``quiet`` hides the progress bars and
    the compiling line (:mod:`atlas.pipeline.progress`), never a warning.

    For grids that fit in memory (11 bytes an orbit). Raises what a run raises for a config
    it cannot compute (:class:`~atlas.errors.AtlasError`, one line)."""
    backend = backend or cfg.execution.backend
    device, _ = resolve(backend)
    try:
        device.check_method(cfg.integrator.method)
    except ValueError as exc:  # a backend override of a valid config
        raise AtlasError(f"integrator.{exc}") from None
    layout = layout_of(cfg, backend)
    device.require()
    identity = run_identity(cfg, backend)
    tiles = MemoryTiles(layout, file_attrs(cfg, identity))
    begun = planner(layout.model).begin(cfg, layout)
    with progress.compile_notice(quiet):
        try:
            finish_tiles(tiles, cfg, backend, quiet, time.perf_counter(), begun, Phases())
        except OverflowError as exc:  # an orbit beyond the wells an atlas can index
            raise AtlasError(f"{cfg.name}: {exc}") from None
    return tiles.tree


class _ConfigOutput:
    """``atlas.run``'s default ``output``: the config's own output path."""

    def __repr__(self) -> str:
        return "cfg.output"


_CONFIG_OUTPUT = _ConfigOutput()


def run(cfg: Config, output: str | Path | None = _CONFIG_OUTPUT, **options) -> xr.DataTree:
    """``atlas.run``: compute the atlas of ``cfg`` and return it as a DataTree.

    By default it is written to ``cfg.output`` (:func:`atlas.pipeline.sweep.run`, whose
    keyword ``options`` it takes: ``restart``, ``quiet``, ``backend``, ``force``, …); a path
    ``output`` writes it there instead; ``output=None`` writes nothing and returns the atlas
    computed in memory (:func:`basins`, which takes ``backend`` and ``quiet``)."""
    if output is None:
        return basins(cfg, **options)
    if output is not _CONFIG_OUTPUT:
        cfg = cfg.model_copy(update={"output": Path(output)})
    return run_to_file(cfg, **options)
