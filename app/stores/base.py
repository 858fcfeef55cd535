"""What a store keeps per session, and the protocol every store implements.

Per session: the configuration (JSON), the bearer token's hash, the creation
time, a deleted flag, the append-only log of accepted inputs (sequence number,
reception time, the input as JSON) and periodic snapshots of the engine state
(sequence number + the engine's ``export()`` as JSON: numpy arrays become
nested lists through :func:`to_plain`; nothing is ever pickled).

Sequence numbers start at 1 and are contiguous: :meth:`Store.append` accepts
only ``last_seq + 1`` and raises :class:`SequenceConflict` otherwise, so two
writers can never both log the same step.

Retention: a snapshot makes the inputs before it unnecessary for a restore,
so :meth:`Store.compact` drops the inputs up to a sequence number, never past
the latest snapshot (the registry keeps ``log_retention`` inputs behind it).
A history therefore always replays: the full log while it is retained, or
the latest snapshot and the log after it (:func:`history`). A deleted
session's data is freed at once; only a store that has never held its id
would accept it again.

Outages: every store raises :class:`~app.errors.StoreUnavailable` for its
backend's connection and I/O errors (:func:`unavailable_on`), never a raw
driver error, so the service answers 503 instead of 500.

Corruption: a session's stored value that cannot be decoded (its config, an
input, a snapshot, a missing field) raises
:class:`~app.errors.SessionUnreadable` naming the session and what of it
(:func:`readable`): a permanent fault of that session alone, which the registry
quarantines. A store whose own structure is damaged (a malformed sqlite file)
raises :class:`~app.errors.StoreCorrupt`. Neither quotes stored text.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime
from http import HTTPStatus
from typing import Any, Protocol, runtime_checkable

import numpy as np
import orjson

from app.errors import (
    Conflict,
    LimitExceeded,
    SessionNotFound,
    SessionUnreadable,
    StoreUnavailable,
)

JsonObject = dict[str, Any]
_PLAIN_KINDS = frozenset("biuf")
"""numpy dtype kinds whose ``tolist()`` is plain data (bool, signed/unsigned int, float)."""


SESSION_SLOT_RETRY_S = 60
"""``Retry-After`` of a session refused for want of a slot: a slot frees when a session is
deleted or expires, which the service cannot foresee; a minute is a polite polling period."""


def session_limit(max_sessions: int, live: int) -> LimitExceeded:
    """The refusal of a session beyond ``max_sessions`` (429, the setting named, ``Retry-After``)."""
    return LimitExceeded(
        "max_sessions",
        max_sessions,
        live,
        what="live sessions of the service (delete one, or wait for one to expire)",
        status=HTTPStatus.TOO_MANY_REQUESTS,
        retry_after_s=SESSION_SLOT_RETRY_S,
    )


def tenant_session_limit(max_sessions: int, live: int) -> LimitExceeded:
    """The refusal of a session beyond the tenant's ``tenant_max_sessions`` (429)."""
    return LimitExceeded(
        "tenant_max_sessions",
        max_sessions,
        live,
        what="live sessions of this tenant (delete one, or wait for one to expire)",
        status=HTTPStatus.TOO_MANY_REQUESTS,
        retry_after_s=SESSION_SLOT_RETRY_S,
    )


class SequenceConflict(Conflict):
    """An append whose sequence number is not the next one of the session."""

    slug = "sequence-conflict"

    def __init__(self, session_id: str, seq: int, expected: int) -> None:
        super().__init__(
            f"session {session_id!r}: input seq {seq} rejected, the next seq is {expected}",
            session=session_id,
            seq=seq,
            expected=expected,
        )
        self.expected = expected


class SessionExists(Conflict):
    """A session with this id is already stored."""

    slug = "session-exists"

    def __init__(self, session_id: str) -> None:
        super().__init__(f"session {session_id!r} already exists", session=session_id)


@dataclass(frozen=True)
class SessionRecord:
    """A stored session's identity (no log, no state)."""

    id: str
    config: JsonObject
    token_hash: str
    created_at: datetime
    deleted: bool = False
    tenant: str = ""
    """Who created it (:mod:`app.tenants`): its inputs count against that tenant's
    quotas, whichever token sends them ("" for a session stored before tenants existed)."""


