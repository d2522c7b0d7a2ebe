"""The sweep: a config's grid of initial conditions → tiles → a basin atlas on disk.

The grid (θ̇0 rows × θ0 columns, for every α, ω0 of a parameter atlas) is cut into tiles of
whole rows (about ``execution.tile_orbits`` orbits each). Tiles are labelled independently
(:func:`compute_tile`, which any backend can run) and each finished tile is written at once
(:mod:`atlas.tiles`, one atomically written file per tile in ``<output>.partial/``) while
the next tile is computed, so memory is bounded by two tiles and a crash loses only tiles in
flight; when all are done
:func:`atlas.store.finalize` assembles the HDF5 file. Orbits never interact, so results do not
depend on tile size, backend or thread count.

A run continues the partial run at its output if that has the same identity
(:func:`run_identity`: grid, physics, integrator, kernel check interval, atlas version, kernel
class) and refuses one of another identity unless ``restart=True`` discards it.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import shutil
import sys
import threading
import time
from collections.abc import Iterator
from concurrent.futures import Future
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import xarray as xr

from . import defaults, lazy_dask, running, store, zarrstore  # noqa: F401 (lazy_dask installs itself)
from .certificate import Certifier, add_tallies, certifier_for
from .config import Config, config_hash, integrator_json
from .errors import AtlasError, InputFileError, StorageError
from .labels import CHECK_EVERY, RunningBarrier, check_method, label, trap_margin
from .layout import PARAMETERS, Layout, node_name, point_label
from .lock import output_lock
from .model import Pendulum, critical_points
from .tiles import IdentityMismatch, PartialStoreError, TileStore, discard, partial_path
from .validate import FORMAT_VERSION

__all__ = ["run", "compute_tile", "layout_of", "critical_points_dataset", "run_identity",
           "identity_hash"]

log = logging.getLogger(__name__)

#: Upper bound on the bytes one orbit takes on disk (int16 + int8 + float32, uncompressed).
BYTES_PER_ORBIT = 7


def layout_of(cfg: Config, backend: str | None = None) -> Layout:
    """The grid axes, parameter axes and tiling of a config run on ``backend`` (default
    ``execution.backend``): ``execution.tile_orbits`` orbits per tile, or by default
    ``defaults.TILE_ORBITS`` (``TILE_ORBITS_CUDA`` on the GPU, so that a tile fills it)."""
    backend = backend or cfg.execution.backend
    tile = cfg.execution.tile_orbits or (defaults.TILE_ORBITS_CUDA if backend == "cuda"
                                         else defaults.TILE_ORBITS)
    g = cfg.grid
    theta0 = np.linspace(g.theta0.start, g.theta0.stop, g.theta0.num)
    theta_dot0 = np.linspace(g.theta_dot0.start, g.theta_dot0.stop, g.theta_dot0.num)
    return Layout(
        theta0=theta0, theta_dot0=theta_dot0,
        parameters={name: np.array(cfg.pendulum.values(name), np.float64)
                    for name in PARAMETERS},
        swept=cfg.pendulum.swept,
        rows_per_tile=max(1, min(g.theta_dot0.num, tile // g.theta0.num)),
    )


def run_identity(cfg: Config, backend: str) -> dict:
    """What determines a run's tiles, so a partial run may be continued only by an equal one:
    the grid, the physics (every ``pendulum`` key), the integrator, the kernels' trap-check
    interval, the atlas version, the kernel class that computes the labels ('cuda' for the
    GPU kernels; 'cpu' for the CPU kernels, which the Dask backend runs too), and the
    separatrix settings when they are enabled (they measure d_cert, which decides each tile's
    certified statuses). Not the tiling, the output path or the name."""
    from . import __version__

    return {"grid": cfg.grid.model_dump(mode="json"),
            "pendulum": cfg.pendulum.model_dump(mode="json"),
            "integrator": integrator_json(cfg.integrator),
            "separatrices": (cfg.separatrices.model_dump(mode="json")
                             if cfg.separatrices.enabled else {"enabled": False}),
            "check_every": int(CHECK_EVERY), "atlas_version": __version__,
            "kernels": "cuda" if backend == "cuda" else "cpu"}


def identity_hash(identity: dict) -> str:
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:16]


def _pendulums(layout: Layout) -> list[Pendulum]:
    """The pendulum of every parameter point, in the layout's order."""
    return [Pendulum(**layout.point(p)) for p in range(layout.n_params)]


