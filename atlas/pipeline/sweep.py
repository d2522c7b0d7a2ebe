"""The sweep: a config's grid of initial conditions → tiles → a basin atlas on disk.

The grid (θ̇0 rows × θ0 columns, for every α, ω0, τ of a parameter atlas) is cut into tiles
of whole rows (about ``execution.tile_orbits`` orbits each). Tiles are labelled
independently (:func:`atlas.pipeline.schedule.compute_tile`, on any device and scheduler)
and each finished tile is written at once (:mod:`atlas.store.partial`, one atomically
written file per tile in ``<output>.partial/``) while the next tile is computed, so memory
is bounded by two tiles and a crash loses only tiles in flight; when all are done the
output's format (:func:`atlas.store.formats.format_for`: HDF5, or Zarr for ``NAME.zarr``)
assembles the file. Orbits never interact, so results do not depend on tile size, backend
or thread count.

A run continues the partial run at its output if that has the same identity
(:func:`atlas.pipeline.identity.run_identity`: grid, physics, integrator, kernel check
interval, atlas version, kernel class) and refuses one of another identity unless
``restart=True`` discards it.

Before a big run starts, one line says how many orbits, about how long on this machine and
how much disk (:mod:`atlas.pipeline.preflight`; a question on a terminal past a threshold);
while it runs, bars show the per-point phases and the tiles, and a line says when Numba
compiles (:mod:`atlas.pipeline.progress`). A traced separatrix farther from the DOP853 stable
manifold than its bound is a warning on stderr (whatever ``quiet`` says) and, on the command
line, exit status 4 after the file is written (:func:`accuracy_exit`).
"""

from __future__ import annotations

import functools
import logging
import os
import re
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import xarray as xr

from atlas import defaults, lazy_dask  # noqa: F401 (lazy_dask installs itself)
from atlas.errors import EXIT_INEXACT, AtlasError, InputFileError, StorageError
from atlas.layout import Layout
from atlas.models.registry import planner
from atlas.pipeline import preflight, progress
from atlas.pipeline.config import Config
from atlas.pipeline.identity import file_attrs, run_identity
from atlas.pipeline.lock import output_lock
from atlas.pipeline.output import check_output_path, check_output_target
from atlas.pipeline.schedule import Scheduler, resolve
from atlas.store.formats import format_for
from atlas.store.partial import (
    DamagedTile,
    IdentityMismatch,
    PartialStoreError,
    TileStore,
    discard,
    partial_path,
)
from atlas.store.reader import open_atlas
from atlas.store.schema import summary_tree
from atlas.store.separatrices import inexact_points

__all__ = ["run", "layout_of", "accuracy_exit", "kept_after_interrupt", "finish_tiles",
           "Phases"]

log = logging.getLogger(__name__)

