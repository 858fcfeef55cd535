"""Transport limits: what a connection may hold before the application sees a request.

Checked in the HTTP protocol itself (uvicorn's httptools protocol, extended),
before any header is parsed by the application and, for sizes, before the
parser is fed the bytes beyond the limit:

- ``max_header_bytes`` (16 KiB): the request line and headers of one request.
  The parser is fed at most that many bytes of a request head; a longer head
  gets ``431`` and the connection is closed. (Unbounded, one 64 MB header held
  the event loop 5.7 s: the parser copies a header value as each piece arrives.)
- ``max_header_count`` (100): header lines of one request (``431``).
- ``request_head_timeout`` (10 s): from the connection (or the first byte of a
  keep-alive connection's next request) to the end of the request head; a
  client that is slower (slowloris) gets ``408`` and the connection is closed.
  The body then has ``body_read_timeout`` (:mod:`app.http.body_limits`).
- ``keep_alive_timeout`` (5 s): an idle keep-alive connection is closed.
- ``max_connections_per_client`` (64): open connections of one client address
  (HTTP and WebSocket alike); one more is answered ``429`` and closed.
- ``max_connections`` (1 000): open connections in total. At the limit a new
  connection closes one still waiting for its request head (an idle or
  trickling connection: it has nothing in progress), the oldest of the address
  holding the most connections; if every connection is busy, the new one is
  answered ``503`` and closed.

Refusals are problem+json documents written by the protocol (the application
never runs), with ``Connection: close``; a connection refused at its start is
refused before uvicorn sets it up (no address look-ups, no flow control). The process's descriptor limit is
raised to its hard limit at start (:func:`raise_descriptor_limit`), so the
connection limits, not the operating system, decide.
"""

from __future__ import annotations

import asyncio
import functools
import resource
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from http import HTTPStatus
from typing import Any

import httptools
from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

from app.http.errors import (
    HeadersTooLarge,
    HeadTooSlow,
    ServiceError,
    TooManyConnections,
    problem_for,
)
from app.http.responses import dumps
from app.sessions.work import Receipt, receipt
from app.settings import TransportLimits

DRAIN_SECONDS = 2.0
"""How long the rest of a refused head (:data:`HEAD_DRAIN_BYTES` at most) or WebSocket frame
(``DRAIN_BYTES``) is read and discarded before the connection closes."""
HEAD_DRAIN_BYTES = 256 * 1024
"""The rest of a head too large read and discarded before closing (the client reads the 431
meanwhile): a header bomb is not read whole, as an oversize body is (up to 8 MiB)."""


RECEIVED_AT = "credal.received_at"
"""The scope key of the :class:`~app.sessions.work.Receipt` of a request, taken when its last
byte was read: the start of its wait for an answer (``max_queue_ms``,
:meth:`~app.sessions.pipeline.InputPipeline.submit`)."""


def received_at(scope: Any) -> Receipt | None:
    """The :data:`RECEIVED_AT` receipt of the request of ``scope`` (``None`` if it was not read
    by :class:`GuardedHttpProtocol`, as under the in-process test client)."""
    stamp = scope.get(RECEIVED_AT)
    return stamp if isinstance(stamp, Receipt) else None


LISTEN_BACKLOG = 256
"""Connections the kernel queues before the server accepts them (uvicorn's default: 2 048).
The server accepts what is queued in one turn of its event loop: a burst of 2 000 waiting
connections was one long turn with every request on hold. Beyond the queue, a client's
connection attempt is retried by its kernel."""


@functools.lru_cache(maxsize=32)
def _cached_refusal(kind: Callable[..., ServiceError], *args: object) -> bytes:
    """The answer of the refusal ``kind(*args)``, written once per server."""
    return refusal_bytes(kind(*args))


def refusal_bytes(refusal: ServiceError) -> bytes:
    """The raw HTTP answer of ``refusal`` (problem+json, the connection closed after it)."""
    problem = problem_for(refusal)
    body = dumps(problem.model_dump(mode="json", exclude_none=True)).encode()
    status = HTTPStatus(refusal.status_code)
    head = (
        f"HTTP/1.1 {status.value} {status.phrase}\r\n"
        "content-type: application/problem+json\r\n"
        "x-content-type-options: nosniff\r\n"
        f"content-length: {len(body)}\r\n"
        "connection: close\r\n\r\n"
    )
    return head.encode("ascii") + body


