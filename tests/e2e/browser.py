"""A headless Chromium page for the browser tests: Debian's ``/usr/bin/chromium`` driven by Playwright.

Playwright cannot download its own browsers here, so it drives the system
package (``make test`` installs it when it is missing: ``tools/test-prerequisites``). A missing Chromium is a
failure, not a skip. Each test gets a fresh profile under its temporary
directory and a page that records what the browser did: every request URL
(WebSockets included), every answer of 400 or more, every console error and
uncaught exception.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import (
    ConsoleMessage,
    Page,
    Response,
    ViewportSize,
    WebSocket,
    sync_playwright,
)

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
]
VIEWPORT: ViewportSize = {"width": 1400, "height": 850}
WAIT_MS = 20_000
"""Longest wait for the page to show something (a slow shared machine, not a timing claim)."""


@dataclass
class BrowserLog:
    """What the page asked for and what went wrong in it."""

    requests: list[str] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)
    console_errors: list[str] = field(default_factory=list)

    def on_console(self, message: ConsoleMessage) -> None:
        if message.type == "error":
            self.console_errors.append(message.text)

    def on_page_error(self, error: Exception) -> None:
        self.console_errors.append(f"uncaught: {error}")

    def on_response(self, response: Response) -> None:
        if response.status >= 400:
            self.failures.append(f"{response.status} {response.url}")

    def on_websocket(self, socket: WebSocket) -> None:
        self.requests.append(socket.url)


@dataclass
class BrowserPage:
    """A Playwright page and its log."""

    page: Page
    log: BrowserLog


@pytest.fixture
def browser_page(tmp_path: Path) -> Iterator[BrowserPage]:
    """A page of a fresh headless Chromium (its profile in the test's tmp dir)."""
    assert CHROMIUM.exists(), (
        f"{CHROMIUM} is missing: the browser tests need Debian's chromium "
        "(apt-get install -y chromium; `make test` installs it: tools/test-prerequisites)"
    )
    with sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            tmp_path / "chromium-profile",
            executable_path=CHROMIUM,
            headless=True,
            args=CHROMIUM_ARGS,
            viewport=VIEWPORT,
        )
        try:
            page = context.pages[0] if context.pages else context.new_page()
            page.set_default_timeout(WAIT_MS)
            log = BrowserLog()
            page.on("console", log.on_console)
            page.on("pageerror", log.on_page_error)
            page.on("request", lambda request: log.requests.append(request.url))
            page.on("response", log.on_response)
            page.on("websocket", log.on_websocket)
            yield BrowserPage(page=page, log=log)
        finally:
            context.close()


def viewer_state(page: Page) -> dict[str, Any]:
    """The viewer's own account of what it draws (``window.__viewer.state()``)."""
    state = page.evaluate("window.__viewer.state()")
    assert isinstance(state, dict)
    return state


def wait_for_seq(page: Page, seq: int) -> dict[str, Any]:
    """Wait until the page shows ``seq`` (in its status line) and return its state."""
    page.wait_for_function(
        "seq => document.getElementById('seq').textContent === String(seq)", arg=seq
    )
    return viewer_state(page)
