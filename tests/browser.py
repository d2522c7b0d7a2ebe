"""A headless Chromium for the page tests (``tests/views/test_view.py``), driven by Playwright.

Playwright drives the Chromium-family browser already on the machine (``executable_path``):
Debian's ``chromium``, or ``$ATLAS_BROWSER``. It never downloads a browser build of its own
(``playwright install`` is not needed and is not run). :class:`WatchedPage` adds what the
tests check besides the page's own answers: every JavaScript dialog the page opened (each is
accepted, so a page never hangs on one) and every uncaught error or ``console.error``.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome")
FLAGS = ("--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
         "--disable-background-networking", "--mute-audio")


def find_browser() -> str | None:
    """A Chromium-family executable: $ATLAS_BROWSER, else the first on PATH."""
    explicit = os.environ.get("ATLAS_BROWSER")
    if explicit:
        return explicit if os.access(explicit, os.X_OK) else None
    for name in CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    return None


def playwright_missing() -> str | None:
    """Why Playwright cannot be used here (its package is not installed), or None."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError as exc:
        return f"the playwright package is not installed ({exc}; pip install -e '.[dev]')"
    return None


def skip_without_browser():
    """The pytest mark of the tests that need the browser: skipped, with the reason, where
    there is no Chromium-family browser or no Playwright, except where $ATLAS_REQUIRE_BROWSER
    is set (CI, .ci/run, installs a browser and sets it: there a missing one fails)."""
    import pytest

    missing = playwright_missing()
    return pytest.mark.skipif(
        (find_browser() is None or missing is not None)
        and not os.environ.get("ATLAS_REQUIRE_BROWSER"),
        reason=missing or "no Chromium-family browser found (install Debian's chromium: "
        "apt-get install chromium, or set ATLAS_BROWSER); the page itself is still tested "
        "without one")


@dataclass
class WatchedPage:
    """A Playwright page, with the dialogs it opened and the errors it reported since the last
    :meth:`goto`."""

    page: object  # playwright.sync_api.Page
    dialogs: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def __post_init__(self):
        self.page.on("dialog", self._dialog)
        self.page.on("pageerror", lambda exc: self.errors.append(str(exc)))
        self.page.on("console", lambda msg: self.errors.append(msg.text)
                     if msg.type == "error" else None)

    def _dialog(self, dialog) -> None:
        self.dialogs.append(dialog.message)
        dialog.accept()  # answer it, or the page would hang; the test sees the record

    def goto(self, url: str) -> None:
        """Load ``url`` (until its load event) with fresh records of dialogs and errors."""
        self.dialogs.clear()
        self.errors.clear()
        self.page.goto(url, wait_until="load")

    def evaluate(self, expression: str):
        """The JSON value of a JavaScript expression (promises awaited)."""
        return self.page.evaluate(expression)

    def click(self, x: float, y: float) -> None:
        """A left click at the viewport point (x, y) [CSS pixels]."""
        self.page.mouse.click(x, y)


@contextmanager
def headless_page(executable: str, width: int = 1220, height: int = 640) -> Iterator[WatchedPage]:
    """One headless ``executable`` with one page of ``width`` × ``height`` CSS pixels."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, headless=True,
                                             args=list(FLAGS))
        try:
            page = browser.new_page(viewport={"width": width, "height": height},
                                    device_scale_factor=1)
            yield WatchedPage(page)
        finally:
            browser.close()
