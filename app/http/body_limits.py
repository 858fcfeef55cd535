"""Limits on one request: the body's size and read time, and the wire limits of its lists.

Every limit is a setting (``app/settings.py``) checked before the work it bounds:

- ``max_body_bytes`` (1 MiB) and ``body_read_timeout`` (10 s): by
  :class:`BodyLimits`, before anything parses the body (413, 408); a body with a
  ``Content-Encoding`` (gzip…) is refused unread (415): nothing is ever inflated;
- ``max_tracks_per_input`` (2 000, also per side of ``/v1/associate``),
  ``max_sensors`` (64), ``max_classes`` (20), ``max_focal_sets`` (64 per class
  mass): by the wire models on each raw list, before its items are validated
  (:mod:`api_schemas.limits`; 422 ``limit-exceeded``); :class:`BodyLimits`
  puts the configured values in place for the request;
- ``max_associate_pairs`` (250 000) and ``max_associate_class_pairs`` (20 000,
  when the tracks carry class evidence): known × incoming of ``/v1/associate``;
- a fused or accumulated class mass keeps at most 32 focal sets (summarized
  beyond, and said so: :mod:`core.belief.summary`);
- ``max_listed_errors`` (50): a 422 lists that many errors and counts them all;
- ``ws_messages_per_second`` (1 000): per stream connection (an ``error`` beyond);
- a page of ``GET …/events``: ``limit`` events (≤ 10 000) and at most 4 MiB;
- ``max_sessions`` (1 000): counted and taken in one step of the store at session creation,
  across every instance sharing it (429);
- ``rate_limit``: per verified token or client address (:mod:`app.http.rate_limit`).
"""

from __future__ import annotations

import anyio
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from api_schemas.limits import ACTIVE_LIMITS, WireLimits
from app.http.errors import (
    BodyTooLarge,
    BodyTooSlow,
    ServiceError,
    UnsupportedEncoding,
    problem_response,
)

BODY_LIMIT = "max_body_bytes"
READ_TIMEOUT = "body_read_timeout"
DRAIN_BYTES = 8 * 1024 * 1024
"""An oversize body is read and discarded up to this size before the 413 is sent."""


class BodyLimits:
    """ASGI middleware: the request's wire limits; a body too large (413) or too slow (408).

    ``limits`` are put in :data:`~api_schemas.limits.ACTIVE_LIMITS` for the request
    (HTTP and WebSocket). A body larger than ``max_bytes`` gets 413 naming the limit;
    a body not received within ``read_timeout`` seconds gets 408 and the connection
    is closed.

    The body is read (chunked bodies included) only up to the limit and then
    replayed to the application, so no parser ever sees an oversize body.
    After a refusal the rest of the body is read and discarded, up to
    :data:`DRAIN_BYTES`, so the client can read the answer instead of a
    connection reset; a ``Content-Length`` beyond that is refused at once
    and the connection closed.
    """

    def __init__(
        self, app: ASGIApp, max_bytes: int, read_timeout: float, limits: WireLimits
    ) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.read_timeout = read_timeout
        self.limits = limits

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        ACTIVE_LIMITS.set(self.limits)
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = dict(scope["headers"])
        encoding = headers.get(b"content-encoding", b"").strip().lower()
        if encoding not in (b"", b"identity"):
            refusal = UnsupportedEncoding(encoding.decode("latin-1"))
            await _answer(scope, receive, send, refusal, close=True)
            return
        declared_text = headers.get(b"content-length")
        declared = (
            int(declared_text) if declared_text is not None and declared_text.isdigit() else None
        )
        if declared is not None and declared > self.max_bytes:
            ended = declared <= DRAIN_BYTES and await _drain(receive, DRAIN_BYTES)
            await self._refuse(scope, receive, send, declared, ended)
            return
        chunks: list[bytes] = []
        size = 0
        with anyio.move_on_after(self.read_timeout) as reading:
            while True:
                message = await receive()
                if message["type"] == "http.disconnect":
                    return
                chunk: bytes = message.get("body", b"")
                size += len(chunk)
                more = bool(message.get("more_body", False))
                if size > self.max_bytes:
                    ended = not more or await _drain(receive, DRAIN_BYTES)
                    await self._refuse(scope, receive, send, declared, ended)
                    return
                chunks.append(chunk)
                if not more:
                    break
        if reading.cancelled_caught:
            await self._too_slow(scope, receive, send, size)
            return
        body = b"".join(chunks)
        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)

    async def _refuse(
        self, scope: Scope, receive: Receive, send: Send, declared: int | None, ended: bool
    ) -> None:
        refusal = BodyTooLarge(BODY_LIMIT, self.max_bytes, declared)
        await _answer(scope, receive, send, refusal, close=not ended)

    async def _too_slow(self, scope: Scope, receive: Receive, send: Send, received: int) -> None:
        refusal = BodyTooSlow(READ_TIMEOUT, self.read_timeout, received)
        await _answer(scope, receive, send, refusal, close=True)


async def _answer(
    scope: Scope, receive: Receive, send: Send, refusal: ServiceError, *, close: bool
) -> None:
    """Send the problem answer of ``refusal``; ``close``: and close the connection after it."""
    response = problem_response(refusal, scope.get("path"))
    if close:
        response.headers["Connection"] = "close"
    await response(scope, receive, send)


async def _drain(receive: Receive, budget: int) -> bool:
    """Read and discard the rest of a body, at most ``budget`` bytes; whether it ended."""
    drained = 0
    while drained <= budget:
        message = await receive()
        if message["type"] != "http.request":
            return False
        drained += len(message.get("body", b""))
        if not message.get("more_body", False):
            return True
    return False
