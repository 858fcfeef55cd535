"""End-to-end fixtures: the live uvicorn server of the API tests."""

from tests.api.conftest import live_server

__all__ = ["live_server"]