def compute_tile(certifier: Certifier, barrier: RunningBarrier | None, rows: slice, dt, t_max,
                 method=defaults.METHOD, backend="cpu", numba_threads=None):
    """Label and certify the orbits of one tile: the grid rows ``rows`` of ``certifier``'s
    parameter point (θ0 [rad] along columns × θ̇0 [rad s⁻¹] along rows); ``barrier`` the
    point's running certificate (None where it has no running limit cycle); ``dt`` [s],
    ``t_max`` [s] and ``method`` the integrator's.

    Returns ({variable: array shaped (rows, columns)} for every per-orbit variable of the
    file, the tile's tally). A plain function of picklable arguments, so it can run as a Dask
    task on another machine.
    """
    if numba_threads is not None:
        import numba

        numba.set_num_threads(min(numba_threads, numba.config.NUMBA_NUM_THREADS))
    p = certifier.pendulum
    res = label(certifier.theta0[None, :], certifier.theta_dot0[rows][:, None], alpha=p.alpha,
                omega0=p.omega0, torque=p.torque, dt=dt, t_max=t_max, backend=backend,
                method=method, running=barrier)
    status, distance, tally = certifier.tile(rows, res.attractor, res.status)
    return {"attractor": res.attractor, "status": status, "t_trap": res.t_trap,
            "boundary_distance": distance}, tally


