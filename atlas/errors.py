"""atlas's exceptions: each carries one line that names the culprit (a key, a file, a backend).

Failures become messages in one place, the CLI (:func:`atlas.cli.main`), which prints
``atlas: error: <message>`` for any :class:`AtlasError` and exits with its ``exit_code``:

* **2** — bad input (:class:`AtlasError` itself and :class:`ConfigError`,
  :class:`InputFileError`, :class:`OutputInTheWay`, :class:`BackendUnavailable`): nothing
  was created or overwritten;
* **1** — a failure of the environment during a run (:class:`EnvironmentFailure`:
  :class:`StorageError`, a disk full or a write refused; :class:`SeparatrixError`): the
  finished tiles are kept and running the same command again continues;
* **3** — the output is locked by another run (:class:`atlas.pipeline.lock.OutputLocked`, an
  :class:`EnvironmentFailure` too);
* **4** — :data:`EXIT_INEXACT`: a run finished and wrote its file, but an accuracy check
  exceeded its bound (the traced separatrices farther from the DOP853 stable manifold than
  the bound the certificate assumes); ``atlas run --accept-inexact`` exits 0 instead. Not an
  exception: the work is kept and the CLI says so (:func:`atlas.pipeline.sweep.accuracy_exit`).

Ctrl-C and SIGTERM are not errors: the CLI exits 130 and 143 (:class:`Terminated`).
"""

#: Exit status of bad input.
EXIT_BAD_INPUT = 2
#: Exit status of a failure of the environment during a run (disk full, write refused).
EXIT_ENVIRONMENT = 1
#: Exit status of a run whose file was written but whose accuracy check exceeded its bound.
EXIT_INEXACT = 4


class AtlasError(Exception):
    """Bad input (exit status 2) or, in the subclasses that say so, an unusable environment,
    reported to the user as one clear line."""

    exit_code = EXIT_BAD_INPUT


class ConfigError(AtlasError, ValueError):
    """A config file that cannot be read or does not validate."""


class InputFileError(AtlasError):
    """A file given to atlas (``atlas info``/``plot``/``view``/``orbit``, :func:`atlas.open`)
    that it cannot use: missing, unreadable, not an atlas, or failing the schema check."""


class OutputInTheWay(AtlasError):
    """An output path that holds something atlas must not write over: the config being run,
    or an existing file that atlas did not write (``--force`` writes over the latter)."""


class BackendUnavailable(AtlasError, RuntimeError):
    """A requested backend (CUDA, Dask) that is not installed or has no device."""


class EnvironmentFailure(AtlasError):
    """The environment failed a run that was asked for correctly (exit status 1 unless a
    subclass says otherwise); finished tiles are kept."""

    exit_code = EXIT_ENVIRONMENT


class StorageError(EnvironmentFailure):
    """Writing the output failed mid-run (disk full, I/O error); finished tiles are kept."""


class SeparatrixError(EnvironmentFailure, RuntimeError):
    """A separatrix that cannot be certified during a run (a bracket that meets a third basin
    or finds no certified label, a branch with too many vertices, a failed DOP853 reference):
    one line naming the point or branch and what to change."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, turned into an exception so that it stops a run like Ctrl-C does."""