@dataclass(frozen=True)
class LogEntry:
    """One accepted input."""

    seq: int
    received_at: datetime
    input: JsonObject


@dataclass(frozen=True)
class Snapshot:
    """The engine state after input ``seq``."""

    seq: int
    taken_at: datetime
    state: JsonObject


@dataclass(frozen=True)
class SessionLoad:
    """Everything needed to rebuild a session: its record, latest snapshot, log after it."""

    session: SessionRecord
    snapshot: Snapshot | None
    entries: list[LogEntry]

    @property
    def last_seq(self) -> int:
        """The session's latest sequence number."""
        if self.entries:
            return self.entries[-1].seq
        return self.snapshot.seq if self.snapshot is not None else 0


@dataclass(frozen=True)
class StoreUsage:
    """What a store holds now: live sessions, logged inputs, snapshots and their bytes.

    ``bytes`` is the store's own measure of what it keeps (JSON text for the
    memory store, pages in use for sqlite, ``MEMORY USAGE`` of the keys for
    Redis), so a test or a soak can see data freed without looking at RSS.
    """

    sessions: int
    inputs: int
    snapshots: int
    bytes: int


@dataclass(frozen=True)
class History:
    """A replayable stretch of a session's log: an optional snapshot, then inputs after it."""

    snapshot: Snapshot | None
    entries: list[LogEntry]
    last_seq: int
    """The session's latest sequence number when the history was read."""


@runtime_checkable
class Store(Protocol):
    """Durable (or not) keeping of sessions, their input logs and snapshots. Thread-safe."""

    kind: str
    """``memory``, ``sqlite`` or ``redis`` (what the store URL names)."""
    shared: bool
    """Whether several service instances may share the store: then the registry takes
    leases, fans results out through it and checks reads against it."""
    blocking: bool
    """Whether a call may wait on I/O (a disk's fsync, a network round trip): the registry
    then makes its calls in a worker thread; a store that never waits (memory: a dict
    under a lock, microseconds) is called on the event loop, where a thread hop would
    cost more than the call."""

    def create_session(
        self,
        record: SessionRecord,
        max_sessions: int | None = None,
        max_tenant_sessions: int | None = None,
    ) -> None:
        """Store a new session; :class:`SessionExists` if the id is taken,
        :func:`session_limit` (429) if ``max_sessions`` live sessions exist already,
        :func:`tenant_session_limit` (429) if its tenant has ``max_tenant_sessions``.

        Counting and storing are one atomic step of the store (one lock, one
        transaction, one Lua script), so instances sharing it never exceed the limits.
        """
        ...

    def get_session(self, session_id: str) -> SessionRecord | None:
        """The live (not deleted) session with this id, if any."""
        ...

    def list_sessions(self) -> list[SessionRecord]:
        """Every live session that can be read, oldest first (an unreadable one is left out:
        :meth:`session_ids` has it)."""
        ...

    def session_ids(self) -> list[str]:
        """The ids of every live session, readable or not, oldest first."""
        ...

    def count_sessions(self) -> int:
        """How many live sessions there are."""
        ...

    def delete_session(self, session_id: str) -> bool:
        """Mark the session deleted; ``False`` if there was no live session."""
        ...

    def append(
        self, session_id: str, seq: int, entry_input: Mapping[str, Any], received_at: datetime
    ) -> bool:
        """Log an accepted input; returns only once it is durably committed, and whether the
        session's results had a listener through the store then (a subscriber of its pub/sub
        channel, on any instance): an instance sharing the store publishes the input's result
        only if so. A subscriber subscribes before it reads the session's ``seq``, so an input
        logged while no one listened precedes that ``seq``: it misses nothing. ``False`` for a
        store that is not shared (its subscribers are the process's own: the session's hub);
        ``True`` for one shared that cannot count listeners (sqlite among a serve's workers)."""
        ...

    def last_seq(self, session_id: str) -> int:
        """The session's latest sequence number (0 before the first input)."""
        ...

    def entries(self, session_id: str, after: int = 0, limit: int | None = None) -> list[LogEntry]:
        """Logged inputs with ``seq > after``, oldest first, at most ``limit``."""
        ...

    def save_snapshot(self, session_id: str, snapshot: Snapshot) -> None:
        """Keep a snapshot (older ones may be pruned, the latest is always kept)."""
        ...

    def load(self, session_id: str) -> SessionLoad:
        """The latest snapshot and the log after it; :class:`SessionNotFound` if absent."""
        ...

    def compact(self, session_id: str, through: int) -> int:
        """Drop logged inputs with ``seq <= through`` (never past the latest snapshot); how many."""
        ...

    def usage(self) -> StoreUsage:
        """What the store holds now (sessions, inputs, snapshots, bytes)."""
        ...

    def ping(self) -> None:
        """Return if the store answers now; :class:`~app.errors.StoreUnavailable` if not."""
        ...

    def close(self) -> None:
        """Release resources; the store is unusable afterwards."""
        ...