@dataclass
class Connections:
    """The open connections of one server, per client address, and the ones waiting for a
    request head (idle or trickling), per address, oldest first.

    At the total limit, the connection that makes room is the oldest waiting one of the
    address holding the most connections: a crowd of slow connections from a few addresses
    closes its own, not a light client's idle keep-alive connection. The addresses with a
    waiting connection are indexed by their number of connections (``levels``), so that
    choice costs the same whatever the number of addresses (a scan of every address per new
    connection was 2 000 × 300 key calls for 3 000 slowloris connections from 300 addresses,
    tens of ms per turn of the event loop)."""

    limits: TransportLimits
    per_client: dict[str, int] = field(default_factory=dict)
    total: int = 0
    waiting: dict[str, OrderedDict[int, asyncio.BaseTransport]] = field(default_factory=dict)
    levels: dict[int, dict[str, None]] = field(default_factory=dict)
    """Connections of an address → the addresses holding that many with one waiting."""
    top: int = 0
    """No level above holds an address (the highest non-empty one is at or below it)."""

    def admit(self, transport: asyncio.BaseTransport, client: str) -> bytes | None:
        """Count a new connection, or give the answer refusing it (then it is not counted)."""
        limits = self.limits
        if self.per_client.get(client, 0) >= limits.max_connections_per_client:
            return _cached_refusal(
                TooManyConnections,
                "max_connections_per_client",
                limits.max_connections_per_client,
                "this client address",
                HTTPStatus.TOO_MANY_REQUESTS,
            )
        if self.total >= limits.max_connections:
            heaviest = self._heaviest()
            if heaviest is None:
                return _cached_refusal(
                    TooManyConnections,
                    "max_connections",
                    limits.max_connections,
                    "the server",
                    HTTPStatus.SERVICE_UNAVAILABLE,
                )
            waiting = self.waiting[heaviest]
            _, oldest = waiting.popitem(last=False)
            if not waiting:
                self._unindex(heaviest)
                del self.waiting[heaviest]
            oldest.close()  # its connection_lost releases its count
        self._unindex(client)
        self.per_client[client] = self.per_client.get(client, 0) + 1
        self._index(client)
        self.total += 1
        return None

    def release(self, client: str, transport: asyncio.BaseTransport) -> None:
        self.busy(client, transport)
        self._unindex(client)
        left = self.per_client.get(client, 0) - 1
        if left > 0:
            self.per_client[client] = left
            self._index(client)
        else:
            self.per_client.pop(client, None)
        self.total -= 1

    def wait_for_head(self, client: str, transport: asyncio.BaseTransport) -> None:
        waiting = self.waiting.get(client)
        if waiting is None:
            waiting = self.waiting[client] = OrderedDict()
            self._index(client)
        waiting[id(transport)] = transport
        waiting.move_to_end(id(transport))

    def busy(self, client: str, transport: asyncio.BaseTransport) -> None:
        waiting = self.waiting.get(client)
        if waiting is not None:
            waiting.pop(id(transport), None)
            if not waiting:
                self._unindex(client)
                del self.waiting[client]

    def _index(self, client: str) -> None:
        """File an address with a waiting connection under its number of connections."""
        if client in self.waiting:
            count = self.per_client.get(client, 0)
            self.levels.setdefault(count, {})[client] = None
            self.top = max(self.top, count)

    def _unindex(self, client: str) -> None:
        if client in self.waiting:
            count = self.per_client.get(client, 0)
            level = self.levels.get(count)
            if level is not None:
                level.pop(client, None)
                if not level:
                    del self.levels[count]

    def _heaviest(self) -> str | None:
        """The address holding the most connections among those with one waiting (the first
        filed of equals); ``None`` if no connection is waiting."""
        while self.top > 0 and self.top not in self.levels:
            self.top -= 1  # counts move by one: at most max_connections_per_client steps
        level = self.levels.get(self.top)
        return None if level is None else next(iter(level))


