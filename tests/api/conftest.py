"""Fixtures of the API tests: settings, an in-process client, a live uvicorn server."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings
from evaluation.service import serving as serve_in_thread

ADMIN_TOKEN = "admin-token-for-tests-0123456789"


def make_settings(**overrides: object) -> Settings:
    """Test settings: memory store, a known admin token, small limits, and no overload guard
    nor queue-time limit (they read the event loop's lateness and the inputs' waits, which on
    a loaded test machine are the machine's: their tests set ``overload_delay_ms`` and
    ``max_queue_ms`` themselves)."""
    values: dict[str, object] = {
        "store": "memory",
        "admin_token": ADMIN_TOKEN,
        "max_body_bytes": 64 * 1024,
        "overload_delay_ms": 0,
        "max_queue_ms": 0,
    }
    values.update(overrides)
    return Settings.model_validate(values)


@pytest.fixture
def client() -> Iterator[TestClient]:
    """The real application in process (lifespan run), memory store."""
    with TestClient(create_app(make_settings()), raise_server_exceptions=False) as test_client:
        yield test_client


@dataclass(frozen=True)
class LiveServer:
    """A uvicorn server on 127.0.0.1."""

    url: str
    settings: Settings


@contextmanager
def serving(settings: Settings, app: FastAPI | None = None) -> Iterator[LiveServer]:
    """The application (built from ``settings`` unless given) served by uvicorn on a free
    loopback port, in a background thread (:func:`evaluation.service.serving`)."""
    with serve_in_thread(settings, app) as url:
        yield LiveServer(url=url, settings=settings)


@pytest.fixture
def live_server() -> Iterator[LiveServer]:
    """The application served by uvicorn on a free loopback port (memory store)."""
    with serving(make_settings()) as server:
        yield server
