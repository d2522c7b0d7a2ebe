"""``python -m atlas``: the ``atlas`` command line (:mod:`atlas.cli`)."""

from .cli import entry

entry()
