"""The live sessions: one engine per session behind a lock, logged before acknowledged.

Per session (:class:`LiveSession`): the engine, an ``asyncio.Lock`` that
applies inputs one at a time in arrival order, and a :class:`~app.sessions.hub.Hub`
for subscribers. One input (:meth:`SessionRegistry.submit`):

1. checks that need only the config (limits, sensor, dimensions, labels);
2. under the lock, the engine applies it (in a worker thread unless the work
   is tiny); a refusal changes nothing;
3. the input is appended to the store — durably for sqlite — and only then is
   the result returned and published. Steps 2–3 are shielded from
   cancellation (a client that goes away cannot leave the engine ahead of the
   log); if the append fails anyway, the session is evicted from memory and
   rebuilt from the store on its next use;
4. every ``snapshot_every`` inputs the engine state is snapshotted, and the
   log is compacted to the ``log_retention`` inputs behind that snapshot.

Outages: a store that cannot be reached raises
:class:`~app.http.errors.StoreUnavailable` (503 with ``Retry-After``); an input
whose append failed is not acknowledged, and its session is evicted (its
subscribers are closed with 1013 "store unavailable") and rebuilt from the
store on its next use, once the store answers again.

On start every stored session is restored from its latest snapshot plus the
log after it (:meth:`SessionRegistry.restore_all`); a session without input
for ``session_idle_seconds`` is ended (:meth:`SessionRegistry.expire_idle`).

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
session is deleted and when the instance shuts down. Reads (the picture, the
summary) first ask the store for the session's ``last_seq``
(:meth:`SessionRegistry.current`): a session deleted through another instance
is gone (404) and one moved on by another instance is caught up from the log
first, so no instance answers an old ``seq``; when the store cannot be asked,
the read answers 503 with ``Retry-After`` rather than a state that may be old.

A session whose config names no sensor accepts any sensor id: each new one
joins the engine (default reliability and P_D, no field of view) when its
first input is applied, up to ``max_sensors``; the snapshot keeps the list.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any, TypeVar

import anyio
from prometheus_client import Counter, Histogram

from api_schemas.config import SessionConfig
from api_schemas.consistency import detection_report_issues, track_report_issues
from api_schemas.reports import DetectionReport, TrackReport
from app.cluster.fanout import ResultFanout, open_fanout
from app.cluster.lease import SessionLeases, new_owner_id, open_leases
from app.geo.geojson import GeodeticOutput
from app.http.errors import (
    LimitExceeded,
    SessionLeased,
    SessionNotFound,
    StaleReport,
    StoreUnavailable,
    request_validation_error,
)
from app.http.responses import dumps
from app.metrics import ServiceMetrics
from app.runtime import without_collection
from app.sessions.hub import (
    SESSION_ENDED,
    SESSION_RELOADED,
    STORE_UNAVAILABLE,
    Ending,
    Published,
    Subscriber,
)
from app.sessions.live import LiveSession, new_session, restore_snapshot
from app.sessions.log import event_from_entry, log_input
from app.sessions.translate import (
    PlainObject,
    core_detection_report,
    fusion_config,
    picture_json,
    session_frame_report,
    session_geodetic,
    step_json,
    track_fields,
)
from app.settings import Settings
from app.stores import (
    LogEntry,
    SequenceConflict,
    SessionLoad,
    SessionRecord,
    Snapshot,
    Store,
)
from core.errors import StaleReport as CoreStaleReport
from core.fusion.config import FusionConfig
from core.fusion.engine import SessionEngine
from core.fusion.reports import FusedTrackView
from core.tracking.track import ScanTally

TINY_WORK = 64
"""Report tracks + live fused tracks up to which a step runs on the event loop.