_PLAIN_SCALARS = frozenset({type(None), bool, str, int, float})
"""Exact types that are plain data as they are (subclasses take :func:`_plain_at`'s rules)."""


def to_plain(value: Any, path: str = "$") -> Any:
    """``value`` as plain JSON data: numpy arrays → nested lists, numpy scalars → numbers.

    Anything that is not a dict with string keys, a list/tuple, a string, a
    number, a bool or ``None`` is refused with a :class:`TypeError` naming its path.
    Plain lists and dicts are walked without tracking the path (a snapshot holds
    thousands of numbers in lists); the path is found by a second walk only
    when something is refused.
    """
    try:
        return _plain(value)
    except TypeError:
        return _plain_at(value, path)  # raises, naming the path of what is not plain data


def _plain(value: Any) -> Any:
    """:func:`to_plain` without the path; what is not a plain list or dict takes :func:`_plain_at`."""
    kind = type(value)
    if kind in _PLAIN_SCALARS:
        return value
    if kind is list or kind is tuple:
        return [item if type(item) in _PLAIN_SCALARS else _plain(item) for item in value]
    if kind is dict:
        plain: JsonObject = {}
        for key, item in value.items():
            if type(key) is not str:
                raise TypeError(f"key {key!r} is not a string")
            plain[key] = item if type(item) in _PLAIN_SCALARS else _plain(item)
        return plain
    return _plain_at(value, "$")


def _plain_at(value: Any, path: str) -> Any:
    """The rules of :func:`to_plain`, tracking the path of every value."""
    if value is None or isinstance(value, bool | str | int):
        return value
    if isinstance(value, float):
        return value
    if isinstance(value, np.ndarray):
        if value.dtype.kind in _PLAIN_KINDS:
            return value.tolist()  # bools, integers and floats: plain already, no walk in Python
        return _plain_at(value.tolist(), path)
    if isinstance(value, np.generic):
        return _plain_at(value.item(), path)
    if isinstance(value, Mapping):
        plain: JsonObject = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise TypeError(f"{path}: key {key!r} is not a string")
            plain[key] = _plain_at(item, f"{path}.{key}")
        return plain
    if isinstance(value, Sequence):
        return [_plain_at(item, f"{path}[{index}]") for index, item in enumerate(value)]
    raise TypeError(f"{path}: {type(value).__name__} is not plain data")


def _plain_default(value: Any) -> Any:
    """``json.dumps`` hook: numpy values become plain data; anything else is refused by path."""
    return to_plain(value)  # numpy → lists and numbers; anything else: TypeError naming it


