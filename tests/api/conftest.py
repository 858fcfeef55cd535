"""Fixtures of the API tests: settings, an in-process client, a live uvicorn server."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import pytest
import uvicorn
from fastapi import FastAPI
from fastapi.testclient import TestClient

from app.http.keepalive import server_options
from app.main import create_app
from app.settings import Settings

ADMIN_TOKEN = "admin-token-for-tests-0123456789"
SERVER_START_TIMEOUT_S = 20.0


def make_settings(**overrides: object) -> Settings:
    """Test settings: memory store, a known admin token, small limits."""
    values: dict[str, object] = {
        "store": "memory",
        "admin_token": ADMIN_TOKEN,
        "max_body_bytes": 64 * 1024,
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
    loopback port, in a background thread."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    config = uvicorn.Config(
        app or create_app(settings), log_level="warning", lifespan="on", **server_options(settings)
    )
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listener]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + SERVER_START_TIMEOUT_S
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            raise RuntimeError("uvicorn did not start")
        time.sleep(0.01)
    try:
        yield LiveServer(url=f"http://127.0.0.1:{port}", settings=settings)
    finally:
        server.should_exit = True
        thread.join(timeout=SERVER_START_TIMEOUT_S)
        listener.close()


@pytest.fixture
def live_server() -> Iterator[LiveServer]:
    """The application served by uvicorn on a free loopback port (memory store)."""
    with serving(make_settings()) as server:
        yield server