def layout_of(cfg: Config, backend: str | None = None) -> Layout:
    """The grid axes, parameter axes and tiling of a config run on ``backend`` (a backend
    word, default ``execution.backend``): ``execution.tile_orbits`` orbits per tile, or by
    default the device's (:attr:`atlas.labels.backends.Backend.tile_orbits`: a GPU tile
    fills the GPU)."""
    device, _ = resolve(backend or cfg.execution.backend)
    tile = cfg.execution.tile_orbits or device.tile_orbits
    g, model, section = cfg.grid, cfg.description, cfg.section
    return Layout(
        x0=np.linspace(g.theta0.start, g.theta0.stop, g.theta0.num),
        v0=np.linspace(g.theta_dot0.start, g.theta_dot0.stop, g.theta_dot0.num),
        parameters={name: np.array(section.values(name), np.float64)
                    for name in model.parameters},
        swept=section.swept,
        rows_per_tile=max(1, min(g.theta_dot0.num, tile // g.theta0.num)),
        model=model,
    )


def _summary(tiles: TileStore, plan) -> xr.Dataset:
    """The summary variables from the tiles' tallies (O(tiles) numbers, no label re-read):
    the plan's (:class:`atlas.models.base.Plan`)."""
    layout = tiles.layout
    tallies = [[] for _ in plan.points]
    for index in range(layout.n_tiles):  # a damaged record raises DamagedTile
        tallies[index // layout.bands].append(tiles.read_tally(index))
    return plan.summary(tallies)


def _make_output_folder(out: Path) -> None:
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise AtlasError(f"{out}: cannot create the output folder ({exc.strerror})") from None


def _refuse_another(partial: Path, identity: dict, opener=TileStore.open) -> TileStore:
    """The partial run at ``partial`` if it has ``identity``, else one clear InputFileError
    naming ``--restart``."""
    try:
        return opener(partial, identity)
    except IdentityMismatch as exc:
        raise InputFileError(f"{partial}: a partial run of a different config or atlas "
                             f"build is in the way ({', '.join(exc.differs)} differ); run with "
                             "--restart to discard it, or write elsewhere with -o") from None
    except PartialStoreError as exc:
        raise InputFileError(f"{partial}: cannot continue this partial run ({exc}); run with "
                             "--restart to discard it") from None


def _check_partial(partial: Path, identity: dict) -> None:
    """Before anything is written (the lock included): refuse a partial run of another
    identity. Reading is safe without the lock, the manifest being written atomically."""
    if partial.exists():
        _refuse_another(partial, identity, lambda path, ident: TileStore.read(path).check(ident))


def _open_tiles(cfg: Config, layout: Layout, identity: dict, restart: bool) -> TileStore:
    """The partial run to write into: the one at the output if it has this identity (said in
    one line), a new one otherwise. One of another identity is refused, unless ``restart``."""
    partial = partial_path(cfg.output)
    TileStore.clear_leftovers(partial)
    if restart and partial.exists():
        log.warning("discarding the partial run %s (--restart)", partial)
        discard(partial)
    if not partial.exists():
        return TileStore.create(partial, layout, identity, file_attrs(cfg, identity),
                                format_for(cfg.output).tile_run)
    tiles = _refuse_another(partial, identity)
    log.warning("resuming %s: %d of %d tiles already done", partial, tiles.done().size,
                tiles.layout.n_tiles)
    return tiles


def _compute_into(tiles: TileStore, cfg: Config, points: list, device: str,
                  scheduler: Scheduler, quiet: bool) -> None:
    """Label and certify the tiles still to do on ``device`` ("cpu", "cuda") and store each as
    it finishes, as ``scheduler`` runs them (the local one computes the next tile meanwhile:
    :func:`atlas.pipeline.schedule.local_results`)."""
    layout, todo = tiles.layout, tiles.todo()
    written_by_workers = scheduler.worker_writes(tiles)
    results = scheduler.results(cfg, tiles, points, todo, device)
    total = preflight.orbits_of(layout, range(layout.n_tiles))
    with progress.bar(total, "tiles", "orbit", quiet,
                      initial=total - preflight.orbits_of(layout, todo)) as bar:
        for index, result in results:
            if written_by_workers:
                tiles.record(index, result)
            else:
                tiles.write(index, *result)
            bar.update(preflight.orbits_of(layout, [index]))
            log.debug("tile %d of %d written", index + 1, layout.n_tiles)


def _process_age() -> float | None:
    """Seconds since this process started (Linux's /proc; None elsewhere)."""
    try:
        start_ticks = int(open("/proc/self/stat").read().rsplit(")", 1)[1].split()[19])
        uptime = float(open("/proc/uptime").read().split()[0])
        return uptime - start_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


class Phases:
    """Wall time of the phases of a run, logged at INFO (``atlas run -v``)."""

    def __init__(self):
        self.last = time.perf_counter()

    def done(self, name: str) -> None:
        now = time.perf_counter()
        log.info("%-32s %6.2f s", name, now - self.last)
        self.last = now


def finish_tiles(tiles: TileStore, cfg: Config, backend: str, quiet: bool, start: float,
                 begun: list, phase: Phases) -> xr.DataTree:
    """Prepare every parameter point (the model's :func:`plan`, from what ``begun`` holds:
    for the pendulum the separatrices, which measure d_cert, which certifying a tile
    needs), compute and certify what is missing, then assemble the file. A tile file found
    damaged is set aside (renamed, not deleted) and computed again. Logs each phase's time
    (``-v``). Returns what was written beyond the basin map
    (:func:`atlas.store.schema.summary_tree`)."""
    track = functools.partial(progress.tracked, quiet=quiet)
    plan = planner(tiles.layout.model).plan(cfg, tiles.layout, begun, track)
    phase.done("per-point plans")
    for line in plan.warnings:  # on stderr even with --quiet
        log.warning(line)
    groups = plan.groups
    for _ in range(3):
        device, scheduler = resolve(backend)
        _compute_into(tiles, cfg, plan.points, device.name, scheduler, quiet)
        phase.done("map (label and certify tiles)")
        try:
            summary = _summary(tiles, plan)
            phase.done("summary")
            attrs = {"run_time_s": time.perf_counter() - start, "backend": backend}
            manifest_attrs = tiles.manifest["attrs"]  # read before finalize removes the tiles
            tiles.finalize(cfg.output, groups, summary, attrs)
            phase.done(f"writing ({tiles.layout.n_tiles} tiles assembled)")
            return summary_tree(tiles.layout, summary, groups, {**manifest_attrs, **attrs})
        except DamagedTile as exc:
            log.warning("%s: %s is damaged; computing it again", tiles.path, exc)
            tiles.set_aside(exc.index)
    raise StorageError(f"{tiles.path}: tile files keep coming back damaged; check the disk")


def run(cfg: Config, *, restart: bool = False, quiet: bool = False,
        backend: str | None = None, force: bool = False,
        config_path: str | Path | None = None, open_result: bool = True,
        confirm: Callable[[preflight.Estimate], bool] | None = None) -> xr.DataTree:
    """Compute the atlas of ``cfg`` into ``cfg.output`` and return it as a DataTree.

    An interrupted run of the same identity at the output (``<output>.partial/``) is
    continued: only its missing tiles are computed, with its own tiling. A partial run of
    another identity raises :class:`InputFileError`, unless ``restart=True`` discards it
    first. ``backend``
    overrides ``execution.backend`` ('cpu', 'cuda' or 'dask'). A write error (disk full, I/O
    error) raises :class:`StorageError`; the tiles finished before it are kept. An output
    that atlas did not write is refused (:class:`~atlas.errors.OutputInTheWay`) unless
    ``force``, and one that is the config file ``config_path`` itself always.
    ``open_result=False`` returns, instead of the file opened (and checked) again, what was
    written beyond the basin map, from memory (:func:`atlas.store.schema.summary_tree`: what
    ``atlas run`` prints).

    Before anything is made, a big run's estimate (:mod:`atlas.pipeline.preflight`) is said
    on stderr (not where ``quiet``); for a run big enough to ask, ``confirm(estimate)`` is
    called instead (it says the line; :func:`atlas.pipeline.preflight.ask` on the command
    line) and an answer other than True stops the run with an :class:`AtlasError`, nothing
    written. ``quiet`` silences the progress bars and the compiling line, never a warning:
    a traced separatrix farther from the DOP853 stable manifold than its bound is logged
    (:func:`atlas.store.separatrices.inexact_points`), and the file is written all the same.
    """
    check_output_target(cfg.output, config_path, force=force)
    _say_what_is_replaced(cfg)
    backend = backend or cfg.execution.backend
    device, _ = resolve(backend)
    try:
        device.check_method(cfg.integrator.method)
    except ValueError as exc:  # a --backend override of a valid config: name the config
        where = f"{config_path}: " if config_path is not None else ""
        raise AtlasError(f"{where}integrator.{exc}") from None
    layout = layout_of(cfg, backend)
    device.require()
    check_output_path(cfg.output, layout)
    partial = partial_path(cfg.output)
    identity = run_identity(cfg, backend)
    if not restart:
        _check_partial(partial, identity)
    begun = planner(layout.model).begin(cfg, layout)
    with progress.compile_notice(quiet):
        _preflight(cfg, layout, begun, device.name, backend, quiet,
                   confirm, None if restart else partial)
        _make_output_folder(cfg.output)
        return _locked_run(cfg, restart, quiet, backend, open_result, layout, identity,
                           begun)


def _say_what_is_replaced(cfg: Config) -> None:
    """Warn (one line, even with ``quiet``) where the output holds a finished atlas of another
    config, which the run replaces: written over on purpose when a changed config is run
    again, by mistake when two configs name one output."""
    from atlas.pipeline.config import config_hash
    from atlas.store.reader import describe, is_atlas_file

    if not (cfg.output.exists() and is_atlas_file(cfg.output)):
        return
    try:
        attrs = describe(cfg.output)["attrs"]
    except InputFileError:
        return
    if attrs.get("config_hash") not in (None, config_hash(cfg)):
        title = str(attrs.get("title", "")).removeprefix("atlas basin map: ")
        log.warning("%s holds an atlas of another config%s; this run replaces it", cfg.output,
                    f" ({title})" if title else "")


def _preflight(cfg: Config, layout: Layout, begun: list, device: str, backend: str,
               quiet: bool, confirm, partial: Path | None) -> None:
    """Say a big run's estimate, or ask ``confirm`` for one big enough to ask (``partial``:
    the partial run to be continued, whose finished tiles are not counted). Nothing is
    measured where nothing would be said or asked: ``quiet`` with no ``confirm``, or with
    one that starts without a word (:func:`atlas.pipeline.preflight.ask`'s ``silent``)."""
    if quiet and (confirm is None or getattr(confirm, "silent", False)):
        return
    todo = range(layout.n_tiles)
    if partial is not None and partial.exists():
        try:
            done = TileStore.read(partial)
            layout, todo = done.layout, done.todo()
        except PartialStoreError:
            pass  # _open_tiles says what is wrong with it, under the lock
    est = preflight.estimate(cfg, layout, begun, preflight.orbits_of(layout, todo), device,
                             backend)
    if confirm is not None and est.asks:
        if not confirm(est):
            raise AtlasError(f"{cfg.output}: not started (the answer was not yes); nothing "
                             "was written")
    elif est.big and not quiet:
        progress.say(est.line())


def _locked_run(cfg: Config, restart: bool, quiet: bool, backend: str, open_result: bool,
                layout: Layout, identity: dict, begun: list) -> xr.DataTree:
    """:func:`run` from the output's lock on: the partial run, the tiles, the file."""
    partial = partial_path(cfg.output)
    start = time.perf_counter()
    age = _process_age()
    if age is not None:
        log.info("%-32s %6.2f s", "start-up (process, imports)", age)
    phase = Phases()
    with output_lock(cfg.output):
        try:
            tiles = _open_tiles(cfg, layout, identity, restart)
            phase.done("partial run (open or resume)")
            written = finish_tiles(tiles, cfg, backend, quiet, start, begun, phase)
        except OverflowError as exc:
            raise AtlasError(f"{cfg.output}: {exc}") from None
        except OSError as exc:
            raise StorageError(f"{partial}: writing failed ({_reason(exc)}); the "
                               "tiles finished before it are kept: free space or fix the "
                               "disk, then run the same command again") from None
    if open_result:
        written = open_atlas(cfg.output)
        phase.done("opening the result")
    log.info("wrote %s in %.2f s", cfg.output, time.perf_counter() - start)
    return written


def accuracy_exit(tree: xr.DataTree, output: Path, accept_inexact: bool = False) -> int:
    """The exit status of ``atlas run`` whose result is ``tree``, written at ``output``: 0, or
    :data:`atlas.errors.EXIT_INEXACT` (4) where a check exceeds its bound
    (:func:`atlas.store.separatrices.inexact_points`, already warned of during the run),
    said in one line on stderr, unless ``accept_inexact`` (``--accept-inexact``)."""
    inexact = inexact_points(tree)
    if not inexact or accept_inexact:
        return 0
    log.warning("%s is written, but its separatrix check exceeds its bound (%d of its "
                "parameter points); exit status %d: lower separatrices.tol or integrator.dt, "
                "or run with --accept-inexact to accept it", output, len(inexact),
                EXIT_INEXACT)
    return EXIT_INEXACT


def kept_after_interrupt(output: Path) -> str:
    """What a run of ``output`` stopped by Ctrl-C or SIGTERM keeps, as the CLI says it after
    "atlas: interrupted; ": its finished tiles, counted, and where, or that no tile was
    finished (stopped before the map, or in its first tile): then running again starts it
    over. Reads the partial run's folder only; never raises."""
    partial = partial_path(output)
    try:
        tiles = TileStore.read(partial)
        done, total = tiles.done().size, tiles.layout.n_tiles
    except (PartialStoreError, OSError):
        done = 0
    if not done:
        return "no tile was finished; run the same command again to start over"
    return (f"{done} of {total} tiles are finished and kept in {partial}; run the same "
            "command again to continue")


def _reason(exc: OSError) -> str:
    """The system's words for a failed write, on one line (HDF5's own messages are long)."""
    if exc.errno:
        return os.strerror(exc.errno)
    text = str(exc)
    found = re.search(r"errno = (\d+)", text)  # HDF5 quotes the system's errno
    if found:
        return os.strerror(int(found.group(1)))
    return text.splitlines()[0] if text else exc.__class__.__name__
