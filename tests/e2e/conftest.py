"""End-to-end fixtures: the live uvicorn server of the API tests, a headless Chromium page."""

from tests.api.conftest import live_server
from tests.e2e.browser import browser_page

__all__ = ["browser_page", "live_server"]