class GuardedHttpProtocol(HttpToolsProtocol):
    """uvicorn's httptools protocol with the limits of this module (see :func:`guarded_http`).

    A request head is the bytes from the end of the previous request (or the
    connection's start) to the end of its headers: the parser is fed at most
    ``max_header_bytes`` of them, and they must arrive within
    ``request_head_timeout`` of the connection or of the head's first byte.
    """

    guard: Connections  # set per server by guarded_http

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.head_bytes = 0
        self.header_count = 0
        self.in_head = True
        self.refused = False
        self.counted: str | None = None
        self.head_timer: asyncio.TimerHandle | None = None
        self.draining: int | None = None
        """Bytes still to read and discard after a refusal, before the connection closes."""

    @property
    def limits(self) -> TransportLimits:
        return self.guard.limits

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        peer = transport.get_extra_info("peername")
        client = str(peer[0]) if peer else "unknown"
        refusal = self.guard.admit(transport, client)
        if refusal is not None:  # before uvicorn sets the connection up: a crowd's cost
            self.transport = transport
            self._refuse(refusal)
            return
        super().connection_made(transport)
        self.counted = client
        self.guard.wait_for_head(client, transport)
        self._arm_head_timer()  # the time to the first byte counts

    def connection_lost(self, exc: Exception | None) -> None:
        self._stop_head_timer()
        if self.counted is not None:
            self.guard.release(self.counted, self.transport)
            self.counted = None
        super().connection_lost(exc)

    def _arm_head_timer(self) -> None:
        if self.head_timer is None:
            self.head_timer = self.loop.call_later(
                self.limits.request_head_timeout, self._head_timed_out
            )

    def _stop_head_timer(self) -> None:
        if self.head_timer is not None:
            self.head_timer.cancel()
            self.head_timer = None

    def _head_timed_out(self) -> None:
        self.head_timer = None
        if self.in_head and not self.transport.is_closing():
            self._refuse(
                _cached_refusal(
                    HeadTooSlow, "request_head_timeout", self.limits.request_head_timeout
                )
            )

    def _refuse(self, answer: bytes, *, drain: bool = False) -> None:
        """Send ``answer`` (a refusal) and close; ``drain``: the client is still sending (a head too
        large), so the rest is read and discarded first (up to ``HEAD_DRAIN_BYTES``, for at most
        ``DRAIN_SECONDS``): a socket closed with unread bytes resets, and the peer loses the
        answer."""
        self.refused = True
        if self.transport.is_closing():
            return
        self.transport.write(answer)
        if not drain or not self.transport.can_write_eof():
            self.transport.close()
            return
        self.transport.write_eof()
        self.draining = HEAD_DRAIN_BYTES
        self.loop.call_later(DRAIN_SECONDS, self.transport.close)

    def data_received(self, data: bytes) -> None:
        if self.draining is not None:
            self.draining -= len(data)
            if self.draining <= 0:
                self.transport.close()
            return
        while data and not self.refused and not self.transport.is_closing():
            if not self.in_head:
                super().data_received(data)
                return
            budget = self.limits.max_header_bytes - self.head_bytes
            if budget <= 0:
                limit = self.limits.max_header_bytes
                self._refuse(
                    _cached_refusal(HeadersTooLarge, "headers", "max_header_bytes", limit),
                    drain=True,
                )
                return
            piece, data = data[:budget], data[budget:]
            self.head_bytes += len(piece)
            super().data_received(piece)
            if self.transport.get_protocol() is not self:
                return  # upgraded to a WebSocket: the rest went to its protocol

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self.header_count = 0
        self._arm_head_timer()  # a keep-alive connection's next request: from its first byte

    def on_header(self, name: bytes, value: bytes) -> None:
        self.header_count += 1
        if self.header_count > self.limits.max_header_count:
            limit = self.limits.max_header_count
            self._refuse(
                _cached_refusal(HeadersTooLarge, "header lines", "max_header_count", limit),
                drain=True,
            )
            raise httptools.HttpParserError("too many header lines")
        super().on_header(name, value)

    def send_400_response(self, msg: str) -> None:
        if not self.refused:  # else a refusal is out already (the parser stopped on it)
            super().send_400_response(msg)

    def on_headers_complete(self) -> None:
        self.in_head = False
        self._stop_head_timer()
        if self.counted is not None:
            self.guard.busy(self.counted, self.transport)
        super().on_headers_complete()

    def on_message_complete(self) -> None:
        self.scope[RECEIVED_AT] = receipt()  # type: ignore[literal-required]
        super().on_message_complete()
        self.in_head = True  # what follows is the next request's head
        self.head_bytes = 0

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self.transport.is_closing() and self.counted is not None:
            self.guard.wait_for_head(
                self.counted, self.transport
            )  # idle: the first to go at the limit

    def handle_websocket_upgrade(self) -> None:
        self._stop_head_timer()
        counted, self.counted = self.counted, None
        if counted is not None:
            self.guard.busy(counted, self.transport)  # the WebSocket protocol releases it
        super().handle_websocket_upgrade()
        if counted is not None:
            guard, transport = self.guard, self.transport
            protocol = transport.get_protocol()
            protocol.release_connection = lambda: guard.release(counted, transport)  # type: ignore[attr-defined]


def guarded_http(limits: TransportLimits) -> type[GuardedHttpProtocol]:
    """The HTTP protocol class of one server (its own connection counts) under ``limits``."""
    return type("GuardedHttpProtocol", (GuardedHttpProtocol,), {"guard": Connections(limits)})


def raise_descriptor_limit() -> int:
    """Raise this process's open-file limit to its hard limit; the new soft limit."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard == resource.RLIM_INFINITY or soft < hard:
        target = hard if hard != resource.RLIM_INFINITY else max(soft, 65536)
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
            soft = target
        except (ValueError, OSError):
            pass
    return soft
