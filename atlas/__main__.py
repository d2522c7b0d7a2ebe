"""``python -m atlas``: the ``atlas`` command line (:mod:`atlas.cli`)."""

import sys

from .cli import main

sys.exit(main())
