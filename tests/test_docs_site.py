"""The quick start and the docs site cannot rot: the README's links resolve and it stays a
quick start (its Python snippets are run by tests/test_doc_snippets.py). (The strict build
of the site itself, which checks every link, anchor and API reference under docs/, is
`make docs`, run by `make test` before pytest.)

What the printed numbers are worth is tested elsewhere against independent references (exact
areas against a Monte-Carlo estimate, labels against DOP853: tests/boundaries, tests/labels);
here they are the documentation's, held to the code so that an edit of either shows.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
LINK = re.compile(r"\]\(([^)\s]+)\)")


def _blocks(text: str, language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", text, re.S)


@pytest.mark.parametrize("page", [README, *sorted((REPO / "docs").rglob("*.md"))],
                         ids=lambda p: str(p.relative_to(REPO)))
def test_relative_links_resolve(page):
    """Every relative link of the README and of the docs' pages names a file that exists
    (and, for a link into a Markdown page, a heading that exists there)."""
    broken = []
    for target in LINK.findall(page.read_text(encoding="utf-8")):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve()
        if not file.exists():
            broken.append(target)
        elif anchor and file.suffix == ".md":
            slugs = {re.sub(r"[^\w\- ]", "", h).strip().lower().replace(" ", "-")
                     for h in re.findall(r"^#+ (.+)$", file.read_text(encoding="utf-8"), re.M)}
            if anchor not in slugs:
                broken.append(target)
    assert broken == []


def test_readme_is_a_quick_start():
    """About 200 lines, with the two commands, a picture of the basins, one of basin
    stability against the torque and one of the driven pendulum's basins, one config and
    the file read back."""
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 220
    assert "make run" in text and "make test" in text
    assert len(re.findall(r"!\[[^]]*\]\(", text)) == 3
    assert len(_blocks(text, "yaml")) == 1 and len(_blocks(text, "python")) == 2
