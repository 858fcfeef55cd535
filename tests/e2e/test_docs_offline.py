"""``/docs`` and ``/redoc`` draw every operation with no request leaving the machine.

Headless Chromium loads both pages with every request to a host other than
the live server's blocked (Playwright route interception): a page that needs
a CDN draws nothing, and the blocked request is listed.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import urlsplit

import httpx
from playwright.sync_api import Route

from tests.api.conftest import LiveServer
from tests.e2e.browser import BrowserPage

LOOPBACK = {"127.0.0.1", "localhost", "::1"}
HTTP_METHODS = {"get", "put", "post", "delete", "patch", "head", "options", "trace"}


def operations(server: LiveServer) -> list[tuple[str, str]]:
    """(method, path) of every operation in the served ``openapi.json``."""
    document = httpx.get(f"{server.url}/openapi.json").json()
    return [
        (method.upper(), path)
        for path, item in document["paths"].items()
        for method in item
        if method in HTTP_METHODS
    ]


def test_docs_and_redoc_load_offline(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    page, log = browser_page.page, browser_page.log
    blocked: list[str] = []

    def loopback_only(route: Route) -> None:
        if urlsplit(route.request.url).hostname in LOOPBACK:
            route.continue_()
        else:
            blocked.append(route.request.url)
            route.abort()

    page.route("**/*", loopback_only)
    documented = operations(live_server)
    assert len(documented) >= 10

    page.goto(f"{live_server.url}/docs")
    page.wait_for_function(
        "n => document.querySelectorAll('#swagger-ui .opblock').length === n", arg=len(documented)
    )
    drawn = {
        (
            block.locator(".opblock-summary-method").inner_text(),
            block.locator(".opblock-summary-path").inner_text().replace("\u200b", ""),
        )
        for block in page.locator("#swagger-ui .opblock").all()
    }
    assert drawn == set(documented)
    page.wait_for_load_state("networkidle")  # what the page asks for once drawn is asked for too

    page.goto(f"{live_server.url}/redoc")
    page.wait_for_function(
        "n => document.querySelectorAll('[data-section-id^=\"operation/\"]').length === n",
        arg=len(documented),
    )
    page.wait_for_load_state("networkidle")
    page.screenshot(path=tmp_path / "redoc.png")

    assert blocked == []
    local = (live_server.url, f"blob:{live_server.url}")
    assert all(url.startswith(local) for url in log.requests), log.requests
    assert not log.failures, log.failures
    assert not log.console_errors, log.console_errors
    icon = httpx.get(f"{live_server.url}/favicon.ico")
    assert icon.status_code == 200 and icon.headers["content-type"] == "image/png"
    assert icon.content.startswith(b"\x89PNG")


def test_try_it_out_creates_a_session_from_the_documented_example(
    live_server: LiveServer, browser_page: BrowserPage
) -> None:
    """ "Try it out → Execute" on ``POST /v1/sessions`` in ``/docs``, as a user clicks it:
    Swagger UI sends the first request example, and the service answers 201."""
    page = browser_page.page
    page.goto(f"{live_server.url}/docs")
    operation = page.locator("#operations-sessions-create_session")
    operation.locator(".opblock-summary").click()
    operation.locator(".try-out__btn").click()
    operation.locator(".execute").click()
    status = operation.locator(".live-responses-table .response .response-col_status").first
    status.wait_for()
    assert status.inner_text().strip() == "201", operation.locator(
        ".live-responses-table"
    ).inner_text()
    body = operation.locator(".live-responses-table .response-col_description pre").first
    assert '"token"' in body.inner_text()
