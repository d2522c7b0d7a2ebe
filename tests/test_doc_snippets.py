"""The Python snippets of the README and the docs are run, so that they cannot rot.

Every fenced block whose info string is ``python`` (or ``py``) in ``README.md`` and
``docs/**/*.md`` runs, the blocks of one page in order in one namespace (a later block may use
the names of an earlier one), in a folder laid out as a checkout after ``make run`` and
``make stability``: the repository's ``configs/`` as shipped, ``outputs/default.h5`` (the
atlas of ``configs/default.yaml``) and ``outputs/swing_stability.h5`` (the study of
``configs/swing_stability.yaml``). A block written as an interactive session (its first line starts
with ``>>>``) runs as a doctest: what it prints must be what the page shows
(``NORMALIZE_WHITESPACE`` and ``ELLIPSIS``: ``...`` stands for any text). Other blocks must
run without an exception.

A block that must not run (one that needs a GPU, a cluster, a browser, or shows an error on
purpose) is marked by an HTML comment on the line before its fence, which renders as nothing:

    <!-- no-test -->
    ```python
    atlas.run(cfg, backend="cuda")
    ```
"""

from __future__ import annotations

import doctest
import io
import re
import shutil
from pathlib import Path

import pytest

from tests.helpers import REPO

#: The marker, on the line before a fence, of a block that is shown but not run.
NO_TEST = "<!-- no-test -->"
_FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`\s]*)")


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(line number of the first code line, code) of each fenced ``python``/``py`` block of a
    Markdown ``text`` not marked :data:`NO_TEST` on the line before its opening fence."""
    blocks, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        opening = _FENCE.match(lines[i])
        if not opening:
            i += 1
            continue
        fence, start = opening["fence"], i + 1
        closing = re.compile(rf" {{0,3}}{re.escape(fence[0])}{{{len(fence)},}}\s*")
        end = start
        while end < len(lines) and not closing.fullmatch(lines[end]):
            end += 1
        marked = i > 0 and lines[i - 1].strip() == NO_TEST
        if opening["info"].lower() in ("python", "py") and not marked:
            indent = len(opening["indent"])
            blocks.append((start + 1, "\n".join(line[indent:] if line[:indent].isspace()
                                                else line for line in lines[start:end])))
        i = end + 1
    return blocks


def _pages() -> list[Path]:
    return [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]


def _pages_with_snippets() -> list[Path]:
    return [page for page in _pages() if python_blocks(page.read_text(encoding="utf-8"))]


def test_blocks_are_found_and_the_marker_leaves_one_out():
    text = "\n".join([
        "# A page", "```python", "x = 1", "```", "", NO_TEST, "```python", "raise SystemExit",
        "```", "```console", "$ atlas run", "```", "~~~py", "y = x + 1", "```inside", "~~~",
        "   ```python", "   z = 2", "   ```"])
    assert python_blocks(text) == [(3, "x = 1"), (14, "y = x + 1\n```inside"), (18, "z = 2")]
    # a closing fence is as long as the opening one at least, and has no info string
    assert python_blocks("````python\na = 1\n```python\n````") == [(2, "a = 1\n```python")]


@pytest.fixture(scope="module")
def checkout(tmp_path_factory) -> Path:
    """A folder like a checkout after ``make run`` and ``make stability`` (module
    docstring)."""
    import atlas
    from atlas.commands.stability import run_study

    root = tmp_path_factory.mktemp("checkout")
    shutil.copytree(REPO / "configs", root / "configs")
    (root / "outputs").mkdir()
    atlas.run(atlas.load_config(root / "configs" / "default.yaml",
                                output=root / "outputs" / "default.h5"), quiet=True)
    run_study(root / "configs" / "swing_stability.yaml",
              output=root / "outputs" / "swing_stability.h5")
    return root


def run_block(code: str, where: str, namespace: dict) -> None:
    """Run one block in ``namespace``: a session (``>>>``) as a doctest whose printed lines
    must match, other code as a program; AssertionError naming ``where`` if it fails."""
    if not code.lstrip().startswith(">>>"):
        exec(compile(code, where, "exec"), namespace)  # the docs' own code
        return
    test = doctest.DocTestParser().get_doctest(code, namespace, where, where, 0)
    report = io.StringIO()
    runner = doctest.DocTestRunner(
        optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    result = runner.run(test, out=report.write, clear_globs=False)
    namespace.update(test.globs)  # a DocTest runs in a copy of the namespace it is given
    assert result.failed == 0, f"{where}: the session prints otherwise\n{report.getvalue()}"


def test_a_session_block_must_print_what_it_shows():
    namespace = {}
    run_block(">>> x = 6 * 7\n>>> print(f'x = {x}')\nx = 42\n>>> [x] * 40\n[42, 42, ...]",
              "page.md:1", namespace)
    assert namespace["x"] == 42  # the namespace is kept for the page's next block
    with pytest.raises(AssertionError, match="page.md:9"):
        run_block(">>> print(6 * 9)\n42", "page.md:9", {})


@pytest.mark.slow  # the default atlas (512² orbits), the 1,001-point study, the pages' runs
@pytest.mark.parametrize("page", _pages_with_snippets(),
                         ids=lambda page: str(page.relative_to(REPO)))
def test_the_python_snippets_of_a_page_run(page, checkout, tmp_path, monkeypatch):
    """Each page's snippets run, in order, in a copy of the checkout (what one page's
    snippets write does not reach another's)."""
    work = tmp_path / "checkout"
    shutil.copytree(checkout, work)
    monkeypatch.chdir(work)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace = {"__name__": "__snippet__"}
    for line, code in python_blocks(page.read_text(encoding="utf-8")):
        run_block(code, f"{page.relative_to(REPO)}:{line}", namespace)
