"""The service's WebSocket protocol: a keepalive that never cuts a client whose results are
queued (the backpressure rule), and an ``error`` before the close of an oversize message.

The server pings every ``ws_ping_interval`` seconds and, in uvicorn, closes
with 1011 a peer whose pong is not back within ``ws_ping_timeout``. But a
peer's pong travels behind everything the server sent before the ping: a
fast producer that reads its results slowly (its library stops reading when
its queue is full) cannot answer in time, and was cut off while its results
were still queued.

The rule here: when the pong deadline passes, the connection stays if the
peer is visibly alive or visibly behind —

- it sent bytes since the ping (a producer is not dead), or
- answers to it are waiting: the transport's write buffer is not empty, or the
  application has not taken the peer's last message because its answers are
  queued (reading is paused: :mod:`app.routes.streams` keeps 16 answers), or
  answers were sent to it since its last pong (beyond the connection's first
  message, the ``ack``): they may sit unread in the peer's buffers, ahead of
  the ping;

then the next ping is scheduled. Otherwise (silent and owed nothing) it is
closed with 1011 as before. Backpressure stays bounded: the stream channel
keeps at most 16 answers per connection, stops reading when they are not
taken, and TCP pushes back on the client; a peer that is gone for good is
ended by TCP's own retransmission timeout.

Every bad message is answered with an ``error`` message (the connection
stays open) — invalid JSON, nesting too deep, a schema violation, more than
``max_body_bytes``, more than ``ws_messages_per_second`` — except a message
beyond ``WS_FRAME_FACTOR × max_body_bytes``: uvicorn stops parsing it there
(it is never buffered whole) and closes with 1009; the ``error`` naming
``max_body_bytes`` is sent just before that close frame. The server then
half-closes the connection and reads and discards what comes (the rest of the
frame, the peer's close) until the peer closes its side, up to ``DRAIN_BYTES``
or :data:`DRAIN_SECONDS`, so that the peer can read both instead of a
connection reset — as an oversize HTTP body is drained before its 413.

Messages are not compressed (no per-message deflate): zlib runs on the event
loop, and compressing one 10 MB result held it ~200 ms (``bench/bounds.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from uvicorn.protocols.websockets.websockets_sansio_impl import WebSocketsSansIOProtocol
from websockets.exceptions import PayloadTooBig
from websockets.frames import Frame, Opcode

from app.http.body_limits import DRAIN_BYTES
from app.http.errors import LimitExceeded, error_message, problem_for
from app.http.transport import DRAIN_SECONDS, LISTEN_BACKLOG, guarded_http
from app.settings import Settings

WS_FRAME_FACTOR = 4
"""uvicorn accepts WebSocket messages up to 4 × ``max_body_bytes``: the application answers
those above ``max_body_bytes`` with an ``error``; beyond, the protocol closes with 1009."""


class PatientWebSocketProtocol(WebSocketsSansIOProtocol):
    """uvicorn's WebSocket protocol with the keepalive rule of this module."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.received_at = 0.0
        self.sent_since_pong = 0
        """Messages sent since the peer's last pong (the first is the connection's ack)."""
        self.ever_ponged = False
        self.draining: int | None = None
        """Bytes still to read and discard after an oversize frame (its rest, the peer's close)."""
        self.release_connection: Callable[[], None] | None = None
        """Gives the connection's count back (:mod:`app.http.transport`), set on upgrade."""

    def connection_lost(self, exc: Exception | None) -> None:
        release, self.release_connection = self.release_connection, None
        if release is not None:
            release()
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        self.received_at = self.loop.time()
        if self.draining is not None:
            self.draining -= len(data)  # the rest of a refused frame: read, never parsed
            if self.draining <= 0:
                self.transport.close()
            return
        super().data_received(data)

    async def send(self, message: Any) -> None:
        if message.get("type") == "websocket.send":
            self.sent_since_pong += 1
        await super().send(message)

    def handle_pong(self, event: Any) -> None:
        if self.pending_ping_payload is not None and bytes(event.data) == self.pending_ping_payload:
            self.sent_since_pong = 0
            self.ever_ponged = True
        super().handle_pong(event)

    def handle_parser_exception(self) -> None:
        too_big = self.conn.parser_exc
        if not isinstance(too_big, PayloadTooBig) or self.close_sent:
            super().handle_parser_exception()
            return
        # ahead of the close frame (the connection is closing: the frame is written as is,
        # not through the connection's state machine)
        text = oversize_error(self.config.ws_max_size, too_big, self.scope.get("path"))
        self.transport.write(Frame(Opcode.TEXT, text.encode()).serialize(mask=False))
        # uvicorn's handler, but the connection is half-closed and the transport closes only
        # once the peer has closed its side (after reading both frames and answering the
        # close), or after DRAIN_BYTES or DRAIN_SECONDS: the rest of the refused frame and the
        # peer's close frame are read and discarded meanwhile. A socket closed with bytes
        # unread resets, and a peer that gets the reset before it has processed both frames
        # loses them (the websockets client drops the frames it has parsed when writing its
        # close answer fails). The close timer also keeps uvicorn from closing the transport
        # as soon as the application has ended on the disconnect below (that immediate close
        # was the reset of a flaky ``error``-then-1009 test).
        assert self.conn.close_sent is not None
        close = self.conn.close_sent
        self.queue.put_nowait(
            {"type": "websocket.disconnect", "code": close.code, "reason": close.reason}
        )
        self.transport.write(b"".join(self.conn.data_to_send()))
        self.close_sent = True
        self.draining = DRAIN_BYTES
        self.close_timer = self.loop.call_later(DRAIN_SECONDS, self.transport.close)
        if self.transport.can_write_eof():
            self.transport.write_eof()

    def keepalive_timeout(self) -> None:
        owed = self.sent_since_pong > (0 if self.ever_ponged else 1)
        behind = owed or self.transport.get_write_buffer_size() > 0 or not self.writable.is_set()
        alive = self.received_at > self.ping_sent_at
        if (behind or alive or self.read_paused) and not self.transport.is_closing():
            self.pong_timer = None
            self.pending_ping_payload = None
            self.schedule_ping()
            return
        super().keepalive_timeout()


def oversize_error(ws_max_size: int, too_big: PayloadTooBig, path: str | None) -> str:
    """The ``error`` message of a message beyond ``ws_max_size`` (the connection then closes)."""
    limit = ws_max_size // WS_FRAME_FACTOR
    size = getattr(too_big, "size", None)  # the declared size of the refused frame
    refusal = LimitExceeded(
        "max_body_bytes",
        limit,
        size,
        what=f"message (beyond {WS_FRAME_FACTOR} × the limit: the connection closes with 1009)",
    )
    return error_message(problem_for(refusal, path), None)


def server_options(settings: Settings) -> dict[str, Any]:
    """uvicorn's options that the service's settings decide (the CLI and the tests use them)."""
    return {
        "http": guarded_http(settings.transport_limits()),
        "backlog": LISTEN_BACKLOG,
        "timeout_keep_alive": settings.keep_alive_timeout,
        "ws": PatientWebSocketProtocol,
        "ws_max_size": WS_FRAME_FACTOR * settings.max_body_bytes,
        "ws_ping_interval": settings.ws_ping_interval,
        "ws_ping_timeout": settings.ws_ping_timeout,
        # no per-message deflate: compressing a 10 MB result is zlib on the event loop
        # (250 ms of stall, bench/bounds.py); HTTP answers are not compressed either
        "ws_per_message_deflate": False,
    }
