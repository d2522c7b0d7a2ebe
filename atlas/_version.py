"""The version of atlas, written once: the package's ``__version__``, the distribution's
version (``pyproject.toml`` reads it from here: ``dynamic = ["version"]``), ``atlas
--version``, and every file's ``atlas_version`` attribute. Semantic versioning; what changed
in each version is in ``CHANGELOG.md``."""

__version__ = "0.1.0"
