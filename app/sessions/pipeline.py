"""The input pipeline of the live sessions: check, apply, log durably, publish, snapshot.

One input (:meth:`InputPipeline.submit`):

0. is refused (503 ``overloaded``) while the instance runs behind, or (429) beyond its
   tenant's ``tenant_max_in_flight`` (:meth:`InputPipeline.admit`);
1. checks that need only the config (limits, sensor, dimensions, labels: its kind's);
2. under the session's lock, in its tenant's turn (:mod:`app.sessions.turns`: the tenants
   take the engine steps round-robin), the engine applies it (in a worker thread unless the
   work is tiny) — unless it has waited longer than ``max_queue_ms`` since it was received
   (503 ``overloaded``: it would be answered late); a refusal changes nothing;
3. the input is appended to the store — durably for sqlite — and only then is
   the result returned and published. Steps 2–3 are shielded from
   cancellation (a client that goes away cannot leave the engine ahead of the
   log); if the append fails anyway, the session is evicted from memory and
   rebuilt from the store on its next use;
4. every ``snapshot_every`` inputs the engine state is snapshotted, and the
   log is compacted to the ``log_retention`` inputs behind that snapshot.

With a shared store the pipeline takes the session's lease first and publishes through
Redis (:class:`~app.cluster.link.ClusterLink`).
"""

from __future__ import annotations

import functools
import hashlib
import logging
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from http import HTTPStatus
from typing import TYPE_CHECKING, Any

import anyio
from prometheus_client import Counter, Histogram

from api_schemas.timing import TimeEpoch
from app.cluster.quotas import input_work
from app.errors import LimitExceeded, Overloaded, SessionNotFound, StoreUnavailable, TooLate
from app.inputs import DecodedKind, Input, SessionView
from app.outputs import JSON, Output
from app.outputs.text import dumps
from app.plausibility import input_warnings
from app.sessions.hub import SESSION_RELOADED, STORE_UNAVAILABLE, Published
from app.sessions.live import IDEMPOTENCY_FIELD, LiveSession, idempotency_record
from app.sessions.log import logged_input
from app.sessions.translate import PlainObject
from app.sessions.turns import Turns
from app.sessions.work import Receipt, StepCount, compute, receipt
from app.stores import LogEntry, SequenceConflict, Snapshot
from core.fusion.engine import SessionEngine
from core.tracking.track import ScanTally

if TYPE_CHECKING:
    from app.sessions.registry import SessionRegistry

DECODED_BYTES_PER_ITEM = 32
"""Bytes of an encoded body (ASTERIX) per item, for :data:`~app.sessions.work.TINY_WORK`:
a plot is ~30 bytes."""

logger = logging.getLogger("credal_fusion.sessions")


@dataclass
class Step:
    """An applied (not yet logged) input: the engine that holds it, its result written in every
    output asked (by its sender, or a subscriber of this instance; :data:`~app.outputs.JSON`
    always), the input as it is logged (all built beside the step, off the event loop) and
    the CPU time of the engine step alone (the thread's)."""

    engine: SessionEngine
    written: dict[Output, str]
    logged: PlainObject
    engine_cpu_s: float
    time_epoch: TimeEpoch
    listened: bool = False
    """Whether its result had a listener through a shared store when it was logged
    (:meth:`~app.stores.base.Store.append`): it is published through the store only then."""

    @property
    def result(self) -> str:
        """The result as the contract's JSON in the session frame."""
        return self.written[JSON]


@dataclass(frozen=True)
class Once:
    """An input's idempotency key and fingerprint (its kind, report, ``explain`` and output)."""

    key: str
    fingerprint: str


@dataclass(frozen=True)
class Arrival:
    """Whose an input is (its session's tenant) and when it was received."""

    tenant: str
    received: Receipt | None
    """``None``: not to be refused for its wait (the later inputs of a decoded body, accepted
    with its first)."""


