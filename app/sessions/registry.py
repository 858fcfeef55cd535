"""The live sessions: one engine per session behind a lock, logged before acknowledged.

Per session (:class:`LiveSession`): the engine, an ``asyncio.Lock`` that
applies inputs one at a time in arrival order, and a :class:`~app.sessions.hub.Hub`
for subscribers. The registry is the cache of the sessions in memory (loaded
from the store on first use, rebuilt from its latest snapshot plus the log
after it) and holds the parts that work on them:

- :class:`~app.sessions.pipeline.InputPipeline`: check, apply, log durably,
  publish, snapshot (:meth:`SessionRegistry.submit`);
- :class:`~app.cluster.link.ClusterLink`: leases, catching up with the store,
  fan-out through Redis, for several instances sharing a store;
- :class:`~app.sessions.expiry.SessionExpiry`: a session without input for
  ``session_idle_seconds`` is ended.

Outages: a store that cannot be reached raises
:class:`~app.errors.StoreUnavailable` (503 with ``Retry-After``); an input
whose append failed is not acknowledged, and its session is evicted (its
subscribers are closed with 1013 "store unavailable") and rebuilt from the
store on its next use, once the store answers again. On start every stored
session is restored (:meth:`SessionRegistry.restore_all`).

A session whose config names no sensor accepts any sensor id: each new one
joins the engine (default reliability and P_D, no field of view) when its
first input is applied, up to ``max_sensors``; the snapshot keeps the list.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
from collections.abc import Callable, Iterator
from datetime import datetime
from typing import Any, TypeVar

import anyio

from app.cluster.fanout import ResultFanout
from app.cluster.lease import SessionLeases
from app.cluster.link import ClusterLink
from app.cluster.quotas import TenantQuotas, open_quotas
from app.errors import SessionNotFound, SessionUnreadable, StoreUnavailable
from app.inputs import DecodedKind, Input
from app.metrics import ServiceMetrics
from app.outputs import JSON, Output
from app.outputs.json_results import track_fields
from app.runtime import LoopLag, without_collection
from app.sessions.expiry import SessionExpiry
from app.sessions.hub import SESSION_ENDED, SESSION_UNREADABLE, Ending, Subscriber
from app.sessions.live import LiveSession, new_session, restore_snapshot
from app.sessions.pipeline import InputPipeline
from app.sessions.translate import PlainObject
from app.sessions.work import TINY_WORK, Receipt, compute
from app.settings import Settings
from app.stores import SessionLoad, SessionRecord, Store

logger = logging.getLogger("credal_fusion.sessions")
T = TypeVar("T")


class SessionRegistry:
    """Every live session of the process (the cache), loaded from and logged to the store, and
    the parts that work on them: :attr:`pipeline` (inputs), :attr:`cluster` (several
    instances), :attr:`expiry` (idle sessions)."""

    def __init__(
        self,
        store: Store,
        settings: Settings,
        metrics: ServiceMetrics,
        *,
        leases: SessionLeases | None = None,
        fanout: ResultFanout | None = None,
        quotas: TenantQuotas | None = None,
        owner: str | None = None,
        loop_lag: LoopLag | None = None,
    ) -> None:
        self.store = store
        self.loop_lag = loop_lag
        """How late the event loop runs (the overload guard's measure); None: never refused."""
        self.settings = settings
        self.metrics = metrics
        self.shared = store.shared
        """Several instances share the store: leases, fan-out through it, fresh reads."""
        self._sessions: dict[str, LiveSession] = {}
        self._load_lock = asyncio.Lock()
        self._tokens: dict[str, str] = {}
        """Token hash → id of the live sessions in memory (the rate limit's verified identities)."""
        self.quarantined: dict[str, str] = {}
        """Sessions the store holds but cannot read: id → what of it (until deleted)."""
        self.store_corrupt: str | None = None
        """Why the store itself is damaged, once seen (a permanent fault: /readyz says it)."""
        self.quotas = quotas or open_quotas(
            store, settings.tenant_inputs_per_second, settings.tenant_work_per_minute
        )
        """The tenants' input quotas (:mod:`app.cluster.quotas`)."""
        self.pipeline = InputPipeline(self)
        self.cluster = ClusterLink(self, leases, fanout, owner)
        self.expiry = SessionExpiry(self)

    def __len__(self) -> int:
        return len(self._sessions)

    def __iter__(self) -> Iterator[LiveSession]:
        return iter(list(self._sessions.values()))

    async def io(self, function: Callable[..., T], *args: Any, size: int = 0) -> T:
        """A store call: inline for a store that does not block on I/O (``Store.blocking``,
        unless it encodes more than :data:`TINY_WORK` items), in a worker thread otherwise
        (without garbage collection for a big one, :func:`app.runtime.collection_paused`)."""
        call = functools.partial(function, *args)
        if size <= TINY_WORK:
            return await anyio.to_thread.run_sync(call) if self.store.blocking else call()
        return await anyio.to_thread.run_sync(without_collection(call))

    async def append(
        self,
        session_id: str,
        seq: int,
        entry_input: PlainObject,
        received_at: datetime,
        size: int = 0,
    ) -> bool:
        """Log an input (:meth:`~app.stores.base.Store.append`): returns once it is durable.
        A store that commits on a thread of its own (sqlite's ``append_queued``: group
        commit) is handed the input and awaited, without a worker thread per input; any
        other store's ``append`` is a store call (:meth:`io`)."""
        queued = getattr(self.store, "append_queued", None)
        if queued is None:
            return await self.io(
                self.store.append, session_id, seq, entry_input, received_at, size=size
            )
        loop = asyncio.get_running_loop()
        logged: asyncio.Future[bool] = loop.create_future()

        def settled(listened: bool, error: Exception | None) -> None:  # the committer's thread
            loop.call_soon_threadsafe(_settle, logged, listened, error)

        queued(session_id, seq, entry_input, received_at, settled)
        return await logged

    def add(self, session: LiveSession) -> LiveSession:
        """Register a session just created in the store (:func:`~app.sessions.live.new_session`)."""
        self._sessions[session.id] = session
        self._tokens[session.record.token_hash] = session.id
        return session

    def session_of_token(self, token_hash: str) -> LiveSession | None:
        """The live session held in memory whose token hashes to ``token_hash``, if any."""
        session_id = self._tokens.get(token_hash)
        return None if session_id is None else self._sessions.get(session_id)

    def tenant_of_token(self, token_hash: str) -> str | None:
        """The tenant of the live session (held in memory) whose token hashes to ``token_hash``."""
        session_id = self._tokens.get(token_hash)
        session = None if session_id is None else self._sessions.get(session_id)
        return None if session is None else session.record.tenant

    async def record(self, session_id: str) -> SessionRecord | None:
        """The stored record of a live session (from memory when the session is loaded)."""
        session = self._sessions.get(session_id)
        if session is not None:
            return session.record
        self._refuse_quarantined(session_id)
        try:
            return await self.io(self.store.get_session, session_id)
        except SessionUnreadable as unreadable:
            raise self.quarantine(unreadable) from None

    def _refuse_quarantined(self, session_id: str) -> None:
        what = self.quarantined.get(session_id)
        if what is not None:
            raise SessionUnreadable(session_id, what)

    def quarantine(self, unreadable: SessionUnreadable) -> SessionUnreadable:
        """Set a session the store cannot read aside (it is served no more, the rest is);
        ``/readyz`` and ``/metrics`` list it. Returns the error, to raise."""
        session_id = unreadable.session_id
        if session_id not in self.quarantined:
            logger.error(
                "session %s quarantined: its stored %s cannot be read", session_id, unreadable.what
            )
        self.quarantined[session_id] = unreadable.what
        self.metrics.quarantined.set(len(self.quarantined))
        self.discard(session_id, SESSION_UNREADABLE)
        return unreadable

    async def get(self, session_id: str) -> LiveSession:
        """The live session ``session_id``, loaded from the store if it is not in memory."""
        session = self._sessions.get(session_id)
        if session is not None:
            return session
        async with self._load_lock:
            session = self._sessions.get(session_id)
            if session is None:
                self._refuse_quarantined(session_id)
                try:
                    session = await self._load(session_id)
                except SessionUnreadable as unreadable:
                    raise self.quarantine(unreadable) from None
                self._sessions[session_id] = session
                self._tokens[session.record.token_hash] = session_id
        return session

    async def _load(self, session_id: str) -> LiveSession:
        record = await self.io(self.store.get_session, session_id)
        if record is None:
            raise SessionNotFound(session_id)
        load = await self.io(self.store.load, session_id)
        try:
            return await anyio.to_thread.run_sync(
                functools.partial(self.rebuild, load.session, load)
            )
        except Exception as error:  # a stored config or snapshot the engine cannot take
            logger.error("session %s: rebuild failed (%s)", session_id, type(error).__name__)
            raise SessionUnreadable(session_id, "state") from error

    def rebuild(self, record: SessionRecord, load: SessionLoad) -> LiveSession:
        """Snapshot + replay of the log after it (runs in a worker thread)."""
        session = new_session(record)
        if load.snapshot is not None:
            restore_snapshot(session, load.snapshot)
        self.pipeline.replay(session, load.entries)
        session.seq = max(session.seq, load.last_seq)
        return session

    async def restore_when_available(self, retry_s: float = 1.0) -> None:
        """:meth:`restore_all` as soon as the store answers (started while it is down: the
        service serves meanwhile, ``/readyz`` says 503 and inputs get 503 with ``Retry-After``)."""
        while True:
            await anyio.sleep(retry_s)
            try:
                restored = await self.restore_all()
            except StoreUnavailable:
                continue
            self.metrics.sessions.set(await self.io(self.store.count_sessions))
            logger.info("store available: %d sessions restored", restored)
            return

    async def restore_all(self) -> int:
        """Load every stored session (on start); returns how many. A session the store cannot
        read is quarantined (:meth:`quarantine`): the others are served."""
        for session_id in await self.io(self.store.session_ids):
            with contextlib.suppress(SessionUnreadable, SessionNotFound):  # quarantined, or gone
                await self.get(session_id)
        return len(self._sessions)

    def discard(self, session_id: str, ending: Ending = SESSION_ENDED) -> None:
        """Forget a session (deleted, or to be rebuilt from the store): its subscribers are
        told why; inputs waiting for its lock go to the session as the store has it."""
        session = self._sessions.pop(session_id, None)
        if session is not None:
            self._tokens.pop(session.record.token_hash, None)
            session.closed = True
            session.hub.close(ending)
        self.cluster.forget(session_id)

    async def delete(self, session_id: str) -> bool:
        """End a session in the store and in memory (and give its lease up); a quarantined
        session is deleted whole (what could not be read goes too)."""
        deleted = await self.io(self.store.delete_session, session_id)
        if self.quarantined.pop(session_id, None) is not None:
            self.metrics.quarantined.set(len(self.quarantined))
        self.discard(session_id)
        await self.cluster.release(session_id)
        self.metrics.sessions.set(await self.io(self.store.count_sessions))
        return bool(deleted)

    async def aclose(self) -> None:
        """Shutdown: end local subscriptions, release the leases this instance holds."""
        for session in self:
            session.hub.close()
        await self.cluster.aclose()

    async def picture(self, session: LiveSession, at: float | None, output: Output = JSON) -> str:
        """The live fused tracks predicted to ``at`` (default: the fusion time) written as
        ``output``, built off the event loop."""
        async with session.lock:
            engine = session.engine
            seq = session.seq
            if engine is None or engine.time is None:
                return output.picture(seq, at, ())
            time_of = engine.time if at is None else at
            return await compute(
                len(engine.tracks), lambda: output.picture(seq, time_of, engine.picture(at))
            )

    async def track_detail(self, session: LiveSession, track_id: str) -> PlainObject | None:
        """One live fused track at the fusion time with its history (for ``wire_json``), or ``None``."""
        async with session.lock:
            engine = session.engine
            track = next((t for t in session.tracks if t.id == track_id), None)
            if engine is None or track is None:
                return None
            view = next(view for view in engine.picture() if view.id == track_id)
            return {
                "track": track_fields([view])[0],
                "history": [{"time": time, "state": state} for time, state in track.history],
            }

    def loaded(self, session_id: str) -> LiveSession | None:
        """The session if it is in memory (not loaded from the store)."""
        return self._sessions.get(session_id)

    # ------------------------------------------------------------ the parts' faces
    @property
    def fanout(self) -> ResultFanout:
        """Results fanned out to every instance (:attr:`cluster`)."""
        return self.cluster.fanout

    async def submit(
        self,
        session: LiveSession,
        submitted: Input,
        *,
        explain: bool = False,
        output: Output = JSON,
        idempotency_key: str | None = None,
        received_at: Receipt | None = None,
    ) -> str:
        """:meth:`InputPipeline.submit`."""
        return await self.pipeline.submit(
            session,
            submitted,
            explain=explain,
            output=output,
            idempotency_key=idempotency_key,
            received_at=received_at,
        )

    async def submit_decoded(
        self,
        session: LiveSession,
        kind: DecodedKind[Any],
        data: bytes,
        parameters: Any,
        *,
        explain: bool = False,
        output: Output = JSON,
        received_at: Receipt | None = None,
    ) -> str:
        """:meth:`InputPipeline.submit_decoded`."""
        return await self.pipeline.submit_decoded(
            session, kind, data, parameters, explain=explain, output=output, received_at=received_at
        )

    async def current(self, session: LiveSession) -> LiveSession:
        """:meth:`ClusterLink.current`."""
        return await self.cluster.current(session)

    async def subscribe(self, session: LiveSession, output: Output = JSON) -> Subscriber:
        """:meth:`ClusterLink.subscribe`."""
        return await self.cluster.subscribe(session, output)

    def unsubscribe(self, session: LiveSession, subscriber: Subscriber) -> None:
        """:meth:`ClusterLink.unsubscribe`."""
        self.cluster.unsubscribe(session, subscriber)

    async def keep_lease(self, session: LiveSession) -> bool:
        """:meth:`ClusterLink.keep_lease`."""
        return await self.cluster.keep_lease(session)

    def leases_held(self) -> int:
        """:meth:`ClusterLink.leases_held`."""
        return self.cluster.leases_held()

    async def expire_idle(self, now: datetime | None = None) -> list[str]:
        """:meth:`SessionExpiry.expire_idle`."""
        return await self.expiry.expire_idle(now)

    async def run_expiry(self) -> None:
        """:meth:`SessionExpiry.run`."""
        await self.expiry.run()


def _settle(future: asyncio.Future[bool], listened: bool, error: Exception | None) -> None:
    """Resolve an append's future on the event loop (unless its waiter has gone)."""
    if future.done():
        return
    if error is not None:
        future.set_exception(error)
    else:
        future.set_result(listened)
