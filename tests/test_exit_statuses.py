"""Every exit status the code defines is listed where a user looks for it: the reliability
page, the README and ``atlas --help``. The statuses are read from the sources (each
``EXIT_… = N`` and each literal ``exit_code = N``), so a new one cannot be forgotten (the
reliability page once lacked 4)."""

from __future__ import annotations

import re

from tests.helpers import REPO


def _defined() -> set[int]:
    """0, and every status that atlas's sources name."""
    found = {0}
    for source in (REPO / "atlas").rglob("*.py"):
        text = source.read_text()
        found |= {int(n) for n in re.findall(r"^\s*EXIT_[A-Z_]+\s*=\s*(\d+)\s*$", text, re.M)}
        found |= {int(n) for n in re.findall(r"^\s*exit_code\s*=\s*(\d+)\s*$", text, re.M)}
    return found


def _paragraph(text: str, opening: str) -> str:
    """The paragraph of ``text`` that holds ``opening``, from there to the next blank line."""
    start = text.index(opening)
    end = text.find("\n\n", start)
    return text[start:end if end >= 0 else None]


def _bold_numbers(text: str) -> set[int]:
    return {int(n) for n in re.findall(r"\*\*(\d+)\*\*", text)}


def test_the_sources_define_the_statuses_we_know_of():
    """A check on the reader of the sources: it finds the statuses of atlas.errors, the lock
    and the CLI (were it to find none, the tests below would pass on nothing)."""
    from atlas import cli, errors
    from atlas.pipeline.lock import EXIT_LOCKED

    known = {0, errors.EXIT_ENVIRONMENT, errors.EXIT_BAD_INPUT, EXIT_LOCKED,
             errors.EXIT_INEXACT, cli.EXIT_INTERRUPTED, cli.EXIT_TERMINATED}
    assert known <= _defined()


def test_the_reliability_page_lists_every_exit_status():
    page = (REPO / "docs" / "reliability.md").read_text()
    assert _bold_numbers(_paragraph(page, "Exit statuses of `atlas`:")) == _defined()


def test_the_readme_lists_every_exit_status():
    readme = (REPO / "README.md").read_text()
    assert _bold_numbers(_paragraph(readme, "Exit statuses of `atlas`:")) == _defined()


def test_atlas_help_lists_every_exit_status():
    from atlas.cli import build_parser

    epilog = build_parser().epilog
    listed = epilog[epilog.index("Exit status:"):epilog.index("`atlas COMMAND")]
    assert {int(n) for n in re.findall(r"\b\d+\b", listed)} == _defined()
