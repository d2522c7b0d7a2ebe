"""The architecture as written down (docs/design/architecture.md) against the package: every
module in the map, and no import circle anywhere (the folder rules themselves are
import-linter's contracts in pyproject.toml, run by `make test`)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def test_architecture_module_map_matches_the_package():
    """Every module of the package has a row in docs/design/architecture.md's map, every row
    names a module that exists, and the README links the map."""
    doc = (REPO / "docs" / "design" / "architecture.md").read_text()
    table = doc[doc.index("## Modules"):]
    named = set(re.findall(r"`atlas/([\w/]+\.py)`", table))
    # every module but the packages' one-line __init__ files (kernels/__init__.py has content)
    modules = {str(p.relative_to(REPO / "atlas")) for p in (REPO / "atlas").rglob("*.py")
               if p.name != "__init__.py" or p.parent.name == "kernels"}
    assert modules - named == set(), "modules missing from docs/design/architecture.md"
    assert {n for n in named if not (REPO / "atlas" / n).exists()} == set()
    assert "docs/design/architecture.md" in (REPO / "README.md").read_text()


def test_no_module_imports_itself_back():
    """No import circle between any two modules of the package (grimp: import-linter's own
    import graph)."""
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("atlas")
    circles = sorted({tuple(sorted((a, b))) for a in graph.modules
                      for b in graph.find_modules_directly_imported_by(a)
                      if b != a and graph.chain_exists(b, a)})
    assert circles == []


def _sources(*skip: str):
    """(path relative to atlas/, text) of every module of the package but ``skip``."""
    for path in sorted((REPO / "atlas").rglob("*.py")):
        name = str(path.relative_to(REPO / "atlas"))
        if name not in skip:
            yield name, path.read_text()


def test_the_exact_boundaries_are_reached_through_their_protocol_only():
    """No module asks which implementation of ExactBoundaries it holds (isinstance) or reaches
    into the tilted one's insides (``.tilted``), but the implementations' own family:
    exact.py, tilted.py and the tilted trace. What studies and traces need is in the
    protocol (``has_boundary``, ``traced_as``, ``cycle``, ``basin_outline``)."""
    implementations = r"(UntiltedExact|TiltedExact|UnboundedExact)"
    found = [name for name, text in _sources("boundaries/exact.py", "boundaries/tilted.py",
                                             "boundaries/trace_tilted.py")
             if re.search(rf"isinstance\([^)]*{implementations}", text)
             or re.search(r"(?<!atlas\.boundaries)\.tilted\.\w", text)]
    assert found == []


def test_no_module_imports_a_private_name_of_another():
    """``from atlas.x import _name`` nowhere in the package: what another module needs of a
    module is public (and documented as such)."""
    import ast

    found = [f"{name}: {node.module}.{alias.name}"
             for name, text in _sources()
             for node in ast.walk(ast.parse(text))
             if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("atlas")
             for alias in node.names
             if alias.name.startswith("_") and not alias.name.startswith("__")]
    assert found == []
