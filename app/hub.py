"""Fan-out of a session's results to its subscribers, never with an unbounded backlog.

Each subscriber has a bounded queue. Publishing never waits: when a
subscriber's queue is full its oldest result is dropped to make room, so a
slow subscriber skips ahead to the latest state (the ``seq`` numbers show the
gap) and a fast one receives every result in order. Everything runs on the
event loop thread.
"""

from __future__ import annotations

import asyncio

SUBSCRIBER_QUEUE = 64
"""Results kept for a subscriber that has not read them yet."""


class Subscriber:
    """One subscriber's queue of serialised messages; ``None`` marks the end."""

    def __init__(self, capacity: int = SUBSCRIBER_QUEUE) -> None:
        self.queue: asyncio.Queue[str | None] = asyncio.Queue(maxsize=capacity)
        self.dropped = 0
        self.closed = False

    def offer(self, message: str | None) -> None:
        """Queue ``message``, dropping the oldest queued ones if the queue is full."""
        if self.closed:
            return
        while self.queue.full():
            self.queue.get_nowait()
            self.dropped += 1
        self.queue.put_nowait(message)
        if message is None:
            self.closed = True

    async def next(self) -> str | None:
        """The next message (``None``: the session ended)."""
        return await self.queue.get()


class Hub:
    """The subscribers of one session."""

    def __init__(self) -> None:
        self._subscribers: set[Subscriber] = set()

    def subscribe(self, capacity: int = SUBSCRIBER_QUEUE) -> Subscriber:
        """A new subscriber that receives every message published from now on."""
        subscriber = Subscriber(capacity)
        self._subscribers.add(subscriber)
        return subscriber

    def unsubscribe(self, subscriber: Subscriber) -> None:
        """Stop delivering to ``subscriber``."""
        self._subscribers.discard(subscriber)

    def publish(self, message: str) -> None:
        """Deliver ``message`` to every subscriber (never waits)."""
        for subscriber in self._subscribers:
            subscriber.offer(message)

    def close(self) -> None:
        """End every subscription (the session ended)."""
        for subscriber in self._subscribers:
            subscriber.offer(None)
        self._subscribers.clear()

    def __len__(self) -> int:
        return len(self._subscribers)
