"""A Griffe extension for the API reference (mkdocs.yml): atlas's docstrings name other
objects with Sphinx roles (:func:`label`, :mod:`atlas.store.reader`), which Markdown would
print as they stand; this shows each as the code it names."""

from __future__ import annotations

import re

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|class|mod|meth|attr|data|obj|exc|const):`~?([^`]+)`")


class SphinxRoles(griffe.Extension):
    """:role:`target` → `target` in every docstring the reference loads."""

    def on_object(self, *, obj: griffe.Object, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = ROLE.sub(r"`\1`", obj.docstring.value)
