"""The cluster link of the live sessions: what several instances sharing a store need.

With the ``redis`` store several instances share the sessions
(:mod:`app.cluster.lease`, :mod:`app.cluster.fanout`): before applying an input
the instance takes (or renews) the session's lease — a session another live
instance holds answers 503 with ``Retry-After``; an instance that (re)takes a
lease first rebuilds the engine from the store if the log moved on meanwhile.
The store's sequence check is the fence: an append that meets
``SequenceConflict`` (overtaken while paused past the lease) rebuilds the
session from the store and applies the input once more. Results go out
through Redis pub/sub, and each instance forwards the results of a session
with local subscribers into that session's hub, so a ``subscribe`` client on
any instance receives every result in order. Leases are released when a
session is deleted and when the instance shuts down. Reads first ask the store
for the session's ``last_seq`` (:meth:`ClusterLink.current`): a session deleted
through another instance is gone (404) and one moved on by another instance is
caught up from the log first, so no instance answers an old ``seq``.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import time
from typing import TYPE_CHECKING

import anyio

from app.cluster.fanout import ResultFanout, open_fanout
from app.cluster.lease import SessionLeases, new_owner_id, open_leases
from app.errors import SessionLeased, SessionNotFound
from app.outputs import JSON, Output
from app.sessions.hub import STORE_UNAVAILABLE, Published, Subscriber
from app.sessions.live import LiveSession

if TYPE_CHECKING:
    from app.sessions.registry import SessionRegistry

logger = logging.getLogger("credal_fusion.sessions")

RENEWED_WITHIN = 0.4
"""An input within this part of the TTL after the lease was taken or renewed is applied
without renewing it again (the store's lease then has at least 0.6 TTL left): one round trip
per 0.4 TTL of a busy session instead of one per input."""


class ClusterLink:
    """Leases, catching up with the store, and results fanned out through Redis."""

    def __init__(
        self,
        registry: SessionRegistry,
        leases: SessionLeases | None = None,
        fanout: ResultFanout | None = None,
        owner: str | None = None,
    ) -> None:
        self.registry = registry
        store = registry.store
        self.leases = leases or open_leases(store)
        self.fanout = fanout or open_fanout(store)
        self.owner = owner or new_owner_id()
        self._forwarders: dict[str, asyncio.Task[None]] = {}

    async def hold_lease(self, session: LiveSession) -> None:
        """Take or renew the session's lease; after a (re)take, catch up with the store's log."""
        ttl_ms = self.registry.settings.lease_ttl_ms
        now = time.monotonic()
        if now < session.lease_deadline - RENEWED_WITHIN * ttl_ms / 1000:
            return  # taken or renewed less than 0.4 TTL ago: held for 0.6 TTL more, no round trip
        held = now < session.lease_deadline
        if not await self.registry.io(self.leases.acquire, session.id, self.owner, ttl_ms):
            session.lease_deadline = 0.0
            left_ms = await self.registry.io(self.leases.remaining_ms, session.id)
            raise SessionLeased(session.id, left_ms)  # Retry-After: the lease's time left
        session.lease_deadline = now + 0.8 * ttl_ms / 1000  # a margin for clock and round trips
        if not held:
            last = await self.registry.io(self.registry.store.last_seq, session.id)
            if last != session.seq:
                await self.catch_up(session, last)

    async def keep_lease(self, session: LiveSession) -> bool:
        """Renew the session's lease if this instance holds it (a stream does, every third of
        the TTL); ``False`` if another instance holds it now. Not holding it (no input yet,
        or a single-process store) is not losing it."""
        if not self.registry.shared or session.lease_deadline == 0.0:
            return True
        ttl_ms = self.registry.settings.lease_ttl_ms
        now = time.monotonic()
        if not await self.registry.io(self.leases.renew, session.id, self.owner, ttl_ms):
            session.lease_deadline = 0.0
            return await self.registry.io(self.leases.holder, session.id) in (None, self.owner)
        session.lease_deadline = now + 0.8 * ttl_ms / 1000
        return True

    async def current(self, session: LiveSession) -> LiveSession:
        """The session at the store's latest ``seq`` (several instances): 404 if it was deleted
        through another instance, caught up from the log if another instance moved it on."""
        if not self.registry.shared:
            return session  # this process applies every input: its memory is the current state
        try:
            last = await self.registry.io(self.registry.store.last_seq, session.id)
        except SessionNotFound:
            self.registry.discard(session.id)
            raise
        if last > session.seq:
            async with session.lock:
                if session.closed:
                    raise SessionNotFound(session.id)
                if last > session.seq:
                    await self.catch_up(session, last)
        return session

    async def catch_up(self, session: LiveSession, last: int) -> None:
        """Apply the inputs logged after the session's ``seq`` (under its lock); rebuild from
        the snapshot instead when the log no longer holds them all (compacted) or went back."""
        entries = await self.registry.io(self.registry.store.entries, session.id, session.seq)
        contiguous = bool(entries) and entries[0].seq == session.seq + 1
        if not contiguous or entries[-1].seq < last or last < session.seq:
            await self.refresh(session)
            return
        await anyio.to_thread.run_sync(
            functools.partial(self.registry.pipeline.replay, session, entries)
        )
        session.since_snapshot = 0

    async def refresh(self, session: LiveSession) -> None:
        """Rebuild the session's engine in place from the store (another instance moved it on)."""
        load = await self.registry.io(self.registry.store.load, session.id)
        fresh = await anyio.to_thread.run_sync(
            functools.partial(self.registry.rebuild, load.session, load)
        )
        logger.info("session %s: rebuilt from the store at seq %d", session.id, fresh.seq)
        session.engine, session.time_epoch = fresh.engine, fresh.time_epoch
        session.seq = fresh.seq
        session.sensor_inputs = fresh.sensor_inputs
        session.last_input_at = fresh.last_input_at
        session.answered, session.answered_chars = fresh.answered, fresh.answered_chars
        session.since_snapshot = 0

    async def publish(self, session: LiveSession, message: str) -> None:
        """Send a result to the session's subscribers on every instance (logged, never raised)."""
        try:
            await self.fanout.publish(session.id, message)
        except Exception:
            logger.exception("session %s: publishing result %d failed", session.id, session.seq)

    async def subscribe(self, session: LiveSession, output: Output = JSON) -> Subscriber:
        """A subscriber of every result of the session published from now on, on any instance,
        written as ``output`` (beside each step, when this instance applies it)."""
        subscriber = session.hub.subscribe(output=output)
        if self.registry.shared:
            try:
                await self._forward(session)
            except BaseException:
                session.hub.unsubscribe(subscriber)
                raise
        return subscriber

    def unsubscribe(self, session: LiveSession, subscriber: Subscriber) -> None:
        """Stop delivering to ``subscriber``; the last one of a session stops its forwarding."""
        session.hub.unsubscribe(subscriber)
        if not len(session.hub):
            forwarder = self._forwarders.pop(session.id, None)
            if forwarder is not None:
                forwarder.cancel()

    async def _forward(self, session: LiveSession) -> None:
        """Forward the session's results from Redis into its hub; returns once subscribed."""
        running = self._forwarders.get(session.id)
        if running is not None and not running.done():
            return
        subscribed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

        async def forward() -> None:
            try:
                async with self.fanout.subscribe(session.id) as results:
                    subscribed.set_result(None)
                    async for message in results:
                        session.hub.publish(Published({JSON: message}))
            except Exception as error:
                if not subscribed.done():
                    subscribed.set_exception(error)
                else:
                    logger.exception("session %s: result forwarding failed", session.id)
                    self.registry.discard(session.id, STORE_UNAVAILABLE)

        self._forwarders[session.id] = asyncio.create_task(
            forward(), name=f"forward-results:{session.id}"
        )
        await subscribed

    def leases_held(self) -> int:
        """Sessions whose lease this instance surely holds now (0 without a shared store)."""
        now = time.monotonic()
        if not self.registry.shared:
            return 0
        return sum(session.lease_deadline > now for session in self.registry)

    def forget(self, session_id: str) -> None:
        """Stop forwarding the results of a session this instance no longer holds."""
        forwarder = self._forwarders.pop(session_id, None)
        if forwarder is not None:
            forwarder.cancel()

    async def release(self, session_id: str) -> None:
        """Give up the session's lease (it was deleted)."""
        if self.registry.shared:
            await self.registry.io(self.leases.release, session_id, self.owner)

    async def aclose(self) -> None:
        """Shutdown: stop forwarding, release the leases this instance holds."""
        for forwarder in self._forwarders.values():
            forwarder.cancel()
        for forwarder in list(self._forwarders.values()):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await forwarder
        self._forwarders.clear()
        if self.registry.shared:
            now = time.monotonic()
            for session in self.registry:
                if session.lease_deadline > now:
                    try:
                        await self.registry.io(self.leases.release, session.id, self.owner)
                    except Exception:
                        logger.exception("session %s: lease release failed", session.id)
        await self.fanout.aclose()