def encode(value: Any) -> bytes | str:
    """Canonical JSON of plain data: keys sorted, no spaces, non-finite floats as extensions.

    orjson's bytes when they hold the same data as the json module would write
    (orjson formats floats about 20 times faster), else the json module's
    text: numpy arrays and scalars through :func:`to_plain`, NaN and ±Infinity
    as ``NaN``/``Infinity``, integers beyond 64 bits, lone surrogates. orjson
    writes NaN and ±Infinity as ``null``, so a text with a ``null`` is kept
    only when it reads back equal to ``value`` (a comparison in C). Enums and
    UUIDs, which the json module refuses, orjson writes as their values: a
    store's data (what ``model_dump(mode="json")`` gives) has neither.
    """
    try:
        text = orjson.dumps(value, option=_ORJSON_STRICT)
    except TypeError:
        return _json_module_text(value)
    if b"null" in text and orjson.loads(text) != value:
        return _json_module_text(value)
    return text


def _json_module_text(value: Any) -> str:
    return json.dumps(
        value, separators=(",", ":"), sort_keys=True, allow_nan=True, default=_plain_default
    )


def decode(text: bytes | str) -> Any:
    """Read what :func:`encode` wrote: its bytes with orjson, its text with the json module."""
    return orjson.loads(text) if isinstance(text, bytes) else json.loads(text)


def dumps(value: Any) -> str:
    """:func:`encode` as a string (what sqlite and Redis keep)."""
    text = encode(value)
    return text.decode() if isinstance(text, bytes) else text


def loads(text: str) -> Any:
    """Parse JSON text written by :func:`dumps` (the json module: it reads ``NaN`` and
    integers beyond 64 bits as they were written)."""
    return json.loads(text)


_ORJSON_STRICT = (
    orjson.OPT_SORT_KEYS  # dumps sorts keys (code-point order = orjson's UTF-8 byte order)
    | orjson.OPT_PASSTHROUGH_DATACLASS
    | orjson.OPT_PASSTHROUGH_DATETIME
    | orjson.OPT_PASSTHROUGH_SUBCLASS
)
"""Types the json module refuses or writes differently stay orjson's errors (then json decides)."""


def history(store: Store, session_id: str, after: int, limit: int) -> History:
    """Inputs with ``seq > after`` (at most ``limit``), led by the latest snapshot when the
    log no longer holds input ``after + 1`` (compacted): replaying the answer continues
    the session exactly from ``after``, or from the snapshot when ``after`` precedes it."""
    last = store.last_seq(session_id)
    if after >= last:  # nothing after it (a number past the log never reaches the backend)
        return History(snapshot=None, entries=[], last_seq=last)
    entries = store.entries(session_id, after=after, limit=limit)
    if entries and entries[0].seq == after + 1:
        return History(snapshot=None, entries=entries, last_seq=last)
    load = store.load(session_id)
    if load.snapshot is None or load.snapshot.seq <= after:  # compacted meanwhile: read again
        entries = store.entries(session_id, after=after, limit=limit)
        return History(snapshot=None, entries=entries, last_seq=load.last_seq)
    return History(snapshot=load.snapshot, entries=load.entries[:limit], last_seq=load.last_seq)


UNREADABLE = (ValueError, KeyError, TypeError, IndexError, AttributeError)
"""What decoding a damaged stored value raises (``json.JSONDecodeError`` is a ValueError)."""


@contextmanager
def readable(session_id: str, what: str) -> Iterator[None]:
    """Decode a session's stored ``what``: a damaged value raises :class:`SessionUnreadable`
    (naming the session and ``what``, never quoting the stored text)."""
    try:
        yield
    except UNREADABLE as error:
        raise SessionUnreadable(session_id, what) from error


@contextmanager
def unavailable_on(errors: tuple[type[BaseException], ...], store: str) -> Iterator[None]:
    """Raise :class:`~app.errors.StoreUnavailable` for the backend's ``errors``."""
    try:
        yield
    except errors as error:
        raise StoreUnavailable(store, f"{type(error).__name__}: {error}"[:200]) from error


def check_seq(session_id: str, seq: int, last: int) -> None:
    """Raise :class:`SequenceConflict` unless ``seq`` follows ``last``."""
    if seq != last + 1:
        raise SequenceConflict(session_id, seq, last + 1)


def require(record: SessionRecord | None, session_id: str) -> SessionRecord:
    """The record, or :class:`SessionNotFound`."""
    if record is None:
        raise SessionNotFound(session_id)
    return record
