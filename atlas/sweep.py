"""The sweep: a config's grid of initial conditions → tiles → a basin atlas on disk.

The grid (θ̇0 rows × θ0 columns, for every α, ω0 of a parameter atlas) is cut into tiles of
whole rows (about ``execution.tile_orbits`` orbits each). Tiles are labelled independently
(:func:`compute_tile`, which any backend can run) and each finished tile is written at once
(:mod:`atlas.store`), so memory is bounded by a tile and a crash loses only tiles in flight.
Orbits never interact, so results do not depend on tile size, backend or thread count.
"""

from __future__ import annotations

import logging
import os
import shutil
import sys
import time
from collections.abc import Iterator
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import xarray as xr

from . import store
from .certificate import labelled
from .config import Config, config_hash
from .errors import AtlasError, StorageError
from .labels import CHECK_EVERY, label, trap_margin
from .lock import output_lock
from .model import Pendulum, critical_points

__all__ = ["run", "compute_tile", "layout_of", "critical_points_dataset"]

log = logging.getLogger(__name__)

#: Upper bound on the bytes one orbit takes on disk (int16 + int8 + float32, uncompressed).
BYTES_PER_ORBIT = 7


def layout_of(cfg: Config) -> store.Layout:
    """The grid axes, parameter axes and tiling of a config."""
    g = cfg.grid
    theta0 = np.linspace(g.theta0.start, g.theta0.stop, g.theta0.num)
    theta_dot0 = np.linspace(g.theta_dot0.start, g.theta_dot0.stop, g.theta_dot0.num)
    sweep = cfg.pendulum.is_sweep
    return store.Layout(
        theta0=theta0, theta_dot0=theta_dot0,
        alpha=np.array(cfg.pendulum.alphas) if sweep else None,
        omega0=np.array(cfg.pendulum.omega0s) if sweep else None,
        rows_per_tile=max(1, min(g.theta_dot0.num, cfg.execution.tile_orbits // g.theta0.num)),
    )


def _pendulum(cfg: Config, params: tuple[int, ...]) -> Pendulum:
    if not params:
        return Pendulum(cfg.pendulum.alphas[0], cfg.pendulum.omega0s[0])
    ia, iw = params
    return Pendulum(cfg.pendulum.alphas[ia], cfg.pendulum.omega0s[iw])


def compute_tile(theta0, theta_dot0, alpha, omega0, dt, t_max, backend="cpu",
                 numba_threads=None):
    """Label the orbits of one tile: θ0 [rad] along columns × θ̇0 [rad s⁻¹] along rows.

    Returns (attractor, status, t_trap), each shaped (rows, columns). A plain function of
    plain arguments, so it can run as a Dask task on another machine.
    """
    if numba_threads is not None:
        import numba

        numba.set_num_threads(min(numba_threads, numba.config.NUMBA_NUM_THREADS))
    res = label(theta0[None, :], theta_dot0[:, None], alpha=alpha, omega0=omega0, dt=dt,
                t_max=t_max, backend=backend)
    return res.attractor, res.status, res.t_trap


def _tile_args(cfg: Config, layout: store.Layout, index: int) -> tuple:
    params, rows = layout.tile(index)
    p = _pendulum(cfg, params)
    return (layout.theta0, layout.theta_dot0[rows], p.alpha, p.omega0,
            cfg.integrator.dt, cfg.integrator.t_max)


def _local_results(cfg, layout, todo, backend) -> Iterator[tuple[int, tuple]]:
    for index in todo:
        yield index, compute_tile(*_tile_args(cfg, layout, index), backend=backend)


def _dask_results(cfg, layout, todo) -> Iterator[tuple[int, tuple]]:
    from .distributed import dask_results

    yield from dask_results(cfg, todo, lambda i: _tile_args(cfg, layout, i), compute_tile)


def critical_points_dataset(cfg: Config, layout: store.Layout) -> xr.Dataset:
    """The ``/critical_points`` group: θ, n, kind and both eigenvalues of every rest state in
    the θ0 window. In a parameter atlas the kinds and eigenvalues depend on (α, ω0) and carry
    those leading dims; θ and n are the same for all."""
    lo, hi = float(layout.theta0[0]), float(layout.theta0[-1])
    per_param = [critical_points(Pendulum(a, w), lo, hi)
                 for a in cfg.pendulum.alphas for w in cfg.pendulum.omega0s]
    points = per_param[0]
    sweep = layout.alpha is not None
    lead_dims = ("alpha", "omega0") if sweep else ()
    lead_shape = (layout.alpha.size, layout.omega0.size) if sweep else ()
    eig = np.array([[p.eigenvalues for p in pts] for pts in per_param], np.complex128)
    eig = eig.reshape(*lead_shape, len(points), 2)
    kind = np.array([[p.kind for p in pts] for pts in per_param]).reshape(*lead_shape,
                                                                           len(points))
    dims = (*lead_dims, "point", "eigen")
    return xr.Dataset(
        {
            "eigenvalue_real": (dims, eig.real, {"units": "s-1",
                                                 "long_name": "real part of the eigenvalue"}),
            "eigenvalue_imag": (dims, eig.imag, {"units": "s-1",
                                                 "long_name": "imaginary part of the eigenvalue"}),
            "kind": ((*lead_dims, "point"), kind,
                     {"long_name": "attractor focus/node/critical node, or saddle"}),
        },
        coords={
            "theta": ("point", np.array([p.theta for p in points]),
                      {"units": "rad", "long_name": "angle of the rest state (n*pi, 0)"}),
            "n": ("point", np.array([p.n for p in points], np.int32),
                  {"units": "1", "long_name": "theta = n*pi"}),
        },
        attrs={"description": "critical points (n*pi, 0) of eq. (1) in the theta0 window and "
                              "their linearisation eigenvalues (essay section 3, eqs. 22-24)"},
    )


def _trace_separatrices(cfg: Config) -> list[xr.Dataset | None]:
    """The traced separatrices of every parameter point (None each when disabled)."""
    points = [Pendulum(a, w) for a in cfg.pendulum.alphas for w in cfg.pendulum.omega0s]
    if not cfg.separatrices.enabled:
        return [None] * len(points)
    from . import separatrices

    g = cfg.grid
    window = ((g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop))
    return [separatrices.trace(p, *window, tol=cfg.separatrices.tol,
                               max_spacing=cfg.separatrices.max_spacing, dt=cfg.integrator.dt)
            for p in points]


def _separatrices_group(cfg: Config, traced: list[xr.Dataset | None]) -> xr.Dataset | None:
    """The ``/separatrices`` group; for a parameter atlas, every (α, ω0)'s curves and
    crossings concatenated, tagged by ``point_alpha``/``point_omega0`` and
    ``crossing_alpha``/``crossing_omega0``."""
    if traced[0] is None:
        return None
    if not cfg.pendulum.is_sweep:
        return traced[0]
    from . import separatrices

    params = [(a, w) for a in cfg.pendulum.alphas for w in cfg.pendulum.omega0s]
    return separatrices.merge_parameter_points(
        [(a, w, ds) for (a, w), ds in zip(params, traced)])


def _certify(f, cfg: Config, layout: store.Layout, traced: list[xr.Dataset | None]):
    """Certify every tile for the exact equation (:mod:`atlas.certificate`): rewrite its
    status and boundary distances, and return each parameter point's summary."""
    from .certificate import Certifier

    points = []
    for p_index, sep in enumerate(traced):
        first = p_index * layout.bands
        p = _pendulum(cfg, layout.tile(first)[0])
        shift, tol = ((float(sep.attrs["discrepancy"]), float(sep.attrs["tol"]))
                      if sep is not None else (np.nan, np.nan))
        cert = Certifier(p, layout.theta0, layout.theta_dot0, shift, tol)
        untrapped = 0
        for index in range(first, first + layout.bands):
            attractor, status = store.read_labels(f, layout, index)
            status, distance = cert.tile(layout.tile(index)[1], attractor, status)
            store.write_certificate(f, layout, index, status, distance)
            untrapped += int(np.count_nonzero(~labelled(status)))
        n = cert.n_points
        points.append({**cert.fractions(), "unresolved_fraction": untrapped / n,
                       "certified_fraction": cert.certified / n, "d_cert": cert.d_cert,
                       "boundary_shift": shift, "side_mismatches": cert.mismatched,
                       "boundary_reference_error": cert.reference_error,
                       "trap_margin": trap_margin(cfg.integrator.dt, p.alpha, p.omega0)})
        if cert.mismatched:
            log.warning("alpha = %g, omega0 = %g: %d labels farther than d_cert from every "
                        "boundary disagree with the exact side; they are flagged near_boundary",
                        p.alpha, p.omega0, cert.mismatched)
    return points


def _versions() -> dict:
    import h5netcdf
    import h5py
    import numba

    from . import __version__

    return {"atlas_version": __version__, "numpy_version": np.__version__,
            "numba_version": numba.__version__, "xarray_version": xr.__version__,
            "h5py_version": h5py.__version__, "h5netcdf_version": h5netcdf.__version__,
            "python_version": sys.version.split()[0]}


def _attrs(cfg: Config) -> dict:
    attrs = {
        "title": f"atlas basin map: {cfg.name}",
        "Conventions": "CF-1.10",
        "method": "rk4",
        "dt": cfg.integrator.dt,
        "t_max": cfg.integrator.t_max,
        "check_every": np.int64(CHECK_EVERY),
        "config": cfg.to_json(),
        "config_hash": config_hash(cfg),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        **_versions(),
    }
    if not cfg.pendulum.is_sweep:
        attrs.update(alpha=cfg.pendulum.alphas[0], omega0=cfg.pendulum.omega0s[0])
    return attrs


def _check_output_path(cfg: Config, layout: store.Layout) -> None:
    """Refuse an output that cannot be written or would not fit, before anything is made."""
    out = cfg.output
    if out.is_dir():
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


def _open_partial(cfg: Config, layout: store.Layout, resume: bool):
    """The partial file to write into, its layout, and the tiles still to do."""
    partial = store.partial_path(cfg.output)
    if resume and partial.exists():
        f, layout, todo = store.open_partial(partial, config_hash(cfg))
        log.info("resuming %s: %d of %d tiles to do", partial, todo.size, layout.n_tiles)
        return f, layout, todo
    if resume:
        log.info("nothing to resume at %s: starting afresh", partial)
    partial.unlink(missing_ok=True)
    return store.create(partial, layout, _attrs(cfg)), layout, np.arange(layout.n_tiles)


def _orbits(layout: store.Layout, tiles) -> int:
    return sum((layout.tile(i)[1].stop - layout.tile(i)[1].start) for i in tiles) \
        * layout.theta0.size


def _compute_into(f, cfg: Config, layout: store.Layout, todo, backend: str, quiet: bool):
    """Label the tiles ``todo`` and write each into ``f`` as it finishes."""
    results = (_dask_results(cfg, layout, todo) if backend == "dask"
               else _local_results(cfg, layout, todo, backend))
    total = _orbits(layout, range(layout.n_tiles))
    with _progress(total, total - _orbits(layout, todo), quiet) as bar:
        for index, (attractor, status, t_trap) in results:
            store.write_tile(f, layout, index, attractor, status, t_trap)
            bar.update(status.size)
            log.debug("tile %d of %d written", index + 1, layout.n_tiles)


def run(cfg: Config, *, resume: bool = False, quiet: bool = False,
        backend: str | None = None) -> xr.DataTree:
    """Compute the atlas of ``cfg`` into ``cfg.output`` and return it as a DataTree.

    ``resume=True`` continues an interrupted run from ``<output>.partial`` (made from the
    same config), computing only the tiles it is missing. ``backend`` overrides
    ``execution.backend`` ('cpu', 'cuda' or 'dask'). A write error (disk full, I/O error)
    raises :class:`StorageError`; the tiles finished before it stay resumable.
    """
    backend = backend or cfg.execution.backend
    layout = layout_of(cfg)
    if backend == "cuda":
        from .kernels.cuda import require_cuda

        require_cuda()
    _check_output_path(cfg, layout)
    _make_output_folder(cfg.output)
    partial = store.partial_path(cfg.output)
    start = time.perf_counter()
    with output_lock(cfg.output):
        try:
            f, layout, todo = _open_partial(cfg, layout, resume)
        except OSError as exc:
            raise StorageError(f"{partial}: cannot create the partial file "
                               f"({exc.strerror or exc})") from None
        try:
            _compute_into(f, cfg, layout, todo, backend, quiet)
            traced = _trace_separatrices(cfg)
            points = _certify(f, cfg, layout, traced)
            groups = {"critical_points": critical_points_dataset(cfg, layout)}
            separatrices = _separatrices_group(cfg, traced)
            if separatrices is not None:
                groups["separatrices"] = separatrices
            store.finalize(f, partial, cfg.output, points, groups,
                           {"run_time_s": time.perf_counter() - start, "backend": backend})
        except OverflowError as exc:
            _close_quietly(f)
            raise AtlasError(f"{cfg.output}: {exc}") from None
        except OSError as exc:
            _close_quietly(f)
            raise StorageError(f"{partial}: writing failed ({exc.strerror or exc}); the "
                               "tiles finished before it are kept: free space or fix the "
                               "disk, then run again with --resume") from None
        except BaseException:
            _close_quietly(f)
            raise
    log.info("wrote %s in %.2f s", cfg.output, time.perf_counter() - start)
    return store.open_atlas(cfg.output)


def _close_quietly(f) -> None:
    try:
        f.close()
    except Exception:  # the file may be unwritable (disk full): its flushed tiles are safe
        log.debug("closing the partial file failed", exc_info=True)
