"""The service on a live uvicorn server in a thread, for the benches and the experiments that
drive it over REST (``bench/peers.py``, :mod:`evaluation.traffic`)."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

SERVER_START_TIMEOUT_S = 20.0
"""The in-thread service must answer by then (else the caller stops, not hangs)."""


@contextmanager
def live_service(max_body_bytes: int = 8 * 1024 * 1024) -> Iterator[str]:
    """The application on uvicorn in a thread, memory store, a free loopback port; yields its URL."""
    import uvicorn

    from app.http.keepalive import server_options
    from app.main import create_app
    from app.settings import Settings

    settings = Settings.model_validate(
        {
            "store": "memory",
            "admin_token": "evaluation-service-admin-token-0123456789",
            "max_body_bytes": max_body_bytes,
            "rate_limit": "none",
        }
    )
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.bind(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    server = uvicorn.Server(
        uvicorn.Config(
            create_app(settings),
            log_level="warning",
            access_log=False,
            **server_options(settings),  # as `credal-fusion serve` runs it
        )
    )
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
