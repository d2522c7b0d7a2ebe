"""atlas's exceptions: each carries one line that names the culprit (a key, a file, a backend).

The CLI prints ``atlas: error: <message>`` for any :class:`AtlasError` and exits with status 2
(bad input) or the error's ``exit_code`` (1 for a fault during a run, 3 for an output locked
by another run).
"""


class AtlasError(Exception):
    """Bad input or an unusable environment, reported to the user as one clear line."""


class ConfigError(AtlasError, ValueError):
    """A config file that cannot be read or does not validate."""


class InputFileError(AtlasError):
    """A file given to atlas (``atlas info``/``atlas plot``/``--resume``) that it cannot use."""


class BackendUnavailable(AtlasError, RuntimeError):
    """A requested backend (CUDA, Dask) that is not installed or has no device."""


class StorageError(AtlasError):
    """Writing the output failed mid-run (disk full, I/O error); finished tiles are kept."""

    exit_code = 1


class SeparatrixError(AtlasError, RuntimeError):
    """A separatrix that cannot be certified during a run (a bracket that meets a third basin
    or finds no certified label, a branch with too many vertices, a failed DOP853 reference):
    one line naming the point or branch and what to change."""

    exit_code = 1


class Terminated(KeyboardInterrupt):
    """SIGTERM, turned into an exception so that it stops a run like Ctrl-C does."""