def _tile_args(cfg: Config, layout: Layout, certifiers: list, index: int) -> tuple:
    certifier, barrier = certifiers[index // layout.bands]
    return (certifier, barrier, layout.tile(index)[1], cfg.integrator.dt, cfg.integrator.t_max,
            cfg.integrator.method)


#: Held by the thread computing a tile ahead: a sweep's tile waits for one that an interrupted
#: sweep left computing, so two never run the kernels at once (Numba's workqueue threading
#: layer aborts the process on concurrent parallel launches).
_AHEAD = threading.Lock()


def _in_background(fn, *args, **kwargs) -> Future:
    """``fn(*args, **kwargs)`` started in a daemon thread; its result, or whatever it raised
    (Ctrl-C included), comes back through the Future. A daemon rather than a
    ThreadPoolExecutor worker: those are joined at interpreter exit, so a run stopped by
    Ctrl-C or SIGTERM would wait for its tile in flight before the process could end."""
    future = Future()

    def work():
        with _AHEAD:
            try:
                future.set_result(fn(*args, **kwargs))
            except BaseException as exc:  # re-raised in the caller by future.result()
                future.set_exception(exc)

    threading.Thread(target=work, name="atlas-tile", daemon=True).start()
    return future


def _local_results(cfg, layout, certifiers, todo, backend) -> Iterator[tuple[int, tuple]]:
    """(index, (arrays, tally)) of the tiles ``todo`` in order, each computed one tile ahead
    in a background thread, so tile i+1 is computed while the caller writes tile i (the
    Numba kernels run without the GIL, and so do zlib and fsync in the write). At most one
    tile is ahead: memory holds two tiles' arrays. A tile whose computation failed raises
    its own exception here, after every tile before it has been yielded; a tile still
    computing when the caller stops (a failed write, Ctrl-C, SIGTERM) is abandoned, its
    result dropped."""
    import numba

    threads = numba.get_num_threads()  # the caller's setting: Numba's is per thread

    def start(index):
        return _in_background(compute_tile, *_tile_args(cfg, layout, certifiers, index),
                              backend=backend, numba_threads=threads)

    ahead = start(todo[0]) if len(todo) else None
    for position, index in enumerate(todo):
        result = ahead.result()
        if position + 1 < len(todo):
            ahead = start(todo[position + 1])
        yield index, result


def compute_tile_into_zarr(path, layout, index, *args, numba_threads=None) -> dict:
    """Label and certify tile ``index`` and write it by region into the Zarr store at
    ``path`` (on the Dask worker itself); return its tally for the client's record."""
    from . import zarrstore

    values, tally = compute_tile(*args, numba_threads=numba_threads)
    zarrstore.write_tile(path, layout, index, values)
    return tally


def _dask_results(cfg, tiles: TileStore, certifiers, todo) -> Iterator[tuple[int, tuple]]:
    """(index, (arrays, tally)), or for a Zarr output (index, tally) of a tile the worker
    has written itself."""
    from .distributed import dask_results

    layout = tiles.layout
    if tiles.format == "zarr":
        from .zarrstore import DATA

        def args_of(i):
            return (tiles.path / DATA, layout, i, *_tile_args(cfg, layout, certifiers, i))

        task = compute_tile_into_zarr
    else:
        def args_of(i):
            return _tile_args(cfg, layout, certifiers, i)

        task = compute_tile
    yield from dask_results(cfg, todo, args_of, task, tiles.manifest["attrs"]["run_identity"])


def critical_points_dataset(p: Pendulum, lo: float, hi: float) -> xr.Dataset:
    """One parameter point's node of ``/critical_points``: θ, n, kind and both eigenvalues
    of every critical point with θ in [``lo``, ``hi``] [rad]."""
    found = critical_points(p, lo, hi)
    eig = np.array([c.eigenvalues for c in found], np.complex128).reshape(len(found), 2)
    dims = ("point", "eigen")
    return xr.Dataset(
        {
            "eigenvalue_real": (dims, eig.real, {"units": "s-1",
                                                 "long_name": "real part of the eigenvalue"}),
            "eigenvalue_imag": (dims, eig.imag, {"units": "s-1",
                                                 "long_name": "imaginary part of the eigenvalue"}),
            "kind": ("point", np.array([c.kind for c in found], dtype=str),
                     {"long_name": "attractor focus/node/critical node, or saddle"}),
        },
        coords={
            "theta": ("point", np.array([c.theta for c in found], np.float64),
                      {"units": "rad", "long_name": "angle of the critical point (theta, 0)"}),
            "n": ("point", np.array([c.n for c in found], np.int32),
                  {"units": "1", "long_name": "index n: the critical point near n*pi (even: "
                                              "rest state, odd: saddle)"}),
        },
        attrs={"description": "critical points of the pendulum in the theta0 window and "
                              "their linearisation eigenvalues (essay section 3, eqs. 22-24)"},
    )


def _window(cfg: Config) -> tuple[tuple[float, float], tuple[float, float]]:
    g = cfg.grid
    return (g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop)


def _tilted_boundaries(cfg: Config, pendulums: list[Pendulum], cycles: list) -> list:
    """The exact tilted boundaries of every parameter point with a torque and rest states
    (None elsewhere), built once for both the separatrices and the certifier."""
    from .tilted import TiltedBoundaries

    return [TiltedBoundaries(p, *_window(cfg), cycle=cycle)
            if p.torque != 0.0 and p.has_rest_states else None
            for p, cycle in zip(pendulums, cycles)]


def _trace_separatrices(cfg: Config, pendulums: list[Pendulum], tilted: list,
                        barriers: list) -> list[xr.Dataset | None]:
    """The traced separatrices of every parameter point (None each when disabled)."""
    if not cfg.separatrices.enabled:
        return [None] * len(pendulums)
    from . import separatrices

    window = _window(cfg)
    settings = {"tol": cfg.separatrices.tol, "max_spacing": cfg.separatrices.max_spacing,
                "dt": cfg.integrator.dt, "method": cfg.integrator.method}
    return [separatrices.trace(p, *window, **settings) if p.torque == 0.0 else
            separatrices.trace_tilted(p, *window, t_max=cfg.integrator.t_max, exact=exact,
                                      barrier=barrier, **settings)
            if exact is not None else None  # |torque| > omega0^2: no saddle, no boundary
            for p, exact, barrier in zip(pendulums, tilted, barriers)]


def _per_point(layout: Layout, group: str, datasets: list[xr.Dataset | None]
               ) -> dict[str, xr.Dataset]:
    """The nodes of a per-point group: one per parameter point, each with the point's
    parameters as attributes (the group itself for an atlas of one point; see
    :mod:`atlas.layout`)."""
    out = {}
    for p, ds in enumerate(datasets):
        if ds is None:
            continue
        path = "/".join(filter(None, (group, node_name(layout, p))))
        out[path] = ds.assign_attrs(layout.point(p))
    return out


def _certifiers(layout: Layout, pendulums: list[Pendulum], traced: list, tilted: list,
                barriers: list) -> list[tuple]:
    """(certifier, running barrier) of every parameter point: the certifier with the boundary
    shift its separatrices measured (NaN without them: then no label is certified for the
    exact equation; :func:`atlas.certificate.certifier_for`), on the tilted boundaries of
    :func:`_tilted_boundaries` where there is a torque, and the barrier of
    :func:`_running_certificates`."""
    out = []
    for p, sep, exact, barrier in zip(pendulums, traced, tilted, barriers):
        shift, tol = ((float(sep.attrs["discrepancy"]), float(sep.attrs["tol"]))
                      if sep is not None else (np.nan, np.nan))
        out.append((certifier_for(p, layout.theta0, layout.theta_dot0, shift, tol, exact),
                    barrier))
    return out


def _running_certificates(pendulums: list[Pendulum], dt: float) -> tuple[list, list]:
    """The running limit cycle of every parameter point and the barrier around it, with the
    margins RK4 at step ``dt`` needs (None each where there is no cycle). Built before
    anything is written: a dt too coarse for the running speeds is bad input (AtlasError,
    one line naming integrator.dt)."""
    cycles, barriers = [], []
    for p in pendulums:
        cycle = running.limit_cycle(p.alpha, p.omega0, p.torque) if p.torque else None
        try:
            barrier = (None if cycle is None else
                       running.running_barrier(p.alpha, p.omega0, p.torque, cycle, dt=dt))
        except ValueError as exc:
            raise AtlasError(f"integrator.dt: {exc} (torque = {p.torque:g})") from None
        cycles.append(cycle)
        barriers.append(barrier)
    return cycles, barriers


def limit_cycle_dataset(cycle) -> xr.Dataset:
    """One parameter point's node of ``/limit_cycle``: the running periodic orbit sampled
    uniformly in θ over one turn, with its period and mean angular velocity."""
    return xr.Dataset(
        {"theta_dot": ("sample", cycle.theta_dot, {"units": "rad s-1",
                                                   "long_name": "angular velocity"}),
         "time": ("sample", cycle.time, {"units": "s", "long_name": "time from the first "
                                                                    "sample"})},
        coords={"theta": ("sample", cycle.theta, {"units": "rad", "long_name": "angle"})},
        attrs={"description": "the running limit cycle (steady rotation) of the pendulum with "
                              "torque: fixed point of the Poincare map over one turn (DOP853)",
               "period": cycle.period, "period_units": "s",
               "mean_theta_dot": cycle.mean_theta_dot, "direction": np.int8(cycle.direction),
               "relative_error": cycle.error})


def _summary(cfg: Config, tiles: TileStore, certifiers: list[Certifier]) -> xr.Dataset:
    """The summary variables from the tiles' tallies (O(tiles) numbers, no label re-read)."""
    layout = tiles.layout
    tallies = [[] for _ in certifiers]
    for index in range(layout.n_tiles):
        try:
            tallies[index // layout.bands].append(tiles.read_tally(index))
        except Exception as exc:  # a damaged record: OSError, ValueError, BadZipFile
            raise store.DamagedTile(index, exc.__class__.__name__) from None
    points = []
    for p, ((cert, _), point) in enumerate(zip(certifiers, tallies)):
        summary = cert.summary(add_tallies(point))
        pendulum = cert.pendulum
        summary["trap_margin"] = trap_margin(cfg.integrator.dt, pendulum.alpha, pendulum.omega0)
        if summary["side_mismatches"]:
            log.warning("%s: %d labels farther than d_cert from every boundary disagree with "
                        "the exact side; they are flagged near_boundary",
                        point_label(layout.point(p)), summary["side_mismatches"])
        points.append(summary)
    return store.summary_dataset(layout, points)


def _versions() -> dict:
    import h5netcdf
    import h5py
    import numba

    from . import __version__

    return {"atlas_version": __version__, "numpy_version": np.__version__,
            "numba_version": numba.__version__, "xarray_version": xr.__version__,
            "h5py_version": h5py.__version__, "h5netcdf_version": h5netcdf.__version__,
            "python_version": sys.version.split()[0]}


def _attrs(cfg: Config, identity: dict) -> dict:
    attrs = {
        "title": f"atlas basin map: {cfg.name}",
        "Conventions": "CF-1.10",
        "format_version": np.int64(FORMAT_VERSION),
        "method": cfg.integrator.method,
        "dt": cfg.integrator.dt,
        "t_max": cfg.integrator.t_max,
        "check_every": np.int64(CHECK_EVERY),
        "config": cfg.to_json(),
        "config_hash": config_hash(cfg),
        "run_identity": identity_hash(identity),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        **_versions(),
    }
    return attrs


def _check_output_path(cfg: Config, layout: Layout) -> None:
    """Refuse an output that cannot be written or would not fit, before anything is made."""
    out = cfg.output
    if out.is_dir() and not (zarrstore.is_zarr(out) and (out / "zarr.json").exists()):
        raise AtlasError(f"{out}: the output path is a directory")
    existing = next(p for p in (out.parent, *out.parent.parents) if p.exists())
    if not existing.is_dir():
        raise AtlasError(f"{out}: the output folder {existing} is not a directory")
    if not os.access(existing, os.W_OK):
        raise AtlasError(f"{out}: the output folder {existing} is not writable")
    need = layout.n_params * layout.theta0.size * layout.theta_dot0.size * BYTES_PER_ORBIT
    free = shutil.disk_usage(existing).free
    if need > free:
        raise AtlasError(f"{out}: the output may need up to {_size(need)} but only "
                         f"{_size(free)} is free on that disk")


def _size(n_bytes: int) -> str:
    for unit in ("B", "KB", "MB", "GB"):
        if n_bytes < 1000:
            return f"{n_bytes:.3g} {unit}"
        n_bytes /= 1000
    return f"{n_bytes:.3g} TB"


def _make_output_folder(out: Path) -> None:
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise AtlasError(f"{out}: cannot create the output folder ({exc.strerror})") from None


def _progress(total: int, initial: int, quiet: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="orbit", unit_scale=True, smoothing=0.1,
                disable=quiet or not sys.stderr.isatty(), desc="atlas", leave=False)


def _refuse_another(partial: Path, identity: dict, opener=TileStore.open) -> TileStore:
    """The partial run at ``partial`` if it has ``identity``, else one clear InputFileError
    naming ``--restart``."""
    try:
        return opener(partial, identity)
    except IdentityMismatch as exc:
        raise InputFileError(f"{partial}: a partial run of a different config is in the way "
                             f"({', '.join(exc.differs)} differ); run with --restart to discard "
                             "it, or write elsewhere with -o") from None
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
        return TileStore.create(partial, layout, identity, _attrs(cfg, identity),
                                "zarr" if zarrstore.is_zarr(cfg.output) else "hdf5")
    tiles = _refuse_another(partial, identity)
    log.warning("resuming %s: %d of %d tiles already done", partial, tiles.done().size,
                tiles.layout.n_tiles)
    return tiles


def _orbits(layout: Layout, tiles) -> int:
    return sum((layout.tile(i)[1].stop - layout.tile(i)[1].start) for i in tiles) \
        * layout.theta0.size


def _compute_into(tiles: TileStore, cfg: Config, certifiers: list[Certifier], backend: str,
                  quiet: bool) -> None:
    """Label and certify the tiles still to do and store each as it finishes (the local
    backends compute the next tile meanwhile, :func:`_local_results`)."""
    layout, todo = tiles.layout, tiles.todo()
    written_by_workers = backend == "dask" and tiles.format == "zarr"
    results = (_dask_results(cfg, tiles, certifiers, todo) if backend == "dask"
               else _local_results(cfg, layout, certifiers, todo, backend))
    total = _orbits(layout, range(layout.n_tiles))
    with _progress(total, total - _orbits(layout, todo), quiet) as bar:
        for index, result in results:
            if written_by_workers:
                tiles.record(index, result)
            else:
                tiles.write(index, *result, store.FILLS)
            bar.update(_orbits(layout, [index]))
            log.debug("tile %d of %d written", index + 1, layout.n_tiles)


def _groups(layout: Layout, pendulums: list[Pendulum], traced: list,
            cycles: list) -> dict[str, xr.Dataset]:
    """The per-point groups (path → dataset): ``/critical_points``, ``/separatrices`` and
    ``/limit_cycle`` (points with a running cycle only)."""
    lo, hi = float(layout.theta0[0]), float(layout.theta0[-1])
    return {**_per_point(layout, "critical_points",
                         [critical_points_dataset(p, lo, hi) for p in pendulums]),
            **_per_point(layout, "separatrices", traced),
            **_per_point(layout, "limit_cycle",
                         [None if c is None else limit_cycle_dataset(c) for c in cycles])}


def _process_age() -> float | None:
    """Seconds since this process started (Linux's /proc; None elsewhere)."""
    try:
        start_ticks = int(open("/proc/self/stat").read().rsplit(")", 1)[1].split()[19])
        uptime = float(open("/proc/uptime").read().split()[0])
        return uptime - start_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


class _Phases:
    """Wall time of the phases of a run, logged at INFO (``atlas run -v``)."""

    def __init__(self):
        self.last = time.perf_counter()

    def done(self, name: str) -> None:
        now = time.perf_counter()
        log.info("%-32s %6.2f s", name, now - self.last)
        self.last = now


def _finish(tiles: TileStore, cfg: Config, backend: str, quiet: bool, start: float,
            running_certificates: tuple[list, list], phase: _Phases) -> xr.DataTree:
    """Trace the separatrices (they measure d_cert, which certifying a tile needs), compute
    and certify what is missing, then assemble the file. A tile file found damaged is set
    aside (renamed, not deleted) and computed again. Logs each phase's time (``-v``).
    Returns what was written beyond the basin map (:func:`atlas.store.summary_tree`)."""
    pendulums = _pendulums(tiles.layout)
    cycles, barriers = running_certificates
    tilted = _tilted_boundaries(cfg, pendulums, cycles)  # timed with the separatrices
    traced = _trace_separatrices(cfg, pendulums, tilted, barriers)
    phase.done("separatrices")
    certifiers = _certifiers(tiles.layout, pendulums, traced, tilted, barriers)
    groups = _groups(tiles.layout, pendulums, traced, cycles)
    phase.done("exact boundaries and areas")
    for _ in range(3):
        _compute_into(tiles, cfg, certifiers, backend, quiet)
        phase.done("map (label and certify tiles)")
        finalize = zarrstore.finalize if tiles.format == "zarr" else store.finalize
        try:
            summary = _summary(cfg, tiles, certifiers)
            phase.done("summary")
            attrs = {"run_time_s": time.perf_counter() - start, "backend": backend}
            manifest_attrs = tiles.manifest["attrs"]  # read before finalize removes the tiles
            finalize(tiles, cfg.output, groups, summary, attrs)
            phase.done(f"writing ({tiles.layout.n_tiles} tiles assembled)")
            return store.summary_tree(tiles.layout, summary, groups,
                                      {**manifest_attrs, **attrs})
        except store.DamagedTile as exc:
            log.warning("%s: %s is damaged; computing it again", tiles.path, exc)
            tiles.set_aside(exc.index)
    raise StorageError(f"{tiles.path}: tile files keep coming back damaged; check the disk")


def run(cfg: Config, *, resume: bool = True, restart: bool = False, quiet: bool = False,
        backend: str | None = None, force: bool = False,
        config_path: str | Path | None = None, open_result: bool = True) -> xr.DataTree:
    """Compute the atlas of ``cfg`` into ``cfg.output`` and return it as a DataTree.

    An interrupted run of the same identity at the output (``<output>.partial/``) is
    continued: only its missing tiles are computed, with its own tiling. A partial run of
    another identity raises :class:`InputFileError`, unless ``restart=True`` discards it
    first. ``resume`` is accepted for compatibility (continuing is always on). ``backend``
    overrides ``execution.backend`` ('cpu', 'cuda' or 'dask'). A write error (disk full, I/O
    error) raises :class:`StorageError`; the tiles finished before it are kept. An output
    that atlas did not write is refused (:class:`~atlas.errors.OutputInTheWay`) unless
    ``force``, and one that is the config file ``config_path`` itself always.
    ``open_result=False`` returns, instead of the file opened (and checked) again, what was
    written beyond the basin map, from memory (:func:`atlas.store.summary_tree`: what
    ``atlas run`` prints).
    """
    from .validate import check_output_target

    check_output_target(cfg.output, config_path, force=force)
    backend = backend or cfg.execution.backend
    try:
        check_method(cfg.integrator.method, backend)
    except ValueError as exc:  # a --backend override of a valid config: name the config
        where = f"{config_path}: " if config_path is not None else ""
        raise AtlasError(f"{where}integrator.{exc}") from None
    layout = layout_of(cfg, backend)
    if backend == "cuda":
        from .kernels.cuda import require_cuda

        require_cuda()
    _check_output_path(cfg, layout)
    partial = partial_path(cfg.output)
    identity = run_identity(cfg, backend)
    if not restart:
        _check_partial(partial, identity)
    running_certificates = _running_certificates(_pendulums(layout), cfg.integrator.dt)
    _make_output_folder(cfg.output)
    start = time.perf_counter()
    age = _process_age()
    if age is not None:
        log.info("%-32s %6.2f s", "start-up (process, imports)", age)
    phase = _Phases()
    with output_lock(cfg.output):
        try:
            tiles = _open_tiles(cfg, layout, identity, restart)
            phase.done("partial run (open or resume)")
            written = _finish(tiles, cfg, backend, quiet, start, running_certificates, phase)
        except OverflowError as exc:
            raise AtlasError(f"{cfg.output}: {exc}") from None
        except OSError as exc:
            raise StorageError(f"{partial}: writing failed ({_reason(exc)}); the "
                               "tiles finished before it are kept: free space or fix the "
                               "disk, then run the same command again") from None
    if open_result:
        written = store.open_atlas(cfg.output)
        phase.done("opening the result")
    log.info("wrote %s in %.2f s", cfg.output, time.perf_counter() - start)
    return written


def _reason(exc: OSError) -> str:
    """The system's words for a failed write, on one line (HDF5's own messages are long)."""
    if exc.errno:
        return os.strerror(exc.errno)
    text = str(exc)
    found = re.search(r"errno = (\d+)", text)  # HDF5 quotes the system's errno
    if found:
        return os.strerror(int(found.group(1)))
    return text.splitlines()[0] if text else exc.__class__.__name__
