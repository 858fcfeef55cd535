"""Transport limits against a live uvicorn server: connections per client and in all,
a trickled request head, idle keep-alive connections (:mod:`app.http.transport`).

An attacker's connections come from other loopback addresses (127.0.0.0/8 is
all loopback on Linux), so the per-address limit tells them from the test's
own client; no assertion is on a time.
"""

from __future__ import annotations

import contextlib
import json
import socket
import time
from collections.abc import Iterator

import httpx
import pytest

from tests.api.conftest import LiveServer, make_settings, serving

PER_CLIENT = 8
TOTAL = 40


@pytest.fixture(scope="module")
def server() -> Iterator[LiveServer]:
    settings = make_settings(
        max_connections=TOTAL,
        max_connections_per_client=PER_CLIENT,
        request_head_timeout=1.0,
        keep_alive_timeout=0.5,
    )
    with serving(settings) as live:
        yield live


def port_of(server: LiveServer) -> int:
    return int(server.url.rsplit(":", 1)[1])


def connect_from(server: LiveServer, address: str) -> socket.socket:
    return socket.create_connection(("127.0.0.1", port_of(server)), source_address=(address, 0))


def answer_of(connection: socket.socket, timeout: float = 10.0) -> tuple[int, dict[str, object]]:
    """The status and problem document the server wrote before closing (0 if none)."""
    connection.settimeout(timeout)
    received = b""
    with contextlib.suppress(OSError):
        while chunk := connection.recv(65536):
            received += chunk
    if not received:
        return 0, {}
    head, _, body = received.partition(b"\r\n\r\n")
    return int(head.split(b" ", 2)[1]), json.loads(body) if body else {}


def closed(connection: socket.socket) -> bool:
    """Whether the server closed ``connection`` (without waiting)."""
    connection.setblocking(False)
    try:
        return connection.recv(65536) == b""
    except BlockingIOError:
        return False
    except OSError:
        return True
    finally:
        connection.setblocking(True)


def healthy(server: LiveServer) -> bool:
    with httpx.Client(base_url=server.url, timeout=10.0) as client:
        return client.get("/healthz").status_code == 200


def test_one_connection_beyond_the_per_client_limit_is_refused_429(server: LiveServer) -> None:
    held = [connect_from(server, "127.0.0.2") for _ in range(PER_CLIENT)]
    try:
        status, problem = answer_of(connect_from(server, "127.0.0.2"))
        assert status == 429
        assert problem["limit"] == "max_connections_per_client"
        assert problem["type"] == "urn:credal-fusion:problem:too-many-connections"
        assert not any(closed(connection) for connection in held)
        assert healthy(server)  # another address is served meanwhile
    finally:
        for connection in held:
            connection.close()


def test_at_the_total_limit_the_oldest_idle_connections_make_room(server: LiveServer) -> None:
    """Three times the total limit of idle connections, from many addresses: the oldest are
    closed for the newest, and the service still answers."""
    held = [connect_from(server, f"127.0.1.{index % 30 + 1}") for index in range(3 * TOTAL)]
    try:
        time.sleep(0.2)
        assert healthy(server)
        time.sleep(0.2)
        open_ones = [not closed(connection) for connection in held]
        assert sum(open_ones) <= TOTAL
        assert not any(open_ones[:TOTAL])  # the oldest went first
    finally:
        for connection in held:
            connection.close()


def test_a_head_trickled_byte_by_byte_is_cut_at_request_head_timeout(server: LiveServer) -> None:
    """Each byte comes well within the timeout: the head as a whole does not."""
    connection = connect_from(server, "127.0.0.3")
    head = b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Slow: " + b"a" * 100
    refused = False
    for byte in head:
        try:
            connection.sendall(bytes([byte]))
        except OSError:
            refused = True
            break
        if closed(connection):
            refused = True
            break
        time.sleep(0.05)
    assert refused
    connection.close()


def test_a_connection_that_never_speaks_gets_408(server: LiveServer) -> None:
    status, problem = answer_of(connect_from(server, "127.0.0.4"))
    assert status == 408 and problem["limit"] == "request_head_timeout"


def test_an_idle_keep_alive_connection_is_closed(server: LiveServer) -> None:
    connection = connect_from(server, "127.0.0.5")
    connection.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
    connection.settimeout(10.0)
    first = connection.recv(65536)
    assert first.startswith(b"HTTP/1.1 200")
    assert connection.recv(65536) == b""  # closed after keep_alive_timeout, no second answer
    connection.close()


def test_a_thousand_idle_connections_leave_healthz_answering() -> None:
    """1 100 idle connections from 110 addresses (the default total limit is 1 000)."""
    with serving(make_settings()) as live:
        held = [connect_from(live, f"127.0.2.{index % 110 + 1}") for index in range(1100)]
        try:
            time.sleep(0.3)
            assert healthy(live)
            assert sum(not closed(connection) for connection in held) <= 1000
        finally:
            for connection in held:
                connection.close()


def test_a_crowd_at_the_total_limit_closes_its_own_not_a_light_clients(server: LiveServer) -> None:
    """A keep-alive connection idle between two requests, while ten addresses open twice the
    total limit: the room is made from the addresses holding the most connections."""
    light = connect_from(server, "127.0.0.7")
    light.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
    light.settimeout(10.0)
    assert light.recv(65536).startswith(b"HTTP/1.1 200")
    crowd = [connect_from(server, f"127.0.3.{index % 10 + 1}") for index in range(2 * TOTAL)]
    try:
        time.sleep(0.2)
        light.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
        assert light.recv(65536).startswith(b"HTTP/1.1 200")  # still open, still answered
    finally:
        light.close()
        for connection in crowd:
            connection.close()
