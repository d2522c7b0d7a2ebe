"""The ``atlas`` command line: a thin layer over the Python API.

Failures become messages here and nowhere else: every :class:`~atlas.errors.AtlasError` ends
with one line ``atlas: error: …`` on stderr and its ``exit_code``. Exit statuses: 0 done; 1 a
failure of the environment during a run (disk full, write refused), finished tiles kept; 2 bad
input (config, arguments, files, an output in the way), nothing created or overwritten; 3 the
output is locked by another run; 4 a run wrote its file but its separatrix check exceeded its
bound (0 with ``--accept-inexact``); 130 interrupted by Ctrl-C (SIGINT) and 143 by SIGTERM,
finished tiles kept.
"""

from __future__ import annotations

import argparse
import logging
import os
import re
import signal
import sys
from pathlib import Path

from atlas.defaults import BACKEND_WORDS
from atlas.errors import EXIT_BAD_INPUT, AtlasError, Terminated
from atlas.labels.backends import BACKENDS

EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143
#: The figure formats ``atlas plot --format`` offers: raster PNG, vector SVG and PDF.
PLOT_FORMATS = ("png", "svg", "pdf")


def _raise_terminated(signum, frame):
    raise Terminated()


def _interrupted(exc: KeyboardInterrupt) -> int:
    return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED


