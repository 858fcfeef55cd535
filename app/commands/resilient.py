"""A reference client for a sensor: it streams its inputs and survives a failover, losing none.

What the protocol asks of a client (``docs/asyncapi.yaml``, "Clients and
failures"), as code to read or to reuse:

- keep one input in flight on the ``stream`` WebSocket: send it, wait for its
  ``result`` (its ``seq`` is the session's last applied input);
- on a failure — the connection closes or breaks, no answer within the
  timeout, or an ``error`` with status 503 (``store-unavailable``,
  ``session-leased``) — the input may or may not have been applied. Close, wait
  the problem's ``retry_after`` (or a short backoff), reconnect to the next
  instance of the list, and read the new ``ack.seq``: one more than the last
  answered ``seq`` means the input was applied (its result is lost, the next
  input goes on); equal means it was lost (send it again);
- any other ``error`` (a 4xx: the input itself is refused) is the caller's.

It assumes it is the session's only sender (another sender moves ``seq`` too,
and it then refuses to guess: :class:`SequenceMovedError`).
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from websockets.exceptions import ConnectionClosed, InvalidStatus, WebSocketException
from websockets.sync.client import ClientConnection, connect

RETRYABLE = frozenset({503})
FAILURES = (ConnectionClosed, InvalidStatus, WebSocketException, OSError, TimeoutError)


class SequenceMovedError(RuntimeError):
    """The session's ``seq`` moved by more than this client's one input in flight."""


class InputRefusedError(ValueError):
    """The service refused the input itself (a 4xx ``error``): sending it again will not help."""

    def __init__(self, problem: dict[str, Any]) -> None:
        super().__init__(f"input refused: {problem.get('status')} {problem.get('detail')}")
        self.problem = problem


@dataclass(frozen=True)
class Delivery:
    """How one input went: its ``seq``, and its ``result`` (``None`` when the input was applied
    but its answer was lost in a failover: read ``GET …/tracks`` for the picture)."""

    seq: int
    result: dict[str, Any] | None
    retries: int


class ResilientStream:
    """One sender's ``stream`` connection to a session, over any of ``urls`` (its instances)."""

    def __init__(
        self,
        urls: Sequence[str],
        session: str,
        token: str,
        *,
        answer_timeout_s: float = 30.0,
        give_up_s: float = 60.0,
    ) -> None:
        self.urls = [url.rstrip("/").replace("http", "ws", 1) for url in urls]
        self.session = session
        self.token = token
        self.answer_timeout_s = answer_timeout_s
        self.give_up_s = give_up_s
        self.next_url = 0
        self.connection: ClientConnection | None = None
        self._opened = contextlib.ExitStack()
        self.last_seq: int | None = None
        """The session's ``seq`` as this client last knew it (an ack, or its last result)."""

    def _connect(self) -> int:
        """Connect to the next instance that accepts; the ``ack``'s ``seq``."""
        url = f"{self.urls[self.next_url % len(self.urls)]}/v1/sessions/{self.session}/stream"
        self.next_url += 1
        opened = contextlib.ExitStack()
        connection = opened.enter_context(
            connect(
                url,
                additional_headers={"Authorization": f"Bearer {self.token}"},
                open_timeout=self.answer_timeout_s,
                max_size=None,
            )
        )
        self.connection, self._opened = connection, opened
        ack = json.loads(connection.recv(timeout=self.answer_timeout_s))
        if ack.get("type") != "ack":
            self._drop()
            raise ConnectionError(f"no ack: {ack.get('type')!r}")
        return int(ack["seq"])

    def _drop(self) -> None:
        if self.connection is not None:
            with contextlib.suppress(*FAILURES):
                self._opened.close()
            self.connection = None

    def send(self, message: dict[str, Any]) -> Delivery:
        """Send one input (a ``tracks`` or ``detections`` message) until it is applied once."""
        deadline = time.monotonic() + self.give_up_s
        retries = 0
        pending = False  # the input may have been applied by a connection that failed
        wait_s = 0.0
        while True:
            if time.monotonic() > deadline:
                raise TimeoutError(f"input not delivered within {self.give_up_s} s")
            time.sleep(wait_s)
            try:
                if self.connection is None:
                    acked = self._connect()
                    if self.last_seq is None:
                        self.last_seq = acked
                    elif pending and acked == self.last_seq + 1:
                        self.last_seq = acked  # applied before the failure: not sent again
                        return Delivery(acked, None, retries)
                    elif acked != self.last_seq:
                        raise SequenceMovedError(
                            f"session {self.session}: seq {acked}, this client knew "
                            f"{self.last_seq}: another sender?"
                        )
                assert self.connection is not None
                pending = True
                self.connection.send(json.dumps(message))
                answer = json.loads(self.connection.recv(timeout=self.answer_timeout_s))
            except FAILURES:
                self._drop()
                retries += 1
                wait_s = min(1.0, 0.1 * retries)
                continue
            if answer.get("type") == "result":
                self.last_seq = int(answer["result"]["seq"])
                return Delivery(self.last_seq, answer["result"], retries)
            problem = answer.get("problem", {})
            if answer.get("type") == "error" and problem.get("status") in RETRYABLE:
                self._drop()  # the next ack says whether it was applied
                retries += 1
                # a leased session says its lease's time left to the millisecond
                wait_s = float(problem.get("retry_after_ms", 0)) / 1000 or float(
                    problem.get("retry_after", 1)
                )
                continue
            raise InputRefusedError(problem)

    def close(self) -> None:
        self._drop()