Such a step costs about 2 ms of engine time: less than what a worker-thread
hop adds under load. Larger steps run in a worker thread."""

logger = logging.getLogger("credal_fusion.sessions")
T = TypeVar("T")
Report = TrackReport | DetectionReport


@dataclass
class Step:
    """An applied (not yet logged) input: the engine that holds it, its result as JSON text,
    the same with the tracks' geodetic positions if asked (by its sender or a subscriber),
    the input as it is logged (all built beside the step, off the event loop) and the CPU
    time of the engine step alone (the thread's)."""

    engine: SessionEngine
    fusion: FusionConfig
    result: str
    geodetic: str | None
    logged: PlainObject
    engine_cpu_s: float


@dataclass(frozen=True)
class InputSeries:
    """The metrics of one kind of input (``tracks``, ``detections``)."""

    inputs: Counter
    fusion_step: Histogram
    engine_cpu: Histogram


class SessionRegistry:
    """Every live session of the process, loaded from and logged to the store."""

    def __init__(
        self,
        store: Store,
        settings: Settings,
        metrics: ServiceMetrics,
        *,
        leases: SessionLeases | None = None,
        fanout: ResultFanout | None = None,
        owner: str | None = None,
    ) -> None:
        self.store = store
        self.settings = settings
        self.metrics = metrics
        self.shared = store.shared
        """Several instances share the store: leases, fan-out through it, fresh reads."""
        self.leases = leases or open_leases(store)
        self.fanout = fanout or open_fanout(store)
        self.owner = owner or new_owner_id()
        self._sessions: dict[str, LiveSession] = {}
        self._load_lock = asyncio.Lock()
        self._forwarders: dict[str, asyncio.Task[None]] = {}
        self._tokens: dict[str, str] = {}
        """Token hash → id of the live sessions in memory (the rate limit's verified identities)."""
        self._input_series: dict[str, InputSeries] = {}

    def __len__(self) -> int:
        return len(self._sessions)

    def __iter__(self) -> Iterator[LiveSession]:
        return iter(list(self._sessions.values()))

    # ------------------------------------------------------------ running work
    async def _io(self, function: Callable[..., T], *args: Any, size: int = 0) -> T:
        """A store call: inline for a store that does not block on I/O (``Store.blocking``,
        unless it encodes more than :data:`TINY_WORK` items), in a worker thread otherwise
        (without garbage collection for a big one, :func:`app.runtime.collection_paused`)."""
        call = functools.partial(function, *args)
        if size <= TINY_WORK:
            return await anyio.to_thread.run_sync(call) if self.store.blocking else call()
        return await anyio.to_thread.run_sync(without_collection(call))

    @staticmethod
    async def _compute(size: int, function: Callable[[], T]) -> T:
        """Numeric work: inline when tiny, in a worker thread otherwise (without garbage
        collection: :func:`app.runtime.collection_paused`)."""
        if size <= TINY_WORK:
            return function()
        return await anyio.to_thread.run_sync(without_collection(function))

    # ------------------------------------------------------------ lifecycle
    def check_config(self, config: SessionConfig) -> None:
        """Refuse a config the engine cannot run (422 located at the field)."""
        fusion_config(config, [] if config.sensors else ["probe"])

    def add(self, record: SessionRecord) -> LiveSession:
        """Register a session just created in the store."""
        session = new_session(record)
        self._sessions[record.id] = session
        self._tokens[record.token_hash] = record.id
        return session

    def knows_token(self, token_hash: str) -> bool:
        """Whether ``token_hash`` is the hash of a live session's token held in memory."""
        return token_hash in self._tokens

    async def record(self, session_id: str) -> SessionRecord | None:
        """The stored record of a live session (from memory when the session is loaded)."""
        session = self._sessions.get(session_id)
        if session is not None:
            return session.record
        return await self._io(self.store.get_session, session_id)

    async def get(self, session_id: str) -> LiveSession:
        """The live session ``session_id``, loaded from the store if it is not in memory."""
        session = self._sessions.get(session_id)
        if session is not None:
            return session
        async with self._load_lock:
            session = self._sessions.get(session_id)
            if session is None:
                session = await self._load(session_id)
                self._sessions[session_id] = session
                self._tokens[session.record.token_hash] = session_id
        return session

    async def _load(self, session_id: str) -> LiveSession:
        record = await self._io(self.store.get_session, session_id)
        if record is None:
            raise SessionNotFound(session_id)
        load = await self._io(self.store.load, session_id)
        return await anyio.to_thread.run_sync(functools.partial(self._rebuild, load.session, load))

    def _rebuild(self, record: SessionRecord, load: SessionLoad) -> LiveSession:
        """Snapshot + replay of the log after it (runs in a worker thread)."""
        session = new_session(record)
        if load.snapshot is not None:
            restore_snapshot(session, load.snapshot)
        self._replay(session, load.entries)
        session.seq = max(session.seq, load.last_seq)
        return session

    def _replay(self, session: LiveSession, entries: list[LogEntry]) -> None:
        """Apply logged inputs to the session in order (a worker thread, under its lock)."""
        record = session.record
        for entry in entries:
            event = event_from_entry(entry)
            try:
                step = self._apply(session, event.report, explain=False)
            except Exception:
                logger.exception("session %s: replay of input %d failed", record.id, entry.seq)
            else:
                session.engine, session.fusion = step.engine, step.fusion
            sensor = str(entry.input.get("report", {}).get("sensor", ""))
            session.sensor_inputs[sensor] = session.sensor_inputs.get(sensor, 0) + 1
            session.seq = entry.seq
            session.last_input_at = entry.received_at

    async def restore_when_available(self, retry_s: float = 1.0) -> None:
        """:meth:`restore_all` as soon as the store answers (started while it is down: the
        service serves meanwhile, ``/readyz`` says 503 and inputs get 503 with ``Retry-After``)."""
        while True:
            await anyio.sleep(retry_s)
            try:
                restored = await self.restore_all()
            except StoreUnavailable:
                continue
            self.metrics.sessions.set(await self._io(self.store.count_sessions))
            logger.info("store available: %d sessions restored", restored)
            return

    async def restore_all(self) -> int:
        """Load every stored session (on start); returns how many."""
        records = await self._io(self.store.list_sessions)
        for record in records:
            try:
                await self.get(record.id)
            except Exception:
                logger.exception("session %s could not be restored", record.id)
        return len(self._sessions)

    def discard(self, session_id: str, ending: Ending = SESSION_ENDED) -> None:
        """Forget a session (deleted, or to be rebuilt from the store): its subscribers are
        told why; inputs waiting for its lock go to the session as the store has it."""
        session = self._sessions.pop(session_id, None)
        if session is not None:
            self._tokens.pop(session.record.token_hash, None)
            session.closed = True
            session.hub.close(ending)
        forwarder = self._forwarders.pop(session_id, None)
        if forwarder is not None:
            forwarder.cancel()

    async def delete(self, session_id: str) -> bool:
        """End a session in the store and in memory (and give its lease up)."""
        deleted = await self._io(self.store.delete_session, session_id)
        self.discard(session_id)
        if self.shared:
            await self._io(self.leases.release, session_id, self.owner)
        self.metrics.sessions.set(await self._io(self.store.count_sessions))
        return bool(deleted)

    async def aclose(self) -> None:
        """Shutdown: end local subscriptions, release the leases this instance holds."""
        for session in self:
            session.hub.close()
        for forwarder in self._forwarders.values():
            forwarder.cancel()
        for forwarder in list(self._forwarders.values()):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await forwarder
        self._forwarders.clear()
        if self.shared:
            now = time.monotonic()
            for session in self:
                if session.lease_deadline > now:
                    try:
                        await self._io(self.leases.release, session.id, self.owner)
                    except Exception:
                        logger.exception("session %s: lease release failed", session.id)
        await self.fanout.aclose()

    async def expire_idle(self, now: datetime | None = None) -> list[str]:
        """End every session idle for longer than ``session_idle_seconds`` (0: never)."""
        idle = self.settings.session_idle_seconds
        if idle <= 0:
            return []
        moment = now or datetime.now(UTC)
        expired = [
            session.id
            for session in self
            if moment - session.idle_since() > timedelta(seconds=idle) and not session.lock.locked()
        ]
        if self.shared:
            expired = [sid for sid in expired if not await self._active_elsewhere(sid, moment)]
        for session_id in expired:
            logger.info("session %s expired after %.0f s without input", session_id, idle)
            await self.delete(session_id)
        return expired

    async def _active_elsewhere(self, session_id: str, now: datetime) -> bool:
        """Whether another instance moved the session's log on (then it is not idle)."""
        session = self._sessions.get(session_id)
        try:
            last = await self._io(self.store.last_seq, session_id)
        except SessionNotFound:
            self.discard(session_id)
            return True
        if session is not None and last != session.seq:
            session.last_input_at = now  # it will be rebuilt when this instance next applies
            return True
        return False

    async def run_expiry(self) -> None:
        """Check idle sessions periodically until cancelled."""
        idle = self.settings.session_idle_seconds
        if idle <= 0:
            return
        period = min(60.0, max(1.0, idle / 10.0))
        while True:
            await anyio.sleep(period)
            try:
                await self.expire_idle()
            except Exception:
                logger.exception("idle expiry failed")

    def leases_held(self) -> int:
        """Sessions whose lease this instance surely holds now (0 without a shared store)."""
        now = time.monotonic()
        return sum(session.lease_deadline > now for session in self) if self.shared else 0

    # ------------------------------------------------------------ subscribers
    async def subscribe(self, session: LiveSession, *, geodetic: bool = False) -> Subscriber:
        """A subscriber of every result of the session published from now on, on any instance
        (``geodetic``: it wants the tracks' geodetic positions, written beside each step)."""
        subscriber = session.hub.subscribe(geodetic=geodetic)
        if self.shared:
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
                        session.hub.publish(Published(message))
            except Exception as error:
                if not subscribed.done():
                    subscribed.set_exception(error)
                else:
                    logger.exception("session %s: result forwarding failed", session.id)
                    self.discard(session.id, STORE_UNAVAILABLE)

        self._forwarders[session.id] = asyncio.create_task(
            forward(), name=f"forward-results:{session.id}"
        )
        await subscribed

    # ------------------------------------------------------------ inputs
    def _series(self, kind: str) -> InputSeries:
        """The metrics of inputs of ``kind`` (``labels()`` once per kind, not per input)."""
        series = self._input_series.get(kind)
        if series is None:
            metrics = self.metrics
            series = self._input_series[kind] = InputSeries(
                inputs=metrics.inputs.labels(kind),
                fusion_step=metrics.fusion_step.labels(kind),
                engine_cpu=metrics.engine_cpu.labels(kind),
            )
        return series

    @staticmethod
    def check(session: LiveSession, report: Report) -> None:
        """Checks that need only the config: item limit, sensor, dimensions, class labels."""
        if isinstance(report, TrackReport):
            issues = track_report_issues(report, session.config)
        else:
            issues = detection_report_issues(report, session.config)
        if issues:
            raise request_validation_error(issues)

    def _engine_for(self, session: LiveSession, sensor: str) -> tuple[SessionEngine, FusionConfig]:
        """The engine to apply a report of ``sensor`` to (a copy with the sensor joined, if new)."""
        known = not session.open_sensors or sensor in session.joined_sensors
        if session.engine is not None and session.fusion is not None and known:
            return session.engine, session.fusion
        joined = session.joined_sensors
        if len(joined) >= self.settings.max_sensors:
            raise LimitExceeded(
                "max_sensors", self.settings.max_sensors, len(joined) + 1, what="sensors"
            )
        fusion = fusion_config(session.config, [*joined, sensor])
        if session.engine is None:
            return SessionEngine(fusion), fusion
        return SessionEngine.restore(fusion, session.engine.export()), fusion

    def _apply(
        self,
        session: LiveSession,
        report: Report,
        *,
        explain: bool,
        geodetic: GeodeticOutput | None = None,
    ) -> Step:
        """Apply an input to the session's engine (or a copy with a new sensor); logs nothing."""
        engine, fusion = self._engine_for(session, report.sensor)
        try:
            if isinstance(report, TrackReport):
                track_report = session_frame_report(report, session.config)
                started = time.thread_time()
                step = engine.apply(track_report, explain=explain)
            else:
                detection_report = core_detection_report(report, session.config)
                started = time.thread_time()
                step = engine.apply_detections(detection_report, explain=explain)
            engine_cpu_s = time.thread_time() - started
        except CoreStaleReport as stale:
            raise StaleReport(stale.sensor, stale.time, stale.last_time) from None
        seq = session.seq + 1
        return Step(
            engine=engine,
            fusion=fusion,
            result=step_json(step, seq),  # serialised once, here
            geodetic=None if geodetic is None else step_json(step, seq, geodetic),
            logged=log_input(report),
            engine_cpu_s=engine_cpu_s,
        )

    async def submit(
        self,
        session: LiveSession,
        report: Report,
        *,
        explain: bool = False,
        geodetic: GeodeticOutput | None = None,
    ) -> str:
        """Apply one input (a track list, or detections for the sensor's local tracker), log
        it durably, publish its result, and return the answer to its sender (JSON text;
        ``geodetic``: with the tracks' geodetic positions)."""
        items = len(report.tracks) if isinstance(report, TrackReport) else len(report.detections)
        await self._compute(items, functools.partial(self.check, session, report))
        return await self._submit(session, report, items, explain=explain, geodetic=geodetic)

    async def _submit(
        self,
        session: LiveSession,
        report: Report,
        items: int,
        *,
        explain: bool,
        geodetic: GeodeticOutput | None,
    ) -> str:
        """Under the session lock: (lease,) apply, log durably, then publish and return the result.

        An input that waited for the lock of a session evicted meanwhile goes to the session
        as the store has it now: 404 if it was deleted, 503 if the store is down.
        """
        kind = "tracks" if isinstance(report, TrackReport) else "detections"
        async with session.lock:
            if not session.closed:
                return await self._submit_locked(
                    session, report, items, kind, explain=explain, geodetic=geodetic
                )
        return await self._submit(
            await self.get(session.id), report, items, explain=explain, geodetic=geodetic
        )

    async def _submit_locked(
        self,
        session: LiveSession,
        report: Report,
        items: int,
        kind: str,
        *,
        explain: bool,
        geodetic: GeodeticOutput | None,
    ) -> str:
        """:meth:`_submit` once the session's lock is held."""
        if geodetic is None and not self.shared and session.hub.wants_geodetic():
            # for this instance's subscribers (with a shared store they are fed through Redis,
            # the session-frame text only)
            written = session_geodetic(session.config)
        else:
            written = geodetic
        apply = functools.partial(self._apply, session, report, explain=explain, geodetic=written)
        with anyio.CancelScope(shield=True):
            if self.shared:
                await self._hold_lease(session)
            try:
                step = await self._apply_and_log(session, apply, report.sensor, items, kind)
            except SequenceConflict:
                if not self.shared:
                    raise
                # overtaken by another instance: rebuild from the store, apply once more
                await self._refresh(session)
                step = await self._apply_and_log(session, apply, report.sensor, items, kind)
            self._series(kind).inputs.inc()
            if self.shared:  # local subscribers too receive it through Redis (the text only)
                await self._publish(session, result_message(step.result))
            elif len(session.hub):
                session.hub.publish(
                    Published(
                        result_message(step.result),
                        None if step.geodetic is None else result_message(step.geodetic),
                    )
                )
            session.since_snapshot += 1
            if session.since_snapshot >= self.settings.snapshot_every:
                await self._snapshot(session)
        if geodetic is not None and step.geodetic is not None:
            return step.geodetic
        return step.result

    async def _apply_and_log(
        self,
        session: LiveSession,
        apply: Callable[[], Step],
        sensor: str,
        items: int,
        kind: str,
    ) -> Step:
        """``apply()`` the input, append it to the log, then move the session on (else it is
        rebuilt)."""
        started = time.perf_counter()
        size = items + len(session.tracks)
        engine_seq = None if session.engine is None else session.engine.seq
        tallied = _tally(session.engine, sensor)
        try:
            step = await self._compute(size, apply)
        except BaseException:
            if session.engine is not None and session.engine.seq != engine_seq:
                # the last defence: steps are transactions, so a refused input that changed
                # the engine is a bug; rebuild the session from its log
                logger.error("session %s: a refused input changed the engine", session.id)
                self.metrics.rebuilds.labels("refused_after_change").inc()
                self.discard(session.id, SESSION_RELOADED)
            raise
        series = self._series(kind)
        series.fusion_step.observe(time.perf_counter() - started)
        self._count_detections(_tally(step.engine, sensor), tallied)
        series.engine_cpu.observe(step.engine_cpu_s)
        received_at = datetime.now(UTC)
        seq = session.seq + 1
        try:
            await self._io(self.store.append, session.id, seq, step.logged, received_at, size=size)
        except SequenceConflict:
            if not self.shared:
                self.metrics.rebuilds.labels("unlogged").inc()
                self.discard(session.id, SESSION_RELOADED)
            raise  # shared: the caller rebuilds the engine in place from the store
        except SessionNotFound:
            self.discard(session.id)  # deleted (through another instance)
            raise
        except StoreUnavailable:
            self.discard(session.id, STORE_UNAVAILABLE)  # not logged: rebuilt when it is back
            raise
        except BaseException:
            self.metrics.rebuilds.labels("unlogged").inc()
            # the engine holds an unlogged step: rebuild on next use
            self.discard(session.id, SESSION_RELOADED)
            raise
        session.engine, session.fusion = step.engine, step.fusion
        session.seq = seq
        session.last_input_at = received_at
        session.sensor_inputs[sensor] = session.sensor_inputs.get(sensor, 0) + 1
        return step

    def _count_detections(self, after: ScanTally | None, before: ScanTally | None) -> None:
        """What a detecting sensor's scan did, into ``/metrics`` (docs/algorithms.md §8.5)."""
        if after is None:
            return
        before = before or ScanTally()
        metrics = self.metrics
        for outcome in ("joined_established", "joined_tentative", "started", "unused"):
            metrics.detections.labels(outcome).inc(
                getattr(after, outcome) - getattr(before, outcome)
            )
        for event in ("confirmed", "refuted", "ended"):
            metrics.local_tracks.labels(event).inc(getattr(after, event) - getattr(before, event))

    async def _hold_lease(self, session: LiveSession) -> None:
        """Take or renew the session's lease; after a (re)take, catch up with the store's log."""
        ttl_ms = self.settings.lease_ttl_ms
        now = time.monotonic()
        held = now < session.lease_deadline
        if not await self._io(self.leases.acquire, session.id, self.owner, ttl_ms):
            session.lease_deadline = 0.0
            raise SessionLeased(session.id, math.ceil(ttl_ms / 1000))
        session.lease_deadline = now + 0.8 * ttl_ms / 1000  # a margin for clock and round trips
        if not held:
            last = await self._io(self.store.last_seq, session.id)
            if last != session.seq:
                await self._catch_up(session, last)

    async def current(self, session: LiveSession) -> LiveSession:
        """The session at the store's latest ``seq`` (several instances): 404 if it was deleted
        through another instance, caught up from the log if another instance moved it on."""
        if not self.shared:
            return session  # this process applies every input: its memory is the current state
        try:
            last = await self._io(self.store.last_seq, session.id)
        except SessionNotFound:
            self.discard(session.id)
            raise
        if last > session.seq:
            async with session.lock:
                if session.closed:
                    raise SessionNotFound(session.id)
                if last > session.seq:
                    await self._catch_up(session, last)
        return session

    async def _catch_up(self, session: LiveSession, last: int) -> None:
        """Apply the inputs logged after the session's ``seq`` (under its lock); rebuild from
        the snapshot instead when the log no longer holds them all (compacted) or went back."""
        entries = await self._io(self.store.entries, session.id, session.seq)
        contiguous = bool(entries) and entries[0].seq == session.seq + 1
        if not contiguous or entries[-1].seq < last or last < session.seq:
            await self._refresh(session)
            return
        await anyio.to_thread.run_sync(functools.partial(self._replay, session, entries))
        session.since_snapshot = 0

    async def _refresh(self, session: LiveSession) -> None:
        """Rebuild the session's engine in place from the store (another instance moved it on)."""
        load = await self._io(self.store.load, session.id)
        fresh = await anyio.to_thread.run_sync(functools.partial(self._rebuild, load.session, load))
        logger.info("session %s: rebuilt from the store at seq %d", session.id, fresh.seq)
        session.engine, session.fusion = fresh.engine, fresh.fusion
        session.seq = fresh.seq
        session.sensor_inputs = fresh.sensor_inputs
        session.last_input_at = fresh.last_input_at
        session.since_snapshot = 0

    async def _publish(self, session: LiveSession, message: str) -> None:
        """Send a result to the session's subscribers on every instance (logged, never raised)."""
        try:
            await self.fanout.publish(session.id, message)
        except Exception:
            logger.exception("session %s: publishing result %d failed", session.id, session.seq)

    async def _snapshot(self, session: LiveSession) -> None:
        """Snapshot the engine, then compact the log to ``log_retention`` inputs behind it."""
        size = len(session.tracks)
        state = await self._compute(size, session.snapshot_state)
        snapshot = Snapshot(seq=session.seq, taken_at=datetime.now(UTC), state=state)
        try:
            await self._io(self.store.save_snapshot, session.id, snapshot, size=size)
            session.since_snapshot = 0
            through = snapshot.seq - self.settings.log_retention
            if through > 0:
                await self._io(self.store.compact, session.id, through)
        except Exception:
            logger.exception("session %s: snapshot at seq %d failed", session.id, session.seq)

    # ------------------------------------------------------------ reads
    async def picture(
        self,
        session: LiveSession,
        at: float | None,
        write: Callable[[int, float | None, Sequence[FusedTrackView]], str] = picture_json,
    ) -> str:
        """``write(seq, time, views)`` of the live fused tracks predicted to ``at`` (default:
        the fusion time), built off the event loop: a ``FusedPicture`` by default (the routes
        pass the geodetic and GeoJSON writers)."""
        async with session.lock:
            engine = session.engine
            seq = session.seq
            if engine is None or engine.time is None:
                return write(seq, at, ())
            time_of = engine.time if at is None else at
            return await self._compute(
                len(engine.tracks), lambda: write(seq, time_of, engine.picture(at))
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


def result_message(result: str, ref: str | None = None) -> str:
    """A ``result`` WebSocket message around a result's JSON text (not serialised again)."""
    return f'{{"type":"result","ref":{dumps(ref)},"result":{result}}}'


def _tally(engine: SessionEngine | None, sensor: str) -> ScanTally | None:
    """A detecting sensor's tally so far (:class:`~core.tracking.track.ScanTally`), or None."""
    tracker = None if engine is None else engine.local_trackers.get(sensor)
    return None if tracker is None else tracker.tallies.get(sensor)
