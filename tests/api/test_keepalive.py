"""Keepalive never cuts a client whose results are queued (issue 14: a fast producer got 1011).

The client sends many inputs without reading the answers: its library stops
reading once its queue is full, so the server's pings (every 0.1 s here)
wait unanswered behind the results. The server must keep the connection and
deliver every answer in order once the client reads; a silent peer that is
owed nothing is still dropped.
"""

from __future__ import annotations

import base64
import json
import os
import socket
import time
from collections.abc import Iterator

import pytest
from websockets.sync.client import connect

from tests.api.conftest import LiveServer, make_settings, serving
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT

INPUTS = 300
PING_S = 0.1


@pytest.fixture
def pinging_server() -> Iterator[LiveServer]:
    settings = make_settings(ws_ping_interval=PING_S, ws_ping_timeout=PING_S, rate_limit="none")
    with serving(settings) as server:
        yield server


def open_session(server: LiveServer) -> tuple[str, dict[str, str]]:
    import httpx

    created = httpx.post(f"{server.url}/v1/sessions", json=SESSION_CONFIG).json()
    return created["id"], {"Authorization": f"Bearer {created['token']}"}


def test_a_fast_producer_is_not_cut_while_its_results_are_queued(
    pinging_server: LiveServer,
) -> None:
    sid, headers = open_session(pinging_server)
    url = pinging_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
    with connect(url, additional_headers=headers, max_queue=4, ping_interval=None) as ws:
        assert json.loads(ws.recv(timeout=10))["type"] == "ack"
        for index in range(INPUTS):
            ws.send(
                json.dumps(
                    {"type": "tracks", "ref": str(index), **TRACK_REPORT, "time": 1.0 + index}
                )
            )
        time.sleep(10 * PING_S)  # many pings go unanswered meanwhile
        refs = [json.loads(ws.recv(timeout=30))["ref"] for _ in range(INPUTS)]
    assert refs == [str(index) for index in range(INPUTS)]


def test_a_silent_peer_owed_nothing_is_still_dropped(pinging_server: LiveServer) -> None:
    """A raw client that completes the handshake and then never answers a ping: 1011."""
    sid, headers = open_session(pinging_server)
    port = int(pinging_server.url.rsplit(":", 1)[1])
    key = base64.b64encode(os.urandom(16)).decode()
    with socket.create_connection(("127.0.0.1", port), timeout=30) as peer:
        peer.sendall(
            (
                f"GET /v1/sessions/{sid}/stream HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
                f"Authorization: {headers['Authorization']}\r\n\r\n"
            ).encode()
        )
        received = b""
        while chunk := peer.recv(65536):  # until the server closes the connection
            received += chunk
    assert received.startswith(b"HTTP/1.1 101")
    close_1011 = b"\x88" + bytes([2 + len(b"keepalive ping timeout")]) + (1011).to_bytes(2, "big")
    assert close_1011 in received


def test_messages_are_not_compressed_even_when_the_client_offers(
    pinging_server: LiveServer,
) -> None:
    """zlib would run on the event loop for every result: the offer is declined."""
    sid, headers = open_session(pinging_server)
    url = pinging_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
    with connect(url, additional_headers=headers, compression="deflate") as ws:
        assert "permessage-deflate" in str(ws.request.headers.get("Sec-WebSocket-Extensions"))
        assert ws.response.headers.get("Sec-WebSocket-Extensions") is None
        assert json.loads(ws.recv(timeout=10))["type"] == "ack"
