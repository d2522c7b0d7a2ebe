"""``atlas stability CONFIG.yaml [-o OUT.h5] [--backend cpu|dask] [--force] [-v]``: a study
without a grid.

The config is the usual one (each pendulum parameter a number, a list or a range
``{start, stop, num}``; two swept parameters make a 2-D study); its grid's window is the
region of perturbations and ``grid.*.num`` is not used; the optional ``stability:`` section
asks for the Gaussian perturbation (``sigma_theta``, ``sigma_theta_dot``) and the tipping
probabilities (``tipping: true``, 1-D studies). Every parameter point is computed exactly
(:mod:`atlas.stability.study`), the bifurcations of the ranges located
(:mod:`atlas.stability.bifurcations`), and the study written to the config's output (or
``-o``) as :mod:`atlas.store.study` lays it out. Bad input — a config that does not validate,
a study of more than :data:`MAX_POINTS` points without ``--force``, a window or Gaussian box
whose boundaries would run beyond the wells an atlas indexes, an output that holds a file
other than a study without ``--force`` — is refused before any work, with one line (exit
status 2).
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path

from atlas.errors import AtlasError, OutputInTheWay
from atlas.models.pendulum.description import PARAMETERS

__all__ = ["add_parser", "run_study", "run_driven_study", "MAX_POINTS"]

log = logging.getLogger("atlas.stability")

#: The most parameter points a study computes without ``--force``.
MAX_POINTS = 1_000_000


def add_parser(sub, common) -> None:
    """The ``stability`` subcommand of ``atlas`` (``sub``: argparse's subparsers; ``common``:
    the parent parser with ``-v``)."""
    p = sub.add_parser("stability", parents=[common],
                       help="a study without a grid: exact basin stability, minimal fatal "
                       "shocks, tipping and bifurcations per parameter point")
    p.add_argument("config", help="YAML config with parameter ranges, e.g. "
                   "configs/swing_stability.yaml")
    p.add_argument("-o", "--output", help="the study file (default: the config's output; "
                   "NAME.zarr for Zarr)")
    p.add_argument("--backend", choices=("cpu", "dask"),
                   help="compute the points here (cpu) or as Dask tasks (dask; "
                   "execution.scheduler, else a local cluster); default execution.backend")
    p.add_argument("--force", action="store_true", help="compute more than 1,000,000 points, "
                   "or write over a file that is not a study")
    p.set_defaults(func=_cmd_stability)


def _cmd_stability(args) -> int:
    ds, path, seconds = run_study(args.config, output=args.output, backend=args.backend,
                                  force=args.force, verbose=args.verbose > 0)
    from atlas.views.study_info import study_lines

    for line in study_lines(ds):
        print(line)
    print(f"wrote {path} in {seconds:.1f} s")
    return 0


def _check_output(path: Path, force: bool, config) -> None:
    from atlas.store.outputs import check_output

    check_output(path, "study", inputs=(config,), force=force)
    if not path.parent.is_dir():
        raise OutputInTheWay(f"{path.parent}: no such folder for the output")


def _check_reach(settings, alpha: float, config) -> None:
    """Refuse, in one line naming the key, a study whose exact boundaries would run beyond the
    wells an atlas indexes (:func:`atlas.limits.check_reach`, the grid run's bound at the
    smallest ``alpha`` [1/s]): over its window, or over the Gaussian's box around a rest state
    (|θ*| ≤ π/2). Their cost grows with the wells and speeds they span: such a study (a
    window ±1e6 wide, σ = 1e6) ran for hours, or until the memory ran out."""
    from atlas.errors import ConfigError
    from atlas.limits import check_reach
    from atlas.stability.study import gaussian_box

    boxes = [("grid", settings.window)]
    if settings.sigma is not None:
        boxes.append(("stability.sigma_theta, sigma_theta_dot",
                      gaussian_box(0.5 * math.pi, settings.sigma)))
    for key, box in boxes:
        try:
            check_reach(*(max(abs(lo), abs(hi)) for lo, hi in box), alpha)
        except ValueError as exc:
            raise ConfigError(f"{config}: {key}: {exc}") from None


def run_study(config, *, output=None, backend=None, force=False, verbose=False,
              on_result=None):
    """Load, check, compute and write the study of ``config``: (Dataset, output path,
    seconds in all). ``on_result`` as :func:`atlas.stability.study.compute_points`."""
    from atlas.kernels.threads import cores
    from atlas.models.registry import DEFAULT, DRIVEN
    from atlas.pipeline.config import load_config
    from atlas.stability.study import PHASES, StudySettings, compute_points

    start = time.perf_counter()
    cfg = load_config(config, output=output, study=True)
    if cfg.description.name == DRIVEN:
        return run_driven_study(cfg, config, start, backend=backend, force=force,
                                verbose=verbose, on_result=on_result)
    if cfg.description.name != DEFAULT:  # the study is the pendulum's physics
        raise AtlasError(f"{config}: model {cfg.description.name}: atlas stability studies the "
                         "pendulum's basins only")
    count = math.prod(len(cfg.pendulum.values(name)) for name in PARAMETERS)
    if count > MAX_POINTS and not force:
        raise AtlasError(f"{config}: the study has {count:,} parameter points, more "
                         f"than {MAX_POINTS:,}; --force computes it anyway")
    points = cfg.pendulum.points
    g = cfg.grid
    stab = cfg.stability
    settings = StudySettings(
        window=((g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop)),
        sigma=(None if stab is None or stab.sigma_theta is None
               else (stab.sigma_theta, stab.sigma_theta_dot)),
        tipping=bool(stab is not None and stab.tipping))
    _check_reach(settings, min(cfg.pendulum.alphas), config)
    path = Path(cfg.output)
    _check_output(path, force, config)
    backend = backend or ("dask" if cfg.execution.backend == "dask" else "cpu")
    triples = [(p["alpha"], p["omega0"], p["torque"]) for p in points]
    workers = cfg.execution.workers or (None if backend == "dask" else cores())
    results = compute_points(triples, settings, backend=backend,
                             scheduler=cfg.execution.scheduler, workers=workers,
                             on_result=on_result)
    if verbose:
        for line in cost_lines(results, PHASES):
            log.info(line)
    clock = time.perf_counter()
    from atlas.stability.dataset import study_dataset
    from atlas.store.study import write_study

    ds = study_dataset(cfg, settings, results)
    if verbose:
        log.info("bifurcations and the file's layout: %.3f s", time.perf_counter() - clock)
    write_study(ds, path)
    return ds, path, time.perf_counter() - start


def run_driven_study(cfg, config, start: float, *, backend=None, force=False, verbose=False,
                     on_result=None):
    """The study of a driven config (validated ``cfg``, from the file ``config``; the clock
    started at ``start``): its attractors followed along the swept parameter, their basin
    fractions sampled and their bifurcations located (:mod:`atlas.stability.driven`),
    written as :mod:`atlas.store.driven_study` lays it out: (Dataset, path, seconds)."""
    from atlas.kernels.threads import cores
    from atlas.pipeline.config_sections import DRIVEN_SAMPLES
    from atlas.stability.driven import DrivenSettings, compute_study, driven_dataset
    from atlas.store.study import write_study

    pend = cfg.pendulum
    count = len(pend.points)
    if count > MAX_POINTS and not force:
        raise AtlasError(f"{config}: the study has {count:,} parameter points, more "
                         f"than {MAX_POINTS:,}; --force computes it anyway")
    g, stab = cfg.grid, cfg.stability
    settings = DrivenSettings(
        window=((g.theta0.start, g.theta0.stop), (g.theta_dot0.start, g.theta_dot0.stop)),
        samples=(stab.samples if stab is not None and stab.samples is not None
                 else DRIVEN_SAMPLES),
        seed=stab.seed if stab is not None and stab.seed is not None else 0,
        max_period=pend.drive.max_period, t_max=cfg.integrator.t_max, dt=cfg.integrator.dt)
    path = Path(cfg.output)
    _check_output(path, force, config)
    backend = backend or ("dask" if cfg.execution.backend == "dask" else "cpu")
    workers = cfg.execution.workers or (None if backend == "dask" else cores())
    swept = pend.swept[0] if pend.swept else None
    study = compute_study(pend.points, swept, settings, backend=backend,
                          scheduler=cfg.execution.scheduler, workers=workers,
                          on_result=on_result)
    if verbose:
        for line in cost_lines(study.results, ("attractors", "samples")):
            log.info(line)
        log.info("matching and %d bisections: %.2f s", len(study.events),
                 study.seconds["bifurcations"])
    ds = driven_dataset(cfg, settings, study)
    write_study(ds, path)
    return ds, path, time.perf_counter() - start


def cost_lines(results, phases) -> list[str]:
    """The mean and largest cost per point of each phase [s] (``-v``, ``atlas bench``)."""
    import numpy as np

    lines = []
    for phase in phases:
        times = np.array([r.seconds[phase] for r in results if phase in r.seconds])
        if times.size:
            lines.append(f"per point, {phase:<10} mean {1e3 * times.mean():8.2f} ms, "
                         f"max {1e3 * times.max():8.2f} ms ({times.size} of "
                         f"{len(results)} points: those it ran at)")
    return lines