def _interrupt_behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM behind ``exc``, if any: a signal that arrives while a compiled
    kernel calls back into Python (Numba's ``_numba_unpickle``) comes out of the kernel as a
    SystemError ("returned a result with an exception set") caused by the KeyboardInterrupt."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage dump) and exit status 2."""

    def error(self, message):
        where = self.prog.removeprefix("atlas").strip()
        raise AtlasError(f"{where}: {message}" if where else message)


#: What a negative number looks like on the command line of the commands that take numbers
#: (``atlas orbit FILE -pi/2 1``, ``atlas zoom FILE -3 0.5 --width 1e-3``): a minus, then a
#: digit, a point, ``pi``, ``π`` or a parenthesis. argparse takes only -1 and -0.5 for
#: numbers and everything else starting with a minus for an option; none of atlas's options
#: looks like this.
_NEGATIVE_NUMBER = re.compile(r"^-(\d|\.\d|pi|π|\()")


def _takes_negative_numbers(parser: argparse.ArgumentParser) -> None:
    """Let ``parser`` read every :data:`_NEGATIVE_NUMBER` as a value, not as an unknown option
    (argparse has no public switch for it: its own matcher is replaced)."""
    parser._negative_number_matcher = _NEGATIVE_NUMBER


def _version() -> str:
    """The installed distribution's version (``pendulum-atlas``), or the package's where it is
    run from a source tree that is not installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pendulum-atlas")
    except PackageNotFoundError:
        from atlas._version import __version__

        return __version__


class _VersionAction(argparse.Action):
    """``atlas --version``: the version, looked up only when asked (not on every start)."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"atlas {_version()}")
        parser.exit()


def _cmd_run(args) -> int:
    from atlas.pipeline.config import load_config

    cfg = load_config(args.config, output=args.output)  # a bad config is refused before
    from atlas.pipeline import sweep  # the heavy imports (xarray, Numba kernels)


    try:
        from atlas.pipeline.preflight import ask

        tree = sweep.run(cfg, restart=args.restart, quiet=args.quiet, backend=args.backend,
                         force=args.force, config_path=args.config, open_result=False,
                         confirm=ask(yes=args.yes, quiet=args.quiet))
    except (KeyboardInterrupt, SystemError) as exc:
        interrupt = _interrupt_behind(exc)
        if interrupt is None:
            raise
        what = "terminated (SIGTERM)" if isinstance(interrupt, Terminated) else "interrupted"
        print(f"atlas: {what}; {sweep.kept_after_interrupt(cfg.output)}", file=sys.stderr)
        return _interrupted(interrupt)
    if args.resume:  # said after the run, so that bad input still gets its one line
        print("atlas: --resume is deprecated and does nothing (an interrupted run is always "
              "continued); it will be removed", file=sys.stderr)
    if not args.quiet:
        from atlas.views.info import summary_lines

        print(f"wrote {cfg.output}")
        for line in summary_lines(tree, brief=True):
            print("  " + line)
    return sweep.accuracy_exit(tree, cfg.output, accept_inexact=args.accept_inexact)


def _add_point_selectors(p: argparse.ArgumentParser, what: str, default: str) -> None:
    """``--point I``, ``--alpha A``, ``--omega0 W``, ``--torque T``, and of a driven
    pendulum's atlas ``--amplitude``, ``--frequency`` (each repeatable): the parameter points
    of an atlas whose ``what`` is shown (:mod:`atlas.views.selectors`)."""
    p.add_argument("--point", type=int, action="append", metavar="I",
                   help=f"{what} parameter point I (0 the first, -1 the last); repeatable; "
                   f"default: {default}")
    for name, unit, letter in _SELECTORS:
        p.add_argument(f"--{name}", type=float, action="append", metavar=letter,
                       help=f"{what} the point(s) of the nearest {name} [{unit}] (outside "
                       "the atlas's range: refused); repeatable")


#: The parameters a point may be chosen by: name, unit, metavar.
_SELECTORS = (("alpha", "1/s", "A"), ("omega0", "rad/s", "W"), ("torque", "rad/s^2", "T"),
              ("amplitude", "rad/s^2", "F"), ("frequency", "rad/s", "OMEGA"))


def _point_selectors(args) -> dict:
    """The point selectors of ``atlas info`` and ``atlas plot``, as
    :func:`atlas.views.selectors.choose_points` takes them."""
    return {name: getattr(args, name) for name in ("point", *(s[0] for s in _SELECTORS))}


def _cmd_info(args) -> int:
    from atlas.store.readback import DamagedChunk, read_back
    from atlas.views.info import info_lines

    try:
        lines = info_lines(args.file, _point_selectors(args))
    except (AtlasError, OSError):
        if args.check and Path(args.file).exists():
            try:  # a read that failed on a damaged chunk: name it
                read_back(args.file)
            except DamagedChunk:
                raise
            except AtlasError:
                pass
        raise
    if args.check:
        done = read_back(args.file)
        lines.append(f"  check     every stored chunk read back: {done.variables} variables "
                     f"in {done.groups} groups, {done.nbytes:,} bytes")
    for line in lines:
        print(line)
    return 0


def _cmd_plot(args) -> int:
    from atlas.views.plotting import plot_file

    if not (args.dpi is None or 10 <= args.dpi <= 2400):
        raise AtlasError(f"plot: --dpi must be between 10 and 2400 pixels per inch, "
                         f"got {args.dpi:g}")
    if args.outdir is not None:
        _check_folder(Path(args.outdir))  # made once the file is read (bad input: none)
    # all that is drawn is read before a figure is written
    for path in plot_file(args.file, args.outdir, args.format, args.dpi,
                          _point_selectors(args)):
        print(f"wrote {path}")
    return 0


def _output_folder(folder: Path) -> Path:
    """Create ``folder`` for a command's outputs, or one clear AtlasError."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise AtlasError(f"{folder}: cannot create the output folder "
                         f"({exc.strerror or exc})") from None
    return folder


def _check_folder(folder: Path) -> None:
    """One clear AtlasError unless ``folder`` is a folder or could be made (no file in the
    way of it or of a folder above it); nothing is created."""
    for place in (folder, *folder.parents):
        if place.exists():
            if not place.is_dir():
                raise AtlasError(f"{folder}: cannot create the output folder ({place} is a "
                                 "file)")
            return


def _cmd_figures(args) -> int:
    from atlas.commands.figures import write_all

    for path in write_all(_output_folder(Path(args.outdir))):
        print(f"wrote {path}")
    return 0


def _cmd_bench(args) -> int:
    from atlas.commands.bench import bench_to_json
    from atlas.store.outputs import check_output

    output = Path(args.output)
    check_output(output, "bench", option="--output")
    _output_folder(output.parent)
    bench_to_json(output, backend=args.backend, quick=args.quick,
                  gpu_sweeps=tuple(args.gpu_sweep or ()))
    return 0


def _cmd_view(args) -> int:
    from atlas.store.outputs import check_output
    from atlas.views.page import write_view

    output = Path(args.output) if args.output else Path(args.file).with_suffix(".html")
    check_output(output, "page", inputs=(args.file,))
    print(f"wrote {write_view(args.file, output)}")
    return 0


def _orbit_values(values: list[str]) -> tuple[str | None, str, str]:
    """(FILE or None, THETA0, THETA_DOT0) of ``atlas orbit``'s positional arguments, or one
    AtlasError saying which is missing (``atlas orbit FILE 1`` lacks THETA_DOT0: the file is
    not a number)."""
    from atlas.commands.orbit import check_file_argument, looks_like_file

    if len(values) == 2 and looks_like_file(values[0]):
        raise AtlasError(f"orbit: THETA_DOT0 is missing: give {values[0]} THETA0 THETA_DOT0 "
                         "(the initial angle [rad] and angular velocity [rad/s])")
    if len(values) not in (2, 3):
        missing = ("THETA0 and THETA_DOT0 are missing" if len(values) == 1 and
                   looks_like_file(values[0]) else f"got {len(values)} values")
        raise AtlasError("orbit: give THETA0 THETA_DOT0, or FILE THETA0 THETA_DOT0 "
                         f"({missing})")
    file = values[0] if len(values) == 3 else None
    if file is not None:
        check_file_argument(file)
    return file, values[-2], values[-1]


def _cmd_orbit(args) -> int:
    from atlas.commands.orbit import (
        DRIVE_PARAMETERS,
        default_output,
        parse_number,
        plot,
        report,
    )
    from atlas.store.outputs import check_output

    file, theta0, theta_dot0 = _orbit_values(args.values)
    theta0, theta_dot0 = (parse_number(text, name) for text, name in
                          ((theta0, "theta0"), (theta_dot0, "theta_dot0")))
    selectors = ("alpha", "omega0", "torque", *DRIVE_PARAMETERS)
    opts = {name: None if getattr(args, name) is None else parse_number(getattr(args, name),
                                                                         f"--{name}")
            for name in (*selectors, "dt", "t_max")}
    output = Path(args.output) if args.output else default_output(
        file, theta0, theta_dot0, {name: opts[name] for name in selectors})
    check_output(output, "figure", inputs=(file,) if file else (), command="atlas orbit")
    orbit, lines, context = report(theta0, theta_dot0, file=file, **opts)
    _output_folder(output.parent)
    try:
        plot(orbit, output, context)
    finally:
        if context["tree"] is not None:
            context["tree"].close()
    for line in lines:
        print(line)
    print(f"wrote        {output}")
    return 0


def _cmd_zoom(args) -> int:
    from atlas.commands.orbit import parse_number
    from atlas.commands.zoom import write_zoom, zoom_config

    theta0, theta_dot0, width = (parse_number(text, name) for text, name in (
        (args.theta0, "theta0"), (args.theta_dot0, "theta_dot0"), (args.width, "--width")))
    opts = {name: None if getattr(args, name) is None else parse_number(getattr(args, name),
                                                                         f"--{name}")
            for name in ("alpha", "omega0", "torque", "amplitude", "frequency", "phase")}
    if args.num is not None:
        opts["num"] = args.num
    zoom = zoom_config(args.file, theta0, theta_dot0, width, **opts)
    if args.output is None:
        sys.stdout.write(zoom.text)
    else:
        print(f"wrote {write_zoom(zoom, args.output, args.file)}; run it with "
              f"atlas run {args.output}")
    return 0


def _add_view_orbit_zoom(sub) -> None:
    p = sub.add_parser("view", help="OUT.html: a self-contained interactive page of an atlas "
                       "file")
    p.add_argument("file", help="an atlas file (atlas run's output)")
    p.add_argument("-o", "--output", help="the page (default: the atlas file with .html)")
    p.set_defaults(func=_cmd_view)

    p = sub.add_parser("orbit",
                       help="one orbit: label, certificate, phase curve and theta(t) as PNG",
                       usage="%(prog)s [-h] [FILE] THETA0 THETA_DOT0 [--alpha ALPHA] "
                       "[--omega0 OMEGA0]\n                   [--torque TORQUE] [--amplitude A] "
                       "[--frequency F] [--phase PHI]\n                   [--dt DT] "
                       "[--t-max T_MAX] [-o OUTPUT]",
                       description="atlas orbit [FILE] THETA0 THETA_DOT0: one orbit from "
                       "(THETA0 [rad], THETA_DOT0 [rad/s]), numbers or pi expressions, negative "
                       "ones as they are (atlas orbit FILE -pi/2 1); with an atlas FILE at its "
                       "parameters and certificate, else give --alpha and --omega0; a driven "
                       "pendulum's FILE: its RK4 map and attractors, theta(t), the phase curve "
                       "and the stroboscopic returns")
    _takes_negative_numbers(p)
    p.add_argument("values", nargs="+", metavar="[FILE] THETA0 THETA_DOT0",
                   help="an atlas file (optional), then the initial angle theta0 [rad] and "
                   "angular velocity theta_dot0 [rad/s]")
    p.add_argument("--alpha", help="damping [1/s] (with a file: selects a parameter point)")
    p.add_argument("--omega0", help="natural frequency [rad/s] (with a file: selects a point)")
    p.add_argument("--torque", help="torque [rad/s^2] (default 0; with a file: selects a point)")
    p.add_argument("--amplitude", help="drive amplitude A [rad/s^2] (a driven pendulum's "
                   "file: selects a point)")
    p.add_argument("--frequency", help="drive frequency [rad/s] (a driven pendulum's file: "
                   "selects a point)")
    p.add_argument("--phase", help="drive phase [rad] (a driven pendulum's file: selects a "
                   "point)")
    p.add_argument("--dt", help="RK4 step [s] (default 0.01; with a file: the file's)")
    p.add_argument("--t-max", dest="t_max", help="t_max [s] (default 200; a file: the file's)")
    p.add_argument("-o", "--output", help="the figure, .png, .svg or .pdf (default: "
                   "FILE_orbit_THETA0_THETA_DOT0.png next to the file, else "
                   "outputs/orbit_THETA0_THETA_DOT0.png, with the parameters given)")
    p.set_defaults(func=_cmd_orbit)

    p = sub.add_parser("zoom",
                       help="the YAML config of a square window centred on a point, at an "
                       "atlas file's parameters",
                       description="atlas zoom FILE THETA0 THETA_DOT0 --width W: the config "
                       "of a window W wide in theta0 [rad] and theta_dot0 [rad/s] centred on "
                       "(THETA0, THETA_DOT0), at FILE's parameters and integrator; numbers or "
                       "pi expressions, negative ones as they are (atlas zoom FILE -pi/2 1 "
                       "--width 1e-3)")
    _takes_negative_numbers(p)
    p.add_argument("file", help="an atlas file (atlas run's output)")
    p.add_argument("theta0", help="the window's centre theta0 [rad]")
    p.add_argument("theta_dot0", help="the window's centre theta_dot0 [rad/s]")
    p.add_argument("--width", required=True, help="the window's width W [rad and rad/s], > 0")
    p.add_argument("--num", type=int,
                   help="orbits per axis (default 101: the centre is a grid point)")
    p.add_argument("--alpha", help="a parameter atlas: selects the point's damping [1/s]")
    p.add_argument("--omega0", help="a parameter atlas: selects the point's omega0 [rad/s]")
    p.add_argument("--torque", help="a parameter atlas: selects the point's torque [rad/s^2]")
    p.add_argument("--amplitude", help="a driven atlas: selects the drive's amplitude "
                   "[rad/s^2]")
    p.add_argument("--frequency", help="a driven atlas: selects the drive's frequency "
                   "[rad/s]")
    p.add_argument("--phase", help="a driven atlas: selects the drive's phase [rad]")
    p.add_argument("-o", "--output", help="write the config here (default: print it)")
    p.set_defaults(func=_cmd_zoom)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="atlas", description="Phase-space atlas of the damped pendulum "
                     "θ̈ = −ω0² sin θ − 2αθ̇ + τ: basins of attraction, separatrices, figures. "
                     "Angles are in radians; numbers may be pi expressions (3pi, -pi/2).",
                     epilog="Exit status: 0 done; 1 the environment failed a run (disk full, "
                     "write refused; finished tiles kept); 2 bad input (nothing written); 3 "
                     "the output is locked by another run; 4 a run wrote its file but an "
                     "accuracy check exceeded its bound (0 with --accept-inexact); 130/143 "
                     "interrupted (Ctrl-C/SIGTERM; finished tiles kept). `atlas COMMAND -h` "
                     "for a command's help.")
    parser.add_argument("--version", action=_VersionAction,
                        help="print the version of atlas and exit")
    # -v where there is progress to log: `atlas run` (and commands that run sweeps)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-v", "--verbose", action="count", default=0,
                        help="log the time of each stage of the run (-v) and every tile "
                        "written (-vv)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser("run", parents=[common],
                       help="compute the atlas of a YAML config into HDF5 (or Zarr: NAME.zarr)")
    p.add_argument("config", help="YAML config, e.g. configs/default.yaml")
    p.add_argument("-o", "--output", help="output file (overrides the config's output key)")
    p.add_argument("--resume", action="store_true",
                   help="deprecated, does nothing: an interrupted run of the same config is "
                   "always continued (accepted so that old scripts keep working)")
    p.add_argument("--restart", action="store_true",
                   help="discard an interrupted run at the output (its finished tiles) and "
                   "start over")
    p.add_argument("--force", action="store_true",
                   help="write over an existing file at the output that atlas did not write "
                   "(never over the config itself)")
    p.add_argument("--backend", choices=tuple(BACKEND_WORDS),
                   help="override execution.backend: the device (cpu, cuda) or the CPU on a "
                   "Dask cluster (dask)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no summary")
    p.add_argument("--yes", action="store_true", help="start a big run without asking "
                   "(on a terminal, a run of about 2 min or 1 GB or more asks first)")
    p.add_argument("--accept-inexact", action="store_true", help="exit 0 although the "
                   "separatrix check exceeds its bound (else exit 4; the file is written)")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("info", help="describe an atlas file: parameters, basin fractions, "
                       "d_cert, separatrices, provenance")
    p.add_argument("file", help="an atlas file (atlas run's output, NAME.h5 or NAME.zarr); "
                   "for an interrupted run, how far it got")
    _add_point_selectors(p, "print the detail of", "a parameter atlas's points as one "
                         "table")
    p.add_argument("--check", action="store_true", help="also read back every stored chunk "
                   "of every variable (a damaged one: named, exit status 2)")
    p.set_defaults(func=_cmd_info)

    p = sub.add_parser("plot", help="the figures of an atlas file (basin map, trapping "
                       "time, boundary distance, curves of swept parameters)")
    p.add_argument("file", help="an atlas file (atlas run's output)")
    p.add_argument("--outdir", help="write the figures into this folder, made if needed "
                   "(default: next to the file, NAME.png, NAME_t_trap.png, ...)")
    p.add_argument("--format", choices=PLOT_FORMATS, default="png",
                   help="the figures' file format (default png; svg and pdf are vector, with "
                   "the basin maps as embedded images)")
    p.add_argument("--dpi", type=float, help="resolution in pixels per inch (default 150; "
                   "the maps' images hold at most 1200 pixels per axis whatever the dpi)")
    _add_point_selectors(p, "draw only the full maps of", "a parameter atlas's basin maps "
                         "as small multiples, the t_trap and distance maps of its first "
                         "point")
    p.set_defaults(func=_cmd_plot)

    p = sub.add_parser("figures", help="the essay's Figures 1-12, redrawn")
    p.add_argument("--outdir", default="outputs/figures",
                   help="the folder to write them into, made if needed (default "
                   "outputs/figures)")
    p.set_defaults(func=_cmd_figures)

    p = sub.add_parser("bench", help="benchmark table, written to outputs/bench.json")
    p.add_argument("--quick", action="store_true", help="fewer sizes and repetitions")
    p.add_argument("--backend", choices=tuple(BACKENDS), default="cpu",
                   help="the device to benchmark (cuda: the GPU rows)")
    p.add_argument("--output", default="outputs/bench.json",
                   help="the JSON file of the results (default outputs/bench.json)")
    p.add_argument("--gpu-sweep", type=int, action="append", metavar="N",
                   help="with a GPU: also time atlas run --backend cuda of the N x N default "
                        "atlas, end to end (repeatable; 16384 is the target's size)")
    p.set_defaults(func=_cmd_bench)
    _add_view_orbit_zoom(sub)
    from atlas.commands.stability import add_parser as add_stability

    add_stability(sub, common)
    return parser


def _configure_logging(verbose: int) -> None:
    """Warnings from anyone; atlas's own progress (-v) and detail (-vv) from the ``atlas``
    logger only: third-party loggers (Numba's compiler, filelock, Dask) stay at WARNING."""
    logging.basicConfig(level=logging.WARNING, format="atlas: %(message)s")
    level = [logging.WARNING, logging.INFO, logging.DEBUG][min(verbose, 2)]
    logging.getLogger("atlas").setLevel(level)
    for name in ("numba", "filelock"):  # explicit: they may have set their own levels
        logging.getLogger(name).setLevel(logging.WARNING)


def _input_file(args) -> str | None:
    """The atlas file a reading command was given (None for ``run`` and the others)."""
    if getattr(args, "command", None) in ("info", "plot", "view", "zoom"):
        return args.file
    if getattr(args, "command", None) == "orbit" and len(args.values) == 3:
        return args.values[0]
    return None


def _os_error(exc: OSError, args) -> tuple[str, int]:
    """An OSError that reached the CLI: a read of the input file that failed inside HDF5 (no
    system errno: damaged data, checked metadata notwithstanding) is bad input, exit 2; a
    failure of the system (disk full, write refused) is the environment's, exit 1."""
    from atlas.errors import EXIT_ENVIRONMENT

    reason = os.strerror(exc.errno) if exc.errno else (str(exc).strip().splitlines() or
                                                       [type(exc).__name__])[0]
    source = _input_file(args)
    if not exc.errno and source is not None:
        return f"{source}: damaged data, cannot be read ({reason})", EXIT_BAD_INPUT
    where = exc.filename or source or "atlas"
    return f"{where}: {reason}", EXIT_ENVIRONMENT


def _one_line(text: str) -> str:
    """A message on one line, printable (text taken from a file, a config or a library may
    hold newlines or terminal control characters)."""
    text = " ".join(text.split())
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def main(argv: list[str] | None = None) -> int:
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:  # SIGTERM stops a run like Ctrl-C
        signal.signal(signal.SIGTERM, _raise_terminated)
    args = None
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if args.command is None:  # a bare `atlas`: what it can do
            parser.print_help()
            return 0
        _configure_logging(getattr(args, "verbose", 0))
        return args.func(args)
    except AtlasError as exc:
        print(f"atlas: error: {_one_line(str(exc))}", file=sys.stderr)
        return getattr(exc, "exit_code", EXIT_BAD_INPUT)
    except (KeyboardInterrupt, SystemError) as exc:
        interrupt = _interrupt_behind(exc)
        if interrupt is None:
            raise
        print("atlas: terminated (SIGTERM)" if isinstance(interrupt, Terminated)
              else "atlas: interrupted", file=sys.stderr)
        return _interrupted(interrupt)
    except BrokenPipeError:  # `atlas info x.h5 | head`: the reader left, nothing is wrong
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # one that no layer below turned into an AtlasError
        message, code = _os_error(exc, args)
        print(f"atlas: error: {_one_line(message)}", file=sys.stderr)
        return code


def leave(code: int) -> None:
    """End the process with exit status ``code`` without tearing the interpreter down: after
    a run that teardown (xarray's, h5py's and Numba's modules, Numba's threads) takes 0.2–0.4 s
    of the user's wait and does nothing useful — every file atlas wrote is closed and synced,
    the returned atlas is open read-only. Standard output and error are flushed and logging
    shut down first. Where a child process or a non-daemon thread is still alive (a Dask
    cluster being shut down), the interpreter exits the normal way."""
    import threading

    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a reader that left (`atlas info x.h5 | head`)
            pass
    logging.shutdown()
    others = [t for t in threading.enumerate()
              if t is not threading.main_thread() and not t.daemon]
    children = "multiprocessing" in sys.modules and sys.modules[
        "multiprocessing"].active_children()
    if others or children:
        sys.exit(code)
    os._exit(code)


def entry() -> None:
    """The ``atlas`` command and ``python -m atlas``: :func:`main`, then :func:`leave`."""
    leave(main())


if __name__ == "__main__":
    entry()
