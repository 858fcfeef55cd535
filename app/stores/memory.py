"""The ``memory`` store: dictionaries under a lock; nothing survives the process.

A deleted session is removed whole (record, log, snapshot), and a compacted
log drops its entries: what the store holds is what :meth:`MemoryStore.usage`
counts, the JSON text of the live sessions' configs, inputs and snapshots.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from datetime import datetime
from typing import Any

from app.stores.base import (
    LogEntry,
    SessionExists,
    SessionLoad,
    SessionRecord,
    Snapshot,
    StoreUsage,
    check_seq,
    decode,
    encode,
    require,
    session_limit,
    tenant_session_limit,
)


@dataclass(frozen=True)
class _Stored:
    """An input or a snapshot as the store keeps it: its JSON (one object for the collector,
    not a tree of lists and dicts)."""

    seq: int
    at: datetime
    text: bytes | str

    def entry(self) -> LogEntry:
        return LogEntry(seq=self.seq, received_at=self.at, input=decode(self.text))

    def snapshot(self) -> Snapshot:
        return Snapshot(seq=self.seq, taken_at=self.at, state=decode(self.text))


@dataclass
class _SessionData:
    record: SessionRecord
    """The session's record, its config kept apart as JSON text in ``config``."""
    config: bytes | str
    log: list[_Stored] = field(default_factory=list)
    snapshot: _Stored | None = None

    def full_record(self) -> SessionRecord:
        return replace(self.record, config=decode(self.config))


class MemoryStore:
    """A :class:`~app.stores.base.Store` in memory. Inputs are kept as JSON, like the sqlite store.

    Kept as JSON text rather than as parsed lists and dicts, a long log costs
    the garbage collector one object per input instead of a few hundred.
    """

    kind = "memory"
    shared = False
    """Whether several service instances may share this store (leases, fan-out, fresh reads)."""
    blocking = False
    """Whether a call may wait on I/O (then the registry calls it in a worker thread)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._sessions: dict[str, _SessionData] = {}

    def _live(self, session_id: str) -> _SessionData | None:
        return self._sessions.get(session_id)

    def create_session(
        self,
        record: SessionRecord,
        max_sessions: int | None = None,
        max_tenant_sessions: int | None = None,
    ) -> None:
        with self._lock:
            if record.id in self._sessions:
                raise SessionExists(record.id)
            if max_sessions is not None and len(self._sessions) >= max_sessions:
                raise session_limit(max_sessions, len(self._sessions))
            if max_tenant_sessions is not None:
                tenant = record.tenant
                live = sum(data.record.tenant == tenant for data in self._sessions.values())
                if live >= max_tenant_sessions:
                    raise tenant_session_limit(max_tenant_sessions, live)
            if not record.deleted:
                self._sessions[record.id] = _SessionData(
                    replace(record, config={}), encode(record.config)
                )

    def get_session(self, session_id: str) -> SessionRecord | None:
        with self._lock:
            data = self._live(session_id)
            return data.full_record() if data is not None else None

    def list_sessions(self) -> list[SessionRecord]:
        with self._lock:
            records = [data.full_record() for data in self._sessions.values()]
        return sorted(records, key=lambda record: (record.created_at, record.id))

    def session_ids(self) -> list[str]:
        return [record.id for record in self.list_sessions()]

    def count_sessions(self) -> int:
        with self._lock:
            return len(self._sessions)

    def delete_session(self, session_id: str) -> bool:
        with self._lock:
            return self._sessions.pop(session_id, None) is not None

    def append(
        self, session_id: str, seq: int, entry_input: Mapping[str, Any], received_at: datetime
    ) -> bool:
        logged = _Stored(seq=seq, at=received_at, text=encode(entry_input))
        with self._lock:
            data = self._require(session_id)
            check_seq(session_id, seq, self._last_seq(data))
            data.log.append(logged)
        return False

    def _require(self, session_id: str) -> _SessionData:
        data = self._live(session_id)
        require(data.record if data is not None else None, session_id)
        assert data is not None
        return data

    @staticmethod
    def _last_seq(data: _SessionData) -> int:
        if data.log:
            return data.log[-1].seq
        return data.snapshot.seq if data.snapshot is not None else 0

    def last_seq(self, session_id: str) -> int:
        with self._lock:
            return self._last_seq(self._require(session_id))

    def entries(self, session_id: str, after: int = 0, limit: int | None = None) -> list[LogEntry]:
        with self._lock:
            selected = [logged for logged in self._require(session_id).log if logged.seq > after]
        return [logged.entry() for logged in (selected if limit is None else selected[:limit])]

    def save_snapshot(self, session_id: str, snapshot: Snapshot) -> None:
        kept = _Stored(seq=snapshot.seq, at=snapshot.taken_at, text=encode(snapshot.state))
        with self._lock:
            data = self._require(session_id)
            if data.snapshot is None or snapshot.seq >= data.snapshot.seq:
                data.snapshot = kept

    def load(self, session_id: str) -> SessionLoad:
        with self._lock:
            data = self._require(session_id)
            after = data.snapshot.seq if data.snapshot is not None else 0
            return SessionLoad(
                session=data.full_record(),
                snapshot=None if data.snapshot is None else data.snapshot.snapshot(),
                entries=[logged.entry() for logged in data.log if logged.seq > after],
            )

    def compact(self, session_id: str, through: int) -> int:
        with self._lock:
            data = self._require(session_id)
            limit = min(through, data.snapshot.seq if data.snapshot is not None else 0)
            kept = [logged for logged in data.log if logged.seq > limit]
            dropped = len(data.log) - len(kept)
            data.log = kept
            return dropped

    def usage(self) -> StoreUsage:
        with self._lock:
            sessions = list(self._sessions.values())
            return StoreUsage(
                sessions=len(sessions),
                inputs=sum(len(data.log) for data in sessions),
                snapshots=sum(data.snapshot is not None for data in sessions),
                bytes=sum(
                    len(data.config)
                    + sum(len(logged.text) for logged in data.log)
                    + (len(data.snapshot.text) if data.snapshot is not None else 0)
                    for data in sessions
                ),
            )

    def ping(self) -> None:
        return None

    def close(self) -> None:
        with self._lock:
            self._sessions.clear()
