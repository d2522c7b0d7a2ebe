"""``python -m atlas``: the ``atlas`` command line (:mod:`atlas.cli`)."""

from atlas.cli import entry

entry()
