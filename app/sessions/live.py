"""One session in memory: its engine, its lock, its subscribers and what the service counts.

A snapshot (:meth:`LiveSession.snapshot_state`) keeps the engine's export and
the service's counters; :func:`restore_snapshot` is its inverse.
"""

from __future__ import annotations

import asyncio
import dataclasses
from collections import OrderedDict
from dataclasses import dataclass, field
from datetime import datetime

from api_schemas.config import SessionConfig
from api_schemas.issues import FieldIssue, Location
from api_schemas.limits import CEILINGS, limits_of
from api_schemas.timing import EXAMPLE_TIMESTAMP, TimeEpoch, epoch_of
from app.errors import IdempotencyKeyReused, InvalidFields, LimitExceeded
from app.sessions.hub import Hub
from app.sessions.translate import PlainObject, class_frame, fusion_config
from app.stores import SessionRecord, Snapshot
from core.belief import Frame
from core.fusion.config import SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.track import FusedTrack

SNAPSHOT_FORMAT = 1
IDEMPOTENCY_KEYS = 256
"""Answers kept per session for retried inputs (``Idempotency-Key``)."""
IDEMPOTENCY_BYTES = 1024 * 1024
"""Characters of those answers kept per session beyond the latest one (an answer is ~800 bytes
per fused track): what they add to its memory and to each of its snapshots."""
IDEMPOTENCY_FIELD = "idempotency"
"""The logged input's field holding its key, fingerprint and first answer (:meth:`LiveSession.remember_logged`)."""


@dataclass
class LiveSession:
    """A session in memory: its engine and what the service counts about it."""

    record: SessionRecord
    """Its identity and token hash; the raw config is not kept here (``config`` holds it
    validated: a config of 64 polygon fields of view is 64 000 lists as JSON data)."""
    config: SessionConfig
    frame: Frame | None
    engine: SessionEngine | None
    seq: int = 0
    sensor_inputs: dict[str, int] = field(default_factory=dict)
    last_input_at: datetime | None = None
    since_snapshot: int = 0
    closed: bool = False
    lease_deadline: float = 0.0
    """Monotonic time until which this instance surely holds the session's lease (redis store)."""
    lock: asyncio.Lock = field(default_factory=asyncio.Lock)
    hub: Hub = field(default_factory=Hub)
    time_epoch: TimeEpoch | None = None
    """How its inputs give their times: its first input's way (numbers, ``arbitrary``; RFC 3339
    timestamps, ``unix``; :mod:`api_schemas.timing`), ``None`` before it."""
    answered: OrderedDict[str, tuple[str, str]] = field(default_factory=OrderedDict)
    """The answers to the latest inputs sent with an idempotency key: key → (the input's
    fingerprint, the answer), at most :data:`IDEMPOTENCY_KEYS` and :data:`IDEMPOTENCY_BYTES`
    (the latest is always kept), oldest first. Durable with the inputs they answer: each is
    logged with its input (one store write) and snapshots keep them, so a restart or another
    instance restores them (snapshot, then the log after it)."""
    answered_chars: int = 0

    def answer_of(self, key: str, fingerprint: str) -> str | None:
        """The answer already given to the input of ``key`` (``None``: not seen); 409 if the
        key came with another input."""
        seen = self.answered.get(key)
        if seen is None:
            return None
        if seen[0] != fingerprint:
            raise IdempotencyKeyReused(self.id, key)
        return seen[1]

    def remember(self, key: str, fingerprint: str, answer: str) -> None:
        """Keep the answer to the input of ``key`` (forgetting the oldest beyond the bounds)."""
        previous = self.answered.pop(key, None)
        if previous is not None:
            self.answered_chars -= len(previous[1])
        self.answered[key] = (fingerprint, answer)
        self.answered_chars += len(answer)
        while len(self.answered) > IDEMPOTENCY_KEYS or (
            self.answered_chars > IDEMPOTENCY_BYTES and len(self.answered) > 1
        ):
            _, (_, dropped) = self.answered.popitem(last=False)
            self.answered_chars -= len(dropped)

    def remember_logged(self, logged: PlainObject) -> None:
        """Keep the answer a logged input carries (:func:`idempotency_record`), if any."""
        record = logged.get(IDEMPOTENCY_FIELD)
        if isinstance(record, dict):
            key, fingerprint, answer = (
                record.get("key"),
                record.get("fingerprint"),
                record.get("answer"),
            )
            if isinstance(key, str) and isinstance(fingerprint, str) and isinstance(answer, str):
                self.remember(key, fingerprint, answer)

    def epoch_of(self, time: float | str, where: Location = ("time",)) -> TimeEpoch:
        """The epoch of an input's ``time``: refused (422 at ``where``) unless it is the
        session's (:mod:`api_schemas.timing`)."""
        epoch = epoch_of(time)
        if self.time_epoch is None or epoch == self.time_epoch:
            return epoch
        if epoch == "unix":
            message = (
                f"this session's times are seconds of its own epoch (its first input gave a "
                f"number): send time as a number, not the timestamp {time!r}"
            )
        else:
            message = (
                f"this session's times are RFC 3339 timestamps (its first input gave one): send "
                f"time as a timestamp such as {EXAMPLE_TIMESTAMP!r}, not the number {time!r}"
            )
        raise InvalidFields([FieldIssue(where, message, time)])

    @property
    def id(self) -> str:
        """The session id."""
        return self.record.id

    @property
    def open_sensors(self) -> bool:
        """Whether any sensor id is accepted (the config names none)."""
        return not self.config.sensors

    @property
    def joined_sensors(self) -> list[str]:
        """Sensors that joined an open session, in order of arrival."""
        if not self.open_sensors or self.engine is None:
            return []
        return [sensor.id for sensor in self.engine.config.sensors]

    @property
    def time(self) -> float | None:
        """The fusion time (latest report time), ``None`` before the first input."""
        return None if self.engine is None else self.engine.time

    @property
    def tracks(self) -> list[FusedTrack]:
        """The live fused tracks (terminated ones are gone)."""
        return [] if self.engine is None else self.engine.tracks

    @property
    def created_tracks(self) -> int:
        """Fused tracks ever started."""
        return 0 if self.engine is None else self.engine.next_number - 1

    def sensor_ids(self) -> list[str]:
        """Configured sensors, or the ones that joined an open session."""
        if self.open_sensors:
            return self.joined_sensors
        return [sensor.id for sensor in self.config.sensors]

    def last_time(self, sensor: str) -> float | None:
        """Time of the sensor's latest accepted report."""
        return None if self.engine is None else self.engine.last_report.get(sensor)

    def idle_since(self) -> datetime:
        """When the session last received an input (or was created)."""
        return self.last_input_at or self.record.created_at

    def engine_for(self, sensor: str, max_sensors: int) -> tuple[SessionEngine, bool]:
        """The engine to apply an input of ``sensor`` to, and whether ``sensor`` joined it just
        now: an open session seeing a sensor first (at most ``max_sensors``) joins it to its
        engine in place (:meth:`SessionEngine.join`: no export and restore; the caller undoes
        it with ``engine.leave`` if the input is refused), or builds its first engine."""
        if self.engine is not None and (not self.open_sensors or sensor in self.joined_sensors):
            return self.engine, False
        joined = self.joined_sensors
        if len(joined) >= max_sensors:
            raise LimitExceeded("max_sensors", max_sensors, len(joined) + 1, what="sensors")
        if self.engine is None:  # the first input of an open session
            return SessionEngine(fusion_config(self.config, [sensor])), False
        self.engine.join(SensorSpec(id=sensor))
        return self.engine, True

    def snapshot_state(self) -> PlainObject:
        """What a snapshot keeps: the engine export and the service's counters."""
        return {
            "format": SNAPSHOT_FORMAT,
            "engine": None if self.engine is None else self.engine.export(),  # plain already
            "joined_sensors": self.joined_sensors,
            "sensor_inputs": dict(self.sensor_inputs),
            "last_input_at": None if self.last_input_at is None else self.last_input_at.isoformat(),
            "time_epoch": self.time_epoch,
            "answered": [[key, *seen] for key, seen in self.answered.items()],
        }