@dataclass(frozen=True)
class InputSeries:
    """The metrics of one kind of input (``tracks``, ``detections``)."""

    inputs: Counter
    fusion_step: Histogram
    engine_cpu: Histogram


class InputPipeline:
    """Applies, logs and publishes the inputs of the registry's sessions (module docstring)."""

    def __init__(self, registry: SessionRegistry) -> None:
        self.registry = registry
        self._input_series: dict[str, InputSeries] = {}
        self._tallied: list[tuple[str, Counter]] = []
        self.in_flight = 0
        """Inputs admitted and not yet answered (the overload guard's queue: :meth:`admit`)."""
        self.tenant_in_flight: dict[str, int] = {}
        """The same per tenant (tenants with none are not kept)."""
        self.turns = Turns()
        """The engine steps, taken round-robin between tenants (:mod:`app.sessions.turns`)."""

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
        """Apply one input (of any kind: :mod:`app.inputs`), log it durably, publish its
        result, and return the answer to its sender (text of ``output``). It is checked
        against the session's config first, then its work against ``max_input_work`` (and
        ``max_explain_cells``) and its tenant's quotas. An input sent again with the
        ``idempotency_key`` of one already applied gets that first answer, and nothing is
        applied: the key, the input's fingerprint and its answer are logged with the input
        (:data:`~app.sessions.live.IDEMPOTENCY_FIELD`), so a restart or another instance
        knows them (the session keeps its latest 256, :data:`~app.sessions.live.IDEMPOTENCY_KEYS`).
        An overloaded instance refuses it first (:meth:`admit`), and one that has kept it
        waiting longer than ``max_queue_ms`` since ``received_at`` (when its last byte was
        read: :func:`app.http.transport.received_at`; default: now) refuses it before its step
        (:meth:`check_queue_time`)."""
        arrival = Arrival(session.record.tenant, received_at or receipt())
        with self._admission(arrival.tenant):
            return await self._admitted(
                session,
                submitted,
                arrival,
                explain=explain,
                output=output,
                idempotency_key=idempotency_key,
            )

    @contextmanager
    def _admission(self, tenant: str) -> Iterator[None]:
        """An input of ``tenant`` admitted (:meth:`admit`), counted in :attr:`in_flight` and
        :attr:`tenant_in_flight` until answered."""
        self.admit(tenant)
        self.in_flight += 1
        self.tenant_in_flight[tenant] = self.tenant_in_flight.get(tenant, 0) + 1
        try:
            yield
        finally:
            self.in_flight -= 1
            left = self.tenant_in_flight[tenant] - 1
            if left:
                self.tenant_in_flight[tenant] = left
            else:
                del self.tenant_in_flight[tenant]

    def admit(self, tenant: str) -> None:
        """Refuse a new input of ``tenant`` before any check, quota or work, so that nothing
        changes:

        - with 429 ``tenant_max_in_flight`` (``Retry-After``) when the tenant already has that
          many inputs in flight on this instance (waiting for their turn or being applied):
          a flooding tenant queues no more than that, whatever its connections;
        - with 503 ``overloaded`` (:class:`~app.errors.Overloaded`, ``Retry-After``) while the
          event loop runs later than ``overload_delay_ms`` on average
          (:attr:`app.runtime.LoopLag.smoothed`) and the tenant holds at least its even share
          of the inputs in flight (its own × the tenants with inputs in flight, itself
          included, ≥ all of them). An input that finds none in flight is never refused: a
          client that waits for each answer cannot overload the instance, and the lateness is
          then the machine's other load, which a refusal would not relieve; nor is one of a
          tenant below its share: the tenants sending most are refused first, and one
          tenant's flood cannot have another's sensor refused.

        An instance that takes every input falls behind on all of its sessions at once (answers
        late by seconds, in bursts); one that refuses what it cannot take in time answers the
        inputs it accepts in time, and the refused ones go elsewhere or come back after
        ``Retry-After``."""
        settings = self.registry.settings
        mine = self.tenant_in_flight.get(tenant, 0)
        if mine >= settings.tenant_max_in_flight:
            self.registry.metrics.refused_waiting.labels("tenant_max_in_flight").inc()
            raise LimitExceeded(
                "tenant_max_in_flight",
                settings.tenant_max_in_flight,
                mine + 1,
                what="inputs of this tenant in flight on this instance (waiting or applied); "
                "send the next once one is answered",
                status=HTTPStatus.TOO_MANY_REQUESTS,
                retry_after_s=1,
            )
        limit_ms = settings.overload_delay_ms
        loop_lag = self.registry.loop_lag
        if loop_lag is None or limit_ms <= 0 or self.in_flight == 0:
            return
        tenants = len(self.tenant_in_flight) + (mine == 0)
        delay_ms = 1e3 * loop_lag.smoothed
        if delay_ms > limit_ms and mine * tenants >= self.in_flight:
            self.registry.metrics.overloaded.inc()
            raise Overloaded(delay_ms, limit_ms)

    def check_queue_time(self, received: Receipt) -> None:
        """Refuse an input about to be applied (:class:`~app.errors.TooLate`: 503 ``overloaded``,
        ``Retry-After``) that has waited longer than ``max_queue_ms`` since it was ``received``
        (for the event loop, its session's lock, its tenant's turn) while other inputs' steps
        ran: applied now, it would be answered late, and every input behind it later still.
        Nothing of it was applied or logged. An input whose wait saw no other step start is
        not refused: it waited for the machine's other processes, which a refusal would not
        relieve."""
        limit_ms = self.registry.settings.max_queue_ms
        if limit_ms <= 0 or received.steps_since() == 0:
            return
        queued_ms = 1e3 * (time.monotonic() - received.at)
        if queued_ms > limit_ms:
            self.registry.metrics.refused_waiting.labels("max_queue_ms").inc()
            raise TooLate(queued_ms, limit_ms)

    async def _admitted(
        self,
        session: LiveSession,
        submitted: Input,
        arrival: Arrival,
        *,
        explain: bool = False,
        output: Output = JSON,
        idempotency_key: str | None = None,
    ) -> str:
        """:meth:`submit` once admitted."""
        items = submitted.items
        await compute(items, functools.partial(submitted.check, session.config))
        work = self.check_work(
            session, submitted.sensor, items, submitted.kind.tag, explain=explain
        )
        await self.registry.quotas.charge(session.record.tenant, work)
        once = None
        if idempotency_key is not None:
            text = (
                f"{explain}:{output.name}:{submitted.kind.tag}:{submitted.report.model_dump_json()}"
            )
            once = Once(idempotency_key, hashlib.sha256(text.encode()).hexdigest())
        return await self._submit(
            session, submitted, items, arrival, explain=explain, output=output, once=once
        )

    def check_work(
        self, session: LiveSession, sensor: str, items: int, tag: str, *, explain: bool
    ) -> int:
        """The work units (:func:`~app.cluster.quotas.input_work`) of ``items`` items of kind
        ``tag`` from ``sensor``, refused (422) beyond ``max_input_work``, or beyond
        ``max_explain_cells`` for the matrix ``explain`` adds: before any work (for a large
        REST body, before it is even validated: :mod:`app.routes.inputs`)."""
        known = len(session.tracks)
        tracker = None if session.engine is None else session.engine.tracker_of(sensor)
        known += 0 if tracker is None else tracker.n_tracks  # a detecting sensor's own tracks
        settings = self.registry.settings
        where = (tag,)  # the list of items is named as the kind (tracks, detections)
        work = input_work(items, known)
        if work > settings.max_input_work:
            raise LimitExceeded(
                "max_input_work",
                settings.max_input_work,
                work,
                what=f"work units of this input ({items} items × ({known} known tracks + 1))",
                loc=where,
            )
        cells = (known + items) * items
        if explain and cells > settings.max_explain_cells:
            raise LimitExceeded(
                "max_explain_cells",
                settings.max_explain_cells,
                cells,
                what=f"cells of the explained score matrix (({known} known + {items} reported "
                f"tracks) × {items}); send the input without explain=true",
                loc=where,
            )
        return work

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
        """Decode ``data`` (a kind of :data:`~app.inputs.DECODED_KINDS`) into inputs, checked
        against the session's config, then submit each in order; the kind's answer (JSON text).
        Malformed data or an input the session cannot take refuses the whole body first, and an
        overloaded instance the whole body (:meth:`admit`; ``max_queue_ms`` is checked before
        its first input's step), never a part of it."""
        tenant = session.record.tenant
        first = Arrival(tenant, received_at or receipt())
        with self._admission(tenant):
            view = SessionView(session.config, session.last_time)
            decode = functools.partial(kind.decode, data, parameters, view)
            decoded = await compute(len(data) // DECODED_BYTES_PER_ITEM, decode)
            results = [
                await self._admitted(
                    session,
                    item,
                    first if index == 0 else Arrival(tenant, None),
                    explain=explain,
                    output=output,
                )
                for index, item in enumerate(decoded.inputs)
            ]
            return kind.answer(decoded, results)

    async def _submit(
        self,
        session: LiveSession,
        submitted: Input,
        items: int,
        arrival: Arrival,
        *,
        explain: bool,
        output: Output,
        once: Once | None = None,
    ) -> str:
        """Under the session lock: (lease,) apply, log durably, then publish and return the result.

        An input that waited for the lock of a session evicted meanwhile goes to the session
        as the store has it now: 404 if it was deleted, 503 if the store is down. ``once``:
        the input's idempotency key and fingerprint (its first answer is given again).
        """
        async with session.lock:
            if not session.closed:
                return await self._submit_locked(
                    session, submitted, items, arrival, explain=explain, output=output, once=once
                )
        return await self._submit(
            await self.registry.get(session.id),
            submitted,
            items,
            arrival,
            explain=explain,
            output=output,
            once=once,
        )

    async def _submit_locked(
        self,
        session: LiveSession,
        submitted: Input,
        items: int,
        arrival: Arrival,
        *,
        explain: bool,
        output: Output,
        once: Once | None = None,
    ) -> str:
        """:meth:`_submit` once the session's lock is held. A known idempotency key is looked
        up once the session is the store's latest (after taking the lease, and again after
        being overtaken): an instance that took the session over answers what the first did."""
        kind, sensor = submitted.kind.tag, submitted.sensor
        # this instance's subscribers are written for beside the step (with a shared store
        # they are fed the JSON text through Redis and convert it)
        outputs = {output} if self.registry.shared else {output, *session.hub.outputs()}
        apply = functools.partial(
            self.apply, session, submitted, explain=explain, outputs=frozenset(outputs)
        )
        with anyio.CancelScope(shield=True):
            if self.registry.shared:
                await self.registry.cluster.hold_lease(session)
            answered = None if once is None else session.answer_of(once.key, once.fingerprint)
            if answered is not None:
                return answered
            try:
                step = await self._apply_and_log(
                    session, apply, sensor, items, kind, arrival, once, output
                )
            except SequenceConflict:
                if not self.registry.shared:
                    raise
                # overtaken by another instance: rebuild from the store, apply once more
                await self.registry.cluster.refresh(session)
                answered = None if once is None else session.answer_of(once.key, once.fingerprint)
                if answered is not None:
                    return answered
                step = await self._apply_and_log(
                    session, apply, sensor, items, kind, arrival, once, output
                )
            self._series(kind).inputs.inc()
            if self.registry.shared:
                # local subscribers too receive it through Redis (the text only), and only
                # where someone listens: a subscriber that came later reads a later ``seq``
                if step.listened:
                    await self.registry.cluster.publish(session, result_message(step.result))
            elif len(session.hub):
                session.hub.publish(
                    Published({kind: result_message(text) for kind, text in step.written.items()})
                )
            session.since_snapshot += 1
            if session.since_snapshot >= self.registry.settings.snapshot_every:
                await self._snapshot(session)
        return step.written[output]

    def apply(
        self,
        session: LiveSession,
        submitted: Input,
        *,
        explain: bool,
        outputs: frozenset[Output] = frozenset((JSON,)),
    ) -> Step:
        """Apply an input to the session's engine (or a copy with a new sensor), write its
        result in ``outputs`` (and JSON); logs nothing. Its ``time`` is refused unless given
        as the session's are (numbers or timestamps: :meth:`LiveSession.epoch_of`)."""
        time_epoch = session.epoch_of(submitted.time)
        engine, joined = session.engine_for(submitted.sensor, self.registry.settings.max_sensors)
        try:
            applied = submitted.apply(engine, session.config, explain=explain)
        except BaseException:
            if joined:
                engine.leave(submitted.sensor)  # a refused input joins no sensor
            raise
        step, seq = applied.step, session.seq + 1
        # annotations only: computed beside the step, from the input and the config
        warnings = input_warnings(submitted.kind.tag, submitted.report, session.config)
        return Step(
            engine=engine,
            written={output: output.step(step, seq, warnings) for output in outputs | {JSON}},
            logged=submitted.logged(),
            engine_cpu_s=applied.engine_cpu_s,
            time_epoch=time_epoch,
        )

    def replay(self, session: LiveSession, entries: list[LogEntry]) -> None:
        """Apply logged inputs to the session in order (a worker thread, under its lock)."""
        record = session.record
        for entry in entries:
            try:
                step = self.apply(session, logged_input(entry), explain=False)
            except Exception:
                logger.exception("session %s: replay of input %d failed", record.id, entry.seq)
            else:
                session.engine, session.time_epoch = step.engine, step.time_epoch
            session.remember_logged(entry.input)
            sensor = str(entry.input.get("report", {}).get("sensor", ""))
            session.sensor_inputs[sensor] = session.sensor_inputs.get(sensor, 0) + 1
            session.seq = entry.seq
            session.last_input_at = entry.received_at

    async def _apply_and_log(
        self,
        session: LiveSession,
        apply: Callable[[], Step],
        sensor: str,
        items: int,
        kind: str,
        arrival: Arrival,
        once: Once | None = None,
        output: Output = JSON,
    ) -> Step:
        """``apply()`` the input in its tenant's turn (unless it has waited too long:
        :meth:`check_queue_time`), append it to the log (with its idempotency key and answer in
        ``output``: one write), then move the session on (else it is rebuilt)."""
        size = items + len(session.tracks)
        engine_seq = None if session.engine is None else session.engine.seq
        tallied = _tally(session.engine, sensor)
        try:
            async with self.turns.turn(arrival.tenant, alone=self.in_flight <= 1):
                if arrival.received is not None:
                    self.check_queue_time(arrival.received)
                StepCount.started += 1
                started = time.perf_counter()
                step = await compute(size, apply)
        except BaseException:
            if session.engine is not None and session.engine.seq != engine_seq:
                # the last defence: steps are transactions, so a refused input that changed
                # the engine is a bug; rebuild the session from its log
                logger.error("session %s: a refused input changed the engine", session.id)
                self.registry.metrics.rebuilds.labels("refused_after_change").inc()
                self.registry.discard(session.id, SESSION_RELOADED)
            raise
        series = self._series(kind)
        series.fusion_step.observe(time.perf_counter() - started)
        series.engine_cpu.observe(step.engine_cpu_s)
        self._count_detections(_tally(step.engine, sensor), tallied)
        received_at = datetime.now(UTC)
        seq = session.seq + 1
        logged = step.logged
        if once is not None:
            record = idempotency_record(once.key, once.fingerprint, step.written[output])
            logged = {**logged, IDEMPOTENCY_FIELD: record}
        try:
            step.listened = await self.registry.append(
                session.id, seq, logged, received_at, size=size
            )
        except SequenceConflict:
            if not self.registry.shared:
                self.registry.metrics.rebuilds.labels("unlogged").inc()
                self.registry.discard(session.id, SESSION_RELOADED)
            raise  # shared: the caller rebuilds the engine in place from the store
        except SessionNotFound:
            self.registry.discard(session.id)  # deleted (through another instance)
            raise
        except StoreUnavailable:
            self.registry.discard(
                session.id, STORE_UNAVAILABLE
            )  # not logged: rebuilt when it is back
            raise
        except BaseException:
            self.registry.metrics.rebuilds.labels("unlogged").inc()
            # the engine holds an unlogged step: rebuild on next use
            self.registry.discard(session.id, SESSION_RELOADED)
            raise
        session.engine, session.time_epoch = step.engine, step.time_epoch
        session.seq = seq
        session.last_input_at = received_at
        session.sensor_inputs[sensor] = session.sensor_inputs.get(sensor, 0) + 1
        if once is not None:
            session.remember(once.key, once.fingerprint, step.written[output])
        return step

    def _count_detections(self, after: ScanTally | None, before: ScanTally | None) -> None:
        """What a detecting sensor's scan did, into ``/metrics`` (docs/algorithms.md §8.8)."""
        if after is None:
            return
        before = before or ScanTally()
        for name, counter in self._tally_counters():
            counter.inc(getattr(after, name) - getattr(before, name))

    def _tally_counters(self) -> list[tuple[str, Counter]]:
        """Each counted field of a :class:`ScanTally` with its ``/metrics`` counter (its
        ``labels()`` once, not per input)."""
        if not self._tallied:
            metrics = self.registry.metrics
            self._tallied = [
                (outcome, metrics.detections.labels(outcome))
                for outcome in ("joined_established", "joined_tentative", "started", "unused")
            ] + [
                (event, metrics.local_tracks.labels(event))
                for event in ("confirmed", "refuted", "ended")
            ]
        return self._tallied

    async def _snapshot(self, session: LiveSession) -> None:
        """Snapshot the engine, then compact the log to ``log_retention`` inputs behind it."""
        size = len(session.tracks)
        state = await compute(size, session.snapshot_state)
        snapshot = Snapshot(seq=session.seq, taken_at=datetime.now(UTC), state=state)
        try:
            await self.registry.io(
                self.registry.store.save_snapshot, session.id, snapshot, size=size
            )
            session.since_snapshot = 0
            through = snapshot.seq - self.registry.settings.log_retention
            if through > 0:
                await self.registry.io(self.registry.store.compact, session.id, through)
        except Exception:
            logger.exception("session %s: snapshot at seq %d failed", session.id, session.seq)

    def _series(self, kind: str) -> InputSeries:
        """The metrics of inputs of ``kind`` (``labels()`` once per kind, not per input)."""
        series = self._input_series.get(kind)
        if series is None:
            metrics = self.registry.metrics
            series = self._input_series[kind] = InputSeries(
                inputs=metrics.inputs.labels(kind),
                fusion_step=metrics.fusion_step.labels(kind),
                engine_cpu=metrics.engine_cpu.labels(kind),
            )
        return series


def result_message(result: str, ref: str | None = None) -> str:
    """A ``result`` WebSocket message around a result's JSON text (not serialised again)."""
    written_ref = "null" if ref is None else dumps(ref)  # most answers have no ref
    return f'{{"type":"result","ref":{written_ref},"result":{result}}}'


def _tally(engine: SessionEngine | None, sensor: str) -> ScanTally | None:
    """A detecting sensor's tally so far (:class:`~core.tracking.track.ScanTally`), or None."""
    tracker = None if engine is None else engine.tracker_of(sensor)
    return None if tracker is None else tracker.tallies.get(sensor)
