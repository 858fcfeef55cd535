"""Fan-out of a session's results to its subscribers, never with an unbounded backlog.

Each subscriber has a bounded queue. Publishing never waits: when a
subscriber's queue is full its oldest result is dropped to make room, so a
slow subscriber skips ahead to the latest state (the ``seq`` numbers show the
gap) and a fast one receives every result in order. Everything runs on the
event loop thread.

A result is published as a :class:`Published`: its message text in each
output (:class:`~app.outputs.base.Output`) a subscriber of this instance asked
for (``?format=…&frame=…``) before the step was applied (written beside the
step, in its worker thread), and always as the contract's JSON.

A subscription ends with an :class:`Ending`, the WebSocket close code and
reason its subscriber is told: the session ended (1000), or the store is
unavailable (1013, "try again later": subscribe again once ``/readyz`` says
the store is back).
"""

from __future__ import annotations

import asyncio
from collections.abc import Mapping
from dataclasses import dataclass

from app.outputs import JSON, Output

SUBSCRIBER_QUEUE = 64
"""Results kept for a subscriber that has not read them yet."""


@dataclass(frozen=True)
class Ending:
    """Why a subscription ended: the WebSocket close code and reason."""

    code: int
    reason: str


SESSION_ENDED = Ending(1000, "session ended")
STORE_UNAVAILABLE = Ending(1013, "store unavailable")
SESSION_UNREADABLE = Ending(1011, "session unreadable (quarantined)")
"""The store holds data of the session it cannot read: a permanent fault, do not retry."""
SESSION_RELOADED = Ending(1013, "session reloaded from the store")
"""The session was evicted from memory after a failed step; subscribe again."""


@dataclass(frozen=True)
class Published:
    """A ``result`` message in each output it was written in (:data:`~app.outputs.JSON` always)."""

    texts: Mapping[Output, str]

    @property
    def text(self) -> str:
        """The message with the contract's JSON result in the session frame."""
        return self.texts[JSON]


class Subscriber:
    """One subscriber's queue of results, closed by an :class:`Ending`; ``output``: how it wants
    them written."""

    def __init__(self, capacity: int = SUBSCRIBER_QUEUE, *, output: Output = JSON) -> None:
        self.queue: asyncio.Queue[Published | Ending] = asyncio.Queue(maxsize=capacity)
        self.output = output
        self.dropped = 0
        self.closed = False

    def offer(self, message: Published | Ending) -> None:
        """Queue ``message``, dropping the oldest queued ones if the queue is full."""
        if self.closed:
            return
        while self.queue.full():
            self.queue.get_nowait()
            self.dropped += 1
        self.queue.put_nowait(message)
        if isinstance(message, Ending):
            self.closed = True

    async def next(self) -> Published | Ending:
        """The next message, or why the subscription ended."""
        return await self.queue.get()


class Hub:
    """The subscribers of one session."""

    def __init__(self) -> None:
        self._subscribers: set[Subscriber] = set()

    def subscribe(self, capacity: int = SUBSCRIBER_QUEUE, *, output: Output = JSON) -> Subscriber:
        """A new subscriber that receives every message published from now on."""
        subscriber = Subscriber(capacity, output=output)
        self._subscribers.add(subscriber)
        return subscriber

    def outputs(self) -> set[Output]:
        """The outputs the subscribers want (the steps write each of them too)."""
        return {subscriber.output for subscriber in self._subscribers}

    def unsubscribe(self, subscriber: Subscriber) -> None:
        """Stop delivering to ``subscriber``."""
        self._subscribers.discard(subscriber)

    def publish(self, message: Published) -> None:
        """Deliver ``message`` to every subscriber (never waits)."""
        for subscriber in self._subscribers:
            subscriber.offer(message)

    def close(self, ending: Ending = SESSION_ENDED) -> None:
        """End every subscription, telling each subscriber why."""
        for subscriber in self._subscribers:
            subscriber.offer(ending)
        self._subscribers.clear()

    def __len__(self) -> int:
        return len(self._subscribers)
