"""What a run says while it works (atlas.pipeline.progress): the phases' bars, the compiling
line on a cold kernel cache, and when either is shown."""

from __future__ import annotations

import io
import logging
import subprocess
import sys
import textwrap

import pytest

from atlas.pipeline import progress
from tests.helpers import REPO

_KERNELS = '''
import numba
from atlas.kernels import cached_njit


@cached_njit()
def cached_twice(x):
    return 2 * x


@numba.njit
def plain_thrice(x):
    return 3 * x
'''

_PROBE = '''
import sys
sys.path.insert(0, sys.argv[1])
from atlas.kernels import on_cold_compile
import probe_kernels
seen = []
with on_cold_compile(seen.append):
    probe_kernels.cached_twice(1.5)
    probe_kernels.plain_thrice(1.5)
print(",".join(seen))
'''


@pytest.mark.slow
def test_a_cold_cache_is_reported_and_a_warm_one_is_not(tmp_path):
    """Two fresh processes call a kernel of cached_njit and a plain njit function with an
    empty Numba cache: the first compiles (reported: the cached kernel only, the plain one
    compiles in every process), the second loads machine code from the cache (nothing)."""
    (tmp_path / "probe_kernels.py").write_text(_KERNELS)
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PATH": "/usr/bin:/bin"}

    def seen():
        proc = subprocess.run([sys.executable, "-c", _PROBE, str(tmp_path)], cwd=REPO,
                              env=env, capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout.strip()

    assert seen() == "cached_twice"
    assert seen() == ""


class _Stream(io.StringIO):
    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self):
        return self.tty


@pytest.mark.parametrize(("quiet", "tty", "level", "shown"), [
    (False, True, logging.WARNING, True),
    (True, True, logging.INFO, False),  # --quiet wins, also over -v
    (False, False, logging.WARNING, False),  # a log file or a pipe: nothing
    (False, False, logging.INFO, True),  # ... unless -v
])
def test_who_sees_progress(quiet, tty, level, shown, monkeypatch, request):
    import atlas.kernels.lanes  # noqa: F401 (kernels of cached_njit)

    stream = _Stream(tty)
    monkeypatch.setattr(sys, "stderr", stream)
    logger = logging.getLogger("atlas")
    request.addfinalizer(lambda old=logger.level: logger.setLevel(old))
    logger.setLevel(level)  # (setLevel, not the attribute: it clears the cached levels)
    assert progress.watched(quiet) is shown
    assert list(progress.tracked(range(3), 3, "separatrices", quiet)) == [0, 1, 2]
    assert ("separatrices" in stream.getvalue()) is shown
    with progress.compile_notice(quiet):
        from numba.core import event

        from atlas.kernels import _CACHED

        kernel = next(iter(_CACHED))  # as Numba announces a compilation after a cache miss
        with event.trigger_event("numba:compile", data={"dispatcher": kernel}):
            pass
        with event.trigger_event("numba:compile", data={"dispatcher": kernel}):
            pass  # said once
    assert stream.getvalue().count(progress.COMPILING) == int(shown)


def test_every_per_point_phase_has_a_bar(tmp_path, monkeypatch):
    """The slow per-point phases (exact boundaries, separatrices, certificates) each advance
    a bar over the parameter points, besides the tiles' bar over orbits."""
    import atlas
    from tests.helpers import write_config

    cfg = atlas.load_config(write_config(tmp_path / "c.yaml", textwrap.dedent(f"""\
        pendulum: {{alpha: [0.4, 0.5], omega0: 1.0}}
        grid:
          theta0: {{start: -pi, stop: pi, num: 8}}
          theta_dot0: {{start: -2, stop: 2, num: 6}}
        integrator: {{dt: 0.01, t_max: 60}}
        separatrices: {{enabled: true, tol: 1.0e-8, max_spacing: 0.5}}
        output: {tmp_path / "bars.h5"}
        """)))
    phases, bars = [], []
    real_tracked, real_bar = progress.tracked, progress.bar

    def tracked(items, total, desc, quiet, unit="point"):
        taken = list(real_tracked(items, total, desc, quiet, unit))
        phases.append((desc, total, len(taken)))
        yield from taken

    def bar(total, desc, unit, quiet, initial=0):
        bars.append((desc, unit, total))
        return real_bar(total, desc, unit, quiet, initial)

    monkeypatch.setattr(progress, "tracked", tracked)
    monkeypatch.setattr(progress, "bar", bar)
    atlas.run(cfg, quiet=True)
    assert phases == [("exact boundaries", 2, 2), ("separatrices", 2, 2),
                      ("certificates", 2, 2)]
    assert ("tiles", "orbit", 2 * 8 * 6) in bars
