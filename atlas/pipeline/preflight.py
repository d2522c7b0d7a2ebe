"""Before a big run: how many orbits, about how long on this machine, how much disk; and,
past a threshold, on a terminal, a question.

The time is measured, not guessed: :func:`measure_rate` labels a sample of the run's own
orbits (whole stretches of grid rows, as a tile has them, at a few of its parameter points)
with the run's kernels on this machine, and the run's orbits are divided by that rate. It
times the labelling only (the RK4 map and its energy trap, the bulk of a big run): the
separatrices and the certificate's distances come on top, and the sample's orbits are
spread over the grid at random, so the figure is "about" (its ± is the sample's spread,
tens of per cent). The calibration takes about a third of a second (:func:`measure_rate`;
and the kernels' loading, which the run would do anyway), and it is done only where the run
may be big: :data:`PREFLIGHT_ORBITS` orbits or more, or :data:`CALIBRATE_STEPS` RK4 steps if
every orbit ran to ``t_max``. A GPU's rate is not measured on a sample (it would time the
launch, not the device): there the line gives no time.

The disk figure is the output policy's own (:func:`atlas.pipeline.output.label_bytes`: every
per-orbit variable at its stored dtype, uncompressed; compression only lowers it).

What happens with the estimate (:func:`atlas.pipeline.sweep.run`, ``confirm``): a run of
:data:`PREFLIGHT_ORBITS` orbits or more, or of about :data:`LINE_S` s or more, says it in one
line on stderr (not with ``--quiet``); one of about :data:`CONFIRM_S` s or more, or of
:data:`CONFIRM_BYTES` or more on disk, asks "Start? [y/N]" when stdin is a terminal
(:func:`ask`; ``--yes`` answers for the user). Not on a terminal (a batch job, ``make``) it
starts without asking and says so (not with ``--quiet``): a cluster job is big on purpose,
and a disk too small is refused anyway before anything starts
(:func:`atlas.pipeline.output.check_output_path`). There is no hard limit.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from atlas.layout import Layout
from atlas.models.registry import planner
from atlas.pipeline.config import Config
from atlas.pipeline.output import human_size, label_bytes

__all__ = ["Estimate", "estimate", "measure_rate", "ask", "PREFLIGHT_ORBITS",
           "CALIBRATE_STEPS", "LINE_S", "CONFIRM_S", "CONFIRM_BYTES", "orbits_of"]

#: Orbits (all parameter points together) from which a run always says its estimate.
PREFLIGHT_ORBITS = 4_000_000
#: RK4 steps, were every orbit to run to t_max, from which the time is measured.
CALIBRATE_STEPS = 2e10
#: Estimated seconds from which a run says its estimate.
LINE_S = 30.0
#: Estimated seconds from which a run on a terminal asks before it starts.
CONFIRM_S = 120.0
#: Bytes on disk from which a run on a terminal asks before it starts.
CONFIRM_BYTES = 10**9
#: Orbits of a calibration stretch: consecutive θ0 of one grid row, as a tile holds them.
STRETCH = 64
#: The calibration's sample: from FIRST_SAMPLE orbits, grown (at most fourfold) until one call
#: takes CALL_S seconds or MAX_SAMPLE orbits, then as large at up to MAX_POINTS parameter
#: points in all.
FIRST_SAMPLE, MAX_SAMPLE, CALL_S, MAX_POINTS = 1024, 65536, 0.05, 3


@dataclass(frozen=True)
class Estimate:
    """A run before it starts: ``orbits`` still to label (all points), ``points`` parameter
    points, ``seconds`` the labelling's estimated wall time on this machine (None where not
    measured), ``sample`` the orbits it was measured on, ``disk_bytes`` the file's labels at
    most, ``backend`` the backend word."""

    orbits: int
    points: int
    seconds: float | None
    sample: int
    disk_bytes: int
    backend: str = "cpu"

    @property
    def big(self) -> bool:
        """Whether the run says its estimate (module docstring)."""
        return self.orbits >= PREFLIGHT_ORBITS or (self.seconds or 0.0) >= LINE_S

    @property
    def asks(self) -> bool:
        """Whether the run asks before it starts, on a terminal (module docstring)."""
        return (self.seconds or 0.0) >= CONFIRM_S or self.disk_bytes >= CONFIRM_BYTES

    def line(self) -> str:
        """The estimate in one line."""
        where = f" at {self.points} parameter points" if self.points > 1 else ""
        if self.seconds is None:
            time_text = f"time not estimated (the {self.backend} backend)"
        else:
            time_text = (f"labelling about {_duration(self.seconds)} on this machine "
                         f"(measured on {self.sample} of its orbits; the per-point "
                         "preparation extra)")
        return (f"atlas: {_count(self.orbits)} orbits{where}, {time_text}, up to "
                f"{human_size(self.disk_bytes)} on disk")


def _count(n: int) -> str:
    return f"{n / 1e9:.3g} G" if n >= 1e9 else f"{n / 1e6:.3g} M" if n >= 1e6 else f"{n:,}"


def _duration(s: float) -> str:
    if s < 90:
        return f"{s:.2g} s"
    if s < 5400:
        return f"{s / 60:.2g} min"
    return f"{s / 3600:.2g} h"


def orbits_of(layout: Layout, tiles) -> int:
    """The orbits of the tiles ``tiles`` of ``layout`` (indices)."""
    return sum(layout.tile(i)[1].stop - layout.tile(i)[1].start for i in tiles) \
        * layout.x0.size


def measure_rate(cfg: Config, layout: Layout, begun: list, seed: int = 0
                 ) -> tuple[float, int]:
    """(orbits per second, orbits timed): the rate at which this machine's CPU labels the
    run's orbits, from seeded samples of stretches of :data:`STRETCH` consecutive θ0 of
    random grid rows (as a tile holds them), labelled with the run's kernels (the model's
    sample of each point from ``begun``: :class:`atlas.models.base.Planner`).

    A first, untimed call of :data:`FIRST_SAMPLE` orbits at each point timed loads (or
    compiles) the kernels the timed calls take (it stops at the first trap test, so costs
    little; a smaller one would load another kernel: :func:`atlas.kernels.lanes.n_chunks`,
    and time the compilation of the one the timed calls take). The sample grows from
    :data:`FIRST_SAMPLE` orbits (aimed at the rate seen, at most fourfold:
    :func:`_next_sample`) until one call takes :data:`CALL_S` s (or
    :data:`MAX_SAMPLE` orbits), at one random parameter point, then is labelled as large at
    up to :data:`MAX_POINTS` − 1 further random points. A call's fixed cost (starting the
    threads: tens of ms on a busy machine, which a run's big tiles pay once each) is measured
    by the same call stopped at its first trap test, and taken off."""
    rng = np.random.default_rng(seed)
    width = min(STRETCH, layout.x0.size)

    def sample(n: int) -> tuple[np.ndarray, np.ndarray]:
        k = -(-n // width)
        rows = rng.integers(layout.v0.size, size=k)
        cols = rng.integers(layout.x0.size - width + 1, size=k)
        return (layout.x0[cols[:, None] + np.arange(width)].ravel(),
                np.repeat(layout.v0[rows], width))

    def seconds(p: int, orbits: tuple, t_max: float = cfg.integrator.t_max) -> float:
        labeller = planner(layout.model).sample(cfg, begun, p)
        start = time.perf_counter()
        labeller.label(*orbits, t_max=t_max)
        return time.perf_counter() - start

    points = [int(p) for p in rng.permutation(layout.n_params)[:MAX_POINTS]]
    for p in points:  # untimed: load (or compile) every kernel the timed calls take, which
        # a batch's size chooses (one chunk runs a serial twin: atlas.kernels.lanes)
        seconds(p, sample(FIRST_SAMPLE), t_max=cfg.integrator.dt)
    n = FIRST_SAMPLE
    while True:
        first = sample(n)
        spent = [seconds(points[0], first)]
        if spent[0] >= CALL_S or n >= MAX_SAMPLE:
            break
        n = _next_sample(n, spent[0])
    spent += [seconds(p, sample(n)) for p in points[1:]]
    fixed = seconds(points[0], first, t_max=cfg.integrator.dt)
    work = sum(spent) - fixed * len(spent)
    timed = len(spent) * first[0].size
    return timed / max(work, 0.1 * sum(spent)), timed


def _next_sample(n: int, spent: float) -> int:
    """The calibration's next sample size after ``n`` orbits took ``spent`` s (< CALL_S):
    aimed at a call of 1.25·CALL_S at the rate just seen (so more than 1.25·n), at most four
    times ``n`` and MAX_SAMPLE (the sample rounds it up to whole stretches). Aimed rather
    than fourfold, the last call takes about CALL_S instead of up to four times it, as do
    the MAX_POINTS − 1 calls of its size that follow."""
    aimed = n * 1.25 * CALL_S / spent if spent > 0.0 else 4.0 * n
    return math.ceil(min(aimed, 4.0 * n, MAX_SAMPLE))


def estimate(cfg: Config, layout: Layout, begun: list, orbits: int, device: str,
             backend: str) -> Estimate:
    """The :class:`Estimate` of labelling ``orbits`` orbits of ``layout`` on ``device``
    ("cpu", "cuda"; ``backend`` the run's word), its time measured only where the run may be
    big (module docstring)."""
    steps = orbits * cfg.integrator.t_max / cfg.integrator.dt
    seconds, sample = None, 0
    if device == "cpu" and orbits and (orbits >= PREFLIGHT_ORBITS or steps >= CALIBRATE_STEPS):
        rate, sample = measure_rate(cfg, layout, begun)
        seconds = orbits / rate
    return Estimate(orbits=orbits, points=layout.n_params, seconds=seconds, sample=sample,
                    disk_bytes=label_bytes(layout), backend=backend)


def ask(yes: bool = False, quiet: bool = False, stdin=None) -> Callable[[Estimate], bool]:
    """The command line's ``confirm`` for :func:`atlas.pipeline.sweep.run`, called for a run
    that :attr:`Estimate.asks` and responsible for saying its line: True (start) where ``yes``
    (``--yes``) or stdin is not a terminal (the line then says so; nothing said where
    ``quiet``), else the user's answer to the line and "Start? [y/N]" (no answer, Ctrl-D or
    Ctrl-C: no). Its ``silent`` is True where it would start without a word (``quiet``, and
    ``yes`` or stdin not a terminal): a run need not estimate at all then."""
    from atlas.pipeline.progress import say

    def confirm(est: Estimate) -> bool:
        inp = stdin if stdin is not None else sys.stdin
        if yes or not _is_terminal(inp):
            if not quiet:
                say(est.line() + ("" if yes else
                                  "; stdin is not a terminal: starting without asking"))
            return True
        print(f"{est.line()}. Start? [y/N] ", end="", file=sys.stderr, flush=True)
        try:
            answer = inp.readline()
        except KeyboardInterrupt as exc:
            if type(exc) is not KeyboardInterrupt:  # SIGTERM (atlas.cli): stopped, not "no"
                raise
            answer = ""
        return answer.strip().lower() in ("y", "yes")

    # quiet, and no question to put: the estimate would be neither said nor asked about
    confirm.silent = quiet and (yes or not _is_terminal(stdin if stdin is not None
                                                        else sys.stdin))
    return confirm


def _is_terminal(stream) -> bool:
    """Whether ``stream`` is an open terminal (stdin may be None, or closed, in a daemon or
    a job started with ``<&-``: not a terminal)."""
    try:
        return bool(stream is not None and not stream.closed and stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False
