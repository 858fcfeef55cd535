"""Result fan-out: every result of a session reaches its subscribers, on any instance.

The instance that applies an input publishes the result once; each
``subscribe`` WebSocket, whichever instance it is connected to, receives it.
:class:`RedisFanout` goes through Redis pub/sub (channel ``P:{sid}:results``,
one pub/sub connection per subscription); :class:`LocalFanout` stays in the
process, for the memory and sqlite stores.

A subscription buffers at most ``max_pending`` results: when a subscriber
falls behind, the oldest are dropped (and counted in
:attr:`Subscription.dropped`), so a slow subscriber gets the latest state and
never an unbounded backlog — in this process or in Redis's output buffers.
Results carry their ``seq``, so a subscriber can tell a gap.

Use in the routes (recipe)
--------------------------
``fanout = open_fanout(store)`` once in the lifespan (``await fanout.aclose()``
at shutdown). After an input is logged and applied::

    await fanout.publish(sid, result.model_dump_json())

and in the ``subscribe`` WebSocket::

    async with fanout.subscribe(sid) as results:   # subscribed once entered
        async for result_json in results:
            await websocket.send_text(result_json)

Entering the ``async with`` returns only once the subscription is in place,
so every result published afterwards is delivered (subscribe first, then send
the current state, to miss nothing). ``publish`` and the iteration must run on
the event loop the fan-out was first used on; from a worker thread use
``asyncio.run_coroutine_threadsafe(fanout.publish(...), loop)``.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import deque
from collections.abc import Awaitable, Callable
from types import TracebackType
from typing import Protocol, Self, runtime_checkable

import redis.asyncio
from redis.asyncio.client import PubSub

from app.cluster import shared_redis
from app.stores.base import Store, unavailable_on
from app.stores.redis import CONNECT_TIMEOUT_S, SOCKET_TIMEOUT_S, UNREACHABLE
from app.stores.redis_keys import DEFAULT_PREFIX, RedisKeys

DEFAULT_MAX_PENDING = 64
SUBSCRIBE_TIMEOUT_S = 10.0


class Subscription:
    """The results of one session as they are published: an async iterator of JSON texts.

    Use as ``async with``: entering subscribes, leaving unsubscribes.
    Iteration ends after :meth:`aclose`; it raises if the connection behind
    the subscription failed for good.
    """

    def __init__(self, session_id: str, max_pending: int = DEFAULT_MAX_PENDING) -> None:
        if max_pending < 1:
            raise ValueError(f"max_pending {max_pending}: must be at least 1")
        self.session_id = session_id
        self.max_pending = max_pending
        self.dropped = 0
        self._pending: deque[str] = deque()
        self._wakeup = asyncio.Event()
        self._closed = False
        self._failure: BaseException | None = None

    @property
    def pending(self) -> int:
        """Results received and not yet iterated."""
        return len(self._pending)

    def offer(self, result_json: str) -> None:
        """Queue a result, dropping the oldest one when ``max_pending`` are waiting."""
        if self._closed:
            return
        if len(self._pending) >= self.max_pending:
            self._pending.popleft()
            self.dropped += 1
        self._pending.append(result_json)
        self._wakeup.set()

    def fail(self, error: BaseException) -> None:
        """End the iteration with ``error`` (after the queued results)."""
        self._failure = error
        self._wakeup.set()

    async def start(self) -> None:
        """Subscribe (subclasses); returns once published results will be received."""

    async def aclose(self) -> None:
        """Unsubscribe; the iteration ends once the queued results are consumed."""
        self._closed = True
        self._wakeup.set()

    async def __aenter__(self) -> Self:
        await self.start()
        return self

    async def __aexit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        await self.aclose()

    def __aiter__(self) -> Self:
        return self

    async def __anext__(self) -> str:
        while not self._pending:
            if self._failure is not None:
                raise self._failure
            if self._closed:
                raise StopAsyncIteration
            self._wakeup.clear()
            await self._wakeup.wait()
        return self._pending.popleft()


@runtime_checkable
class ResultFanout(Protocol):
    """Publishing a session's results and subscribing to them."""

    async def publish(self, session_id: str, result_json: str) -> int:
        """Send a result to every subscriber of the session; how many subscriptions got it."""
        ...

    def subscribe(self, session_id: str) -> Subscription:
        """A subscription to the session's results (enter it with ``async with``)."""
        ...

    async def ping(self) -> None:
        """Return if results can be published now; :class:`~app.errors.StoreUnavailable` if not."""
        ...

    async def aclose(self) -> None:
        """Release connections; subscriptions end."""
        ...


class _LocalSubscription(Subscription):
    def __init__(self, fanout: LocalFanout, session_id: str, max_pending: int) -> None:
        super().__init__(session_id, max_pending)
        self._fanout = fanout

    async def start(self) -> None:
        self._fanout._subscriptions.setdefault(self.session_id, set()).add(self)

    async def aclose(self) -> None:
        subscribers = self._fanout._subscriptions.get(self.session_id)
        if subscribers is not None:
            subscribers.discard(self)
            if not subscribers:
                del self._fanout._subscriptions[self.session_id]
        await super().aclose()