def new_session(record: SessionRecord, config: SessionConfig | None = None) -> LiveSession:
    """The session of ``record`` before any input, its config converted once: ``config`` is
    the record's, validated already (a creation), else validated here (a stored record). A
    config the engine refuses is a 422 located at the field (:func:`fusion_config`); an open
    session (no sensor named) is checked with one sensor, its engine built at its first input."""
    if config is None:
        with limits_of(CEILINGS):  # a stored config stays readable if the limits were lowered
            config = SessionConfig.model_validate(record.config)
    if config.sensors:
        engine: SessionEngine | None = SessionEngine(fusion_config(config))
    else:
        fusion_config(config, ["probe"])  # the check alone: no engine before a sensor speaks
        engine = None
    return LiveSession(
        record=dataclasses.replace(record, config={}),
        config=config,
        frame=class_frame(config.classes),
        engine=engine,
    )


def engine_from_snapshot(config: SessionConfig, state: PlainObject) -> SessionEngine | None:
    """The engine a snapshot's ``state`` holds (``None`` before the first input)."""
    if state.get("format") != SNAPSHOT_FORMAT:
        raise ValueError(f"unknown snapshot format {state.get('format')!r}")
    if state["engine"] is None:
        return None
    joined = [str(sensor) for sensor in state["joined_sensors"]]
    return SessionEngine.restore(
        fusion_config(config, [] if config.sensors else joined), state["engine"]
    )


def restore_snapshot(session: LiveSession, snapshot: Snapshot) -> None:
    state = snapshot.state
    engine = engine_from_snapshot(session.config, state)
    if engine is not None:
        session.engine = engine
    session.seq = snapshot.seq
    session.sensor_inputs = {str(k): int(v) for k, v in state["sensor_inputs"].items()}
    last = state["last_input_at"]
    session.last_input_at = None if last is None else datetime.fromisoformat(last)
    epoch = state.get("time_epoch")  # absent from a snapshot taken before timestamps existed
    if epoch in ("arbitrary", "unix"):
        session.time_epoch = epoch
    elif engine is not None and engine.time is not None:
        session.time_epoch = "arbitrary"
    session.answered.clear()
    session.answered_chars = 0
    for key, fingerprint, answer in state.get("answered", []):  # absent before they were kept
        session.remember(str(key), str(fingerprint), str(answer))


def idempotency_record(key: str, fingerprint: str, answer: str) -> PlainObject:
    """What a logged input keeps of its idempotency key (:data:`IDEMPOTENCY_FIELD`): read back
    by :meth:`LiveSession.remember_logged` on replay; ``GET …/events`` leaves it out."""
    return {"key": key, "fingerprint": fingerprint, "answer": answer}
