"""`credal-fusion serve` starts a real uvicorn server that answers /healthz."""

from __future__ import annotations

import asyncio
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

from app.main import create_app
from core import __version__

ROOT = Path(__file__).resolve().parents[1]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_healthz_in_process() -> None:
    async def get_health() -> httpx.Response:
        transport = httpx.ASGITransport(app=create_app())
        async with httpx.AsyncClient(transport=transport, base_url="http://test") as client:
            return await client.get("/healthz")

    answer = asyncio.run(get_health())
    assert answer.status_code == 200
    assert answer.json() == {"status": "ok", "version": __version__}


def test_console_script_serves_healthz_on_loopback() -> None:
    port = free_port()
    script = Path(sys.executable).with_name("credal-fusion")
    server = subprocess.Popen(
        [str(script), "serve", "--host", "127.0.0.1", "--port", str(port)],
        cwd=ROOT,
        env={**os.environ, "CREDAL_STORE": "memory"},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
    )
    try:
        deadline = time.monotonic() + 30.0
        while True:
            try:
                answer = httpx.get(f"http://127.0.0.1:{port}/healthz", timeout=1.0)
                break
            except httpx.TransportError:
                assert server.poll() is None, "server exited before answering"
                assert time.monotonic() < deadline, "server did not answer within 30 s"
                time.sleep(0.1)
        assert answer.status_code == 200
        assert answer.json()["version"] == __version__
    finally:
        server.terminate()
        server.wait(timeout=10)