class LocalFanout:
    """Fan-out inside one process (memory and sqlite stores)."""

    def __init__(self, max_pending: int = DEFAULT_MAX_PENDING) -> None:
        self.max_pending = max_pending
        self._subscriptions: dict[str, set[_LocalSubscription]] = {}

    async def publish(self, session_id: str, result_json: str) -> int:
        subscribers = list(self._subscriptions.get(session_id, ()))
        for subscription in subscribers:
            subscription.offer(result_json)
        return len(subscribers)

    def subscribe(self, session_id: str) -> Subscription:
        return _LocalSubscription(self, session_id, self.max_pending)

    async def ping(self) -> None:
        return None

    async def aclose(self) -> None:
        for subscribers in list(self._subscriptions.values()):
            for subscription in list(subscribers):
                await subscription.aclose()


class _RedisSubscription(Subscription):
    def __init__(
        self,
        client: redis.asyncio.Redis,
        channel: str,
        session_id: str,
        max_pending: int,
        registry: set[_RedisSubscription],
    ) -> None:
        super().__init__(session_id, max_pending)
        self._registry = registry
        self._client = client
        self._channel = channel
        self._pubsub: PubSub | None = None
        self._reader: asyncio.Task[None] | None = None

    async def start(self) -> None:
        pubsub = self._client.pubsub()
        self._pubsub = pubsub
        try:
            with unavailable_on((*UNREACHABLE, OSError), "redis"):
                await self._subscribe(pubsub)
        except BaseException:
            await self.aclose()
            raise
        self._reader = asyncio.create_task(self._read(pubsub), name=f"fanout:{self._channel}")

    async def _subscribe(self, pubsub: PubSub) -> None:
        await pubsub.subscribe(self._channel)
        async with asyncio.timeout(SUBSCRIBE_TIMEOUT_S):
            while True:  # the server confirms: from now on, every publish reaches us
                message = await pubsub.get_message(timeout=SUBSCRIBE_TIMEOUT_S)
                if message is not None and message["type"] == "subscribe":
                    break

    async def _read(self, pubsub: PubSub) -> None:
        try:
            while True:
                message = await pubsub.get_message(ignore_subscribe_messages=True, timeout=None)
                if message is not None and message["type"] == "message":
                    self.offer(str(message["data"]))
        except asyncio.CancelledError:
            raise
        except Exception as error:  # the connection failed for good (redis-py retried)
            self.fail(error)

    async def aclose(self) -> None:
        if self._reader is not None:
            self._reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._reader
            self._reader = None
        if self._pubsub is not None:
            pubsub, self._pubsub = self._pubsub, None
            # Dropping the connection makes the server forget the subscription.
            # Typed through a variable: redis-py < 8.2 leaves aclose untyped, 8.2 types it.
            close: Callable[[], Awaitable[None]] = pubsub.aclose
            await close()
        self._registry.discard(self)
        await super().aclose()


class RedisFanout:
    """Fan-out through Redis pub/sub: subscribers on any instance receive every result.

    Parameters
    ----------
    url
        The Redis URL (the store's).
    prefix
        The deployment's key prefix (channels are named under it too: pub/sub
        channels are global to the server, not per database).
    max_pending
        Results a subscription buffers before dropping the oldest.
    """

    def __init__(
        self, url: str, prefix: str = DEFAULT_PREFIX, max_pending: int = DEFAULT_MAX_PENDING
    ) -> None:
        self.keys = RedisKeys(prefix)
        self.max_pending = max_pending
        self.client: redis.asyncio.Redis = redis.asyncio.Redis.from_url(
            url, decode_responses=True, socket_connect_timeout=CONNECT_TIMEOUT_S
        )
        """Subscriptions' connections: they wait for messages as long as it takes."""
        self.publisher: redis.asyncio.Redis = redis.asyncio.Redis.from_url(
            url,
            decode_responses=True,
            socket_connect_timeout=CONNECT_TIMEOUT_S,
            socket_timeout=SOCKET_TIMEOUT_S,
        )
        """Publishing and pings: a frozen Redis fails them within the store's timeout."""
        self._subscriptions: set[_RedisSubscription] = set()

    async def publish(self, session_id: str, result_json: str) -> int:
        return int(await self.publisher.publish(self.keys.results(session_id), result_json))

    def subscribe(self, session_id: str) -> Subscription:
        subscription = _RedisSubscription(
            self.client,
            self.keys.results(session_id),
            session_id,
            self.max_pending,
            self._subscriptions,
        )
        self._subscriptions.add(subscription)
        return subscription

    async def ping(self) -> None:
        with unavailable_on(UNREACHABLE, "redis"):
            await self.publisher.ping()

    async def aclose(self) -> None:
        for subscription in list(self._subscriptions):
            await subscription.aclose()
        await self.client.aclose()
        await self.publisher.aclose()


def open_fanout(store: Store, max_pending: int = DEFAULT_MAX_PENDING) -> ResultFanout:
    """The fan-out that goes with ``store``: Redis pub/sub for a shared store, else local."""
    backing = shared_redis(store)
    if backing is not None:
        return RedisFanout(backing.url, backing.keys.prefix, max_pending)
    return LocalFanout(max_pending)
