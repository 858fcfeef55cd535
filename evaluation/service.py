"""The service on a live uvicorn server in a thread: for the benches and the experiments that
drive it over REST (``bench/peers.py``, :mod:`evaluation.traffic`) and for the API tests."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fastapi import FastAPI

    from app.settings import Settings

SERVER_START_TIMEOUT_S = 20.0
"""The in-thread service must answer by then (else the caller stops, not hangs)."""


@contextmanager
def serving(settings: Settings, app: FastAPI | None = None) -> Iterator[str]:
    """The application (built from ``settings`` unless given) on uvicorn, as ``credal-fusion
    serve`` runs it, on a free loopback port in a background thread; yields its URL."""
    import uvicorn

    from app.http.keepalive import server_options
    from app.main import create_app

    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    config = uvicorn.Config(
        app or create_app(settings),
        log_level="warning",
        access_log=False,
        lifespan="on",
        **server_options(settings),
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
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=SERVER_START_TIMEOUT_S)
        listener.close()


@contextmanager
def live_service(max_body_bytes: int = 8 * 1024 * 1024) -> Iterator[str]:
    """The service with a memory store, no rate limit and large bodies; yields its URL."""
    from app.settings import Settings

    settings = Settings.model_validate(
        {
            "store": "memory",
            "admin_token": "evaluation-service-admin-token-0123456789",
            "max_body_bytes": max_body_bytes,
            "rate_limit": "none",
        }
    )
    with serving(settings) as url:
        yield url
