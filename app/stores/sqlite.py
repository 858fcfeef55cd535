"""The ``sqlite`` store: one file (``./data`` by default), WAL journal, durable commits.

Durability: the database runs in WAL mode with ``synchronous=FULL`` by default, so
every commit fsyncs the write-ahead log before ``COMMIT`` returns; an input
is acknowledged only once the transaction holding it has committed, hence a
crash — of the process or of the machine — loses no acknowledged input.
``synchronous=NORMAL`` (``CREDAL_SQLITE_SYNCHRONOUS``) commits without the
fsync: the WAL frames are in the kernel's page cache when ``COMMIT`` returns,
so an acknowledged input survives the process's death (SIGKILL, a crash of
the service) but the last commits may be lost if the machine itself stops
(power loss, kernel crash); it costs less CPU per input (no fsync).

Retention: a deleted session's rows are deleted, and :meth:`SqliteStore.compact`
deletes the inputs behind a snapshot; sqlite reuses the freed pages, so the
file stops growing once a session's retained log has its size (the WAL is
checkpointed automatically and truncated to ``JOURNAL_SIZE_LIMIT``).
sqlite's ``OperationalError`` (I/O error, full disk, a lock held past the
busy timeout, a file that cannot be opened) is raised as
:class:`~app.errors.StoreUnavailable`; a damaged file ("database disk
image is malformed", "file is not a database") as
:class:`~app.errors.StoreCorrupt`, a permanent fault (opening such a file
succeeds: the service starts, not ready).

Threads: each thread reads on its own connection; every write goes through
one connection, whichever thread makes it, under a process lock (its page
cache stays warm: with a write connection per thread, each append reread the
pages the other threads' connections had changed). Across processes sqlite's
file lock serialises the writes (``BEGIN IMMEDIATE``, or a lone statement's
own transaction), and the sequence-number check is part of the statement that
logs an input (``_APPEND``), so it holds whichever process writes.

Group commit: the fsync is most of an append's cost, so inputs that arrive
while a commit is under way share the next one. Every append is queued; whoever
holds the write lock next (the leader) logs every input queued by then in one
``BEGIN IMMEDIATE`` … ``COMMIT`` (one fsync) and marks them done. The service's
event loop queues its inputs with :meth:`SqliteStore.append_queued` and does not
wait in a thread: the store's committer thread (started on first use) is the
leader, and tells each input's caller once its batch has ended (committed or
not); a thread calling :meth:`SqliteStore.append` queues its input, then takes
the write lock, and returns once its input is done, committed by itself or by
another leader. Either way an input is acknowledged only once the transaction
holding it is durable: a crash loses no acknowledged input, however many share
a commit. A batch of one is a single statement (its own transaction, committed
and fsynced before it returns) — each sqlite call lets the event loop's thread
take the GIL, which the committing thread then waits to get back (a forced
switch each), so the fewer calls the better: per batch, the committer is woken
once, runs its statement(s) and settles the batch; the event loop pays no
worker-thread hop per input.
"""

from __future__ import annotations

import contextlib
import logging
import sqlite3
import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, Literal, TypeVar

from app.errors import SessionNotFound, SessionUnreadable, StoreCorrupt, StoreUnavailable
from app.stores.base import (
    LogEntry,
    SequenceConflict,
    SessionExists,
    SessionLoad,
    SessionRecord,
    Snapshot,
    StoreUsage,
    check_seq,
    dumps,
    loads,
    readable,
    require,
    session_limit,
    tenant_session_limit,
)

SCHEMA_VERSION = 2
"""1: the first; 2: sessions carry their tenant (a version-1 file is migrated on open)."""
SNAPSHOTS_KEPT = 2
BUSY_TIMEOUT_MS = 30_000
JOURNAL_SIZE_LIMIT = 16 * 1024 * 1024
"""Bytes the WAL file is truncated to after a checkpoint."""
T = TypeVar("T")
logger = logging.getLogger("credal_fusion.stores")
Synchronous = Literal["FULL", "NORMAL"]

SCHEMA = """
CREATE TABLE IF NOT EXISTS sessions (
    id TEXT PRIMARY KEY,
    config TEXT NOT NULL,
    token_hash TEXT NOT NULL,
    created_at TEXT NOT NULL,
    deleted INTEGER NOT NULL DEFAULT 0,
    tenant TEXT NOT NULL DEFAULT ''
);
CREATE TABLE IF NOT EXISTS inputs (
    session_id TEXT NOT NULL REFERENCES sessions(id),
    seq INTEGER NOT NULL,
    received_at TEXT NOT NULL,
    input TEXT NOT NULL,
    PRIMARY KEY (session_id, seq)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS snapshots (
    session_id TEXT NOT NULL REFERENCES sessions(id),
    seq INTEGER NOT NULL,
    taken_at TEXT NOT NULL,
    state TEXT NOT NULL,
    PRIMARY KEY (session_id, seq)
) WITHOUT ROWID;
"""


_APPEND = """
INSERT INTO inputs (session_id, seq, received_at, input) SELECT ?1, ?2, ?3, ?4
WHERE EXISTS (SELECT 1 FROM sessions WHERE id = ?1 AND deleted = 0)
AND ?2 = 1 + max(
    coalesce((SELECT max(seq) FROM inputs WHERE session_id = ?1), 0),
    coalesce((SELECT max(seq) FROM snapshots WHERE session_id = ?1), 0)
)
"""
"""An input logged only if its session is live and its seq follows the session's last (logged
input or snapshot): the store's sequence check in the statement that writes."""

_ID = {"inputs": "session_id", "snapshots": "session_id", "sessions": "id"}
"""The column holding the session id, per table."""


def _record(row: sqlite3.Row) -> SessionRecord:
    with readable(str(row["id"]), "record"):
        return SessionRecord(
            id=row["id"],
            config=loads(row["config"]),
            token_hash=row["token_hash"],
            created_at=datetime.fromisoformat(row["created_at"]),
            deleted=bool(row["deleted"]),
            tenant=row["tenant"],
        )


def _entry(session_id: str, row: sqlite3.Row) -> LogEntry:
    with readable(session_id, f"input {row['seq']}"):
        return LogEntry(
            seq=row["seq"],
            received_at=datetime.fromisoformat(row["received_at"]),
            input=loads(row["input"]),
        )


CORRUPT_MESSAGES = ("malformed", "not a database", "corrupt")
"""sqlite errors that say the file itself is damaged (whatever exception class they come as)."""


@contextmanager
def _faults() -> Iterator[None]:
    """sqlite's errors as the service's: a damaged file is :class:`StoreCorrupt` (permanent),
    any other operational error :class:`StoreUnavailable` (503, retry)."""
    try:
        yield
    except sqlite3.DatabaseError as error:
        reason = f"{type(error).__name__}: {error}"[:200]
        damaged = not isinstance(error, sqlite3.OperationalError) or any(
            text in str(error).lower() for text in CORRUPT_MESSAGES
        )
        if damaged:
            raise StoreCorrupt("sqlite", reason) from error
        raise StoreUnavailable("sqlite", reason) from error


Settled = Callable[[bool, Exception | None], None]
"""What :meth:`SqliteStore.append_queued` calls once its input's batch has ended: with what
:meth:`SqliteStore.append` would return, and the error it would raise (``None``: logged)."""


@dataclass(eq=False)
class _Append:
    """An input waiting in :meth:`SqliteStore.append` (or queued by
    :meth:`SqliteStore.append_queued`) for the commit that logs it."""

    session_id: str
    seq: int
    received_at: datetime
    entry_input: Mapping[str, Any]
    settled: Settled | None = None
    """Called by whoever commits its batch (:meth:`SqliteStore.append_queued`)."""
    done: bool = False
    """Its batch's transaction has ended (committed, or rolled back: then ``error`` is set)."""
    error: Exception | None = None


class SqliteStore:
    """A :class:`~app.stores.base.Store` in one SQLite file."""

    kind = "sqlite"
    shared = False
    """Whether several service instances may share this store (leases, fan-out, fresh reads)."""
    blocking = True
    """Whether a call may wait on I/O (then the registry calls it in a worker thread)."""

    def __init__(self, path: Path | str, synchronous: Synchronous = "FULL") -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._synchronous = synchronous
        self._local = threading.local()
        self._connections: list[sqlite3.Connection] = []
        self._connections_lock = threading.Lock()
        self._write_lock = threading.Lock()
        self._write_connection: sqlite3.Connection | None = None
        """One connection for every write (:meth:`_writer`): its page cache stays warm."""
        self._queue_lock = threading.Lock()
        self._queue: list[_Append] = []
        """Appends waiting for the next group commit (:meth:`append`, :meth:`append_queued`)."""
        self._queued = threading.Condition(self._queue_lock)
        """Notified when :meth:`append_queued` queues an input (the committer waits on it)."""
        self._committer: threading.Thread | None = None
        """The thread committing what :meth:`append_queued` queues, started on its first call."""
        self._closed = False
        with contextlib.suppress(StoreCorrupt):  # a damaged file: every use says so (/readyz)
            self._create_schema()

    def _create_schema(self) -> None:
        with self._write() as connection:
            for statement in SCHEMA.split(";"):
                if statement.strip():
                    connection.execute(statement)
            version = connection.execute("PRAGMA user_version").fetchone()[0]
            if version == 1:  # before tenants: every session's tenant is ''
                connection.execute(
                    "ALTER TABLE sessions ADD COLUMN tenant TEXT NOT NULL DEFAULT ''"
                )
            if version in (0, 1):
                connection.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            elif version != SCHEMA_VERSION:
                raise RuntimeError(
                    f"{self.path}: schema version {version}, this service knows {SCHEMA_VERSION}"
                )

    def _connection(self) -> sqlite3.Connection:
        """This thread's connection (reads)."""
        if self._closed:
            raise RuntimeError("the store is closed")
        connection: sqlite3.Connection | None = getattr(self._local, "connection", None)
        if connection is None:
            connection = self._local.connection = self._connect()
        return connection

    def _writer(self) -> sqlite3.Connection:
        """The connection every write uses, whichever thread makes it (under the write lock)."""
        if self._closed:
            raise RuntimeError("the store is closed")
        if self._write_connection is None:
            self._write_connection = self._connect()
        return self._write_connection

    def _connect(self) -> sqlite3.Connection:
        connection = sqlite3.connect(
            self.path,
            isolation_level=None,
            check_same_thread=False,
            timeout=BUSY_TIMEOUT_MS / 1000,
        )
        connection.row_factory = sqlite3.Row
        connection.execute("PRAGMA journal_mode = WAL")
        connection.execute(f"PRAGMA synchronous = {self._synchronous}")
        connection.execute("PRAGMA foreign_keys = ON")
        connection.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        connection.execute(f"PRAGMA journal_size_limit = {JOURNAL_SIZE_LIMIT}")
        with self._connections_lock:
            self._connections.append(connection)
        return connection

    @contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        with self._write_lock, self._transaction() as connection:
            yield connection

    @contextmanager
    def _transaction(self) -> Iterator[sqlite3.Connection]:
        """One ``BEGIN IMMEDIATE`` … ``COMMIT`` on this thread's connection (rolled back on any
        error), sqlite's operational errors as StoreUnavailable; the caller holds the write lock."""
        with _faults():
            connection = self._writer()
            connection.execute("BEGIN IMMEDIATE")
            try:
                yield connection
            except BaseException:
                if connection.in_transaction:
                    connection.execute("ROLLBACK")
                raise
            try:
                connection.execute("COMMIT")
            except BaseException:
                # A failed COMMIT may leave the transaction open (SQLITE_BUSY) or half undone
                # (IOERR, FULL): end it, so that the shared writer's next lone append is its own
                # transaction, not a statement inside one that is never committed.
                if connection.in_transaction:
                    connection.execute("ROLLBACK")
                raise

    def _read(self, read: Callable[[sqlite3.Connection], T]) -> T:
        """``read`` on this thread's connection; sqlite's operational errors as StoreUnavailable."""
        with _faults():
            return read(self._connection())

    def _live_record(self, connection: sqlite3.Connection, session_id: str) -> SessionRecord | None:
        row = connection.execute(
            "SELECT * FROM sessions WHERE id = ? AND deleted = 0", (session_id,)
        ).fetchone()
        return _record(row) if row is not None else None

    @staticmethod
    def _last_seq(connection: sqlite3.Connection, session_id: str) -> int:
        row = connection.execute(
            "SELECT max(seq) FROM (SELECT max(seq) AS seq FROM inputs WHERE session_id = ?"
            " UNION ALL SELECT max(seq) FROM snapshots WHERE session_id = ?)",
            (session_id, session_id),
        ).fetchone()
        return int(row[0]) if row[0] is not None else 0

    def create_session(
        self,
        record: SessionRecord,
        max_sessions: int | None = None,
        max_tenant_sessions: int | None = None,
    ) -> None:
        with self._write() as connection:  # one IMMEDIATE transaction: count, then insert
            exists = connection.execute(
                "SELECT 1 FROM sessions WHERE id = ?", (record.id,)
            ).fetchone()
            if exists is not None:
                raise SessionExists(record.id)
            if max_sessions is not None:
                (live,) = connection.execute(
                    "SELECT COUNT(*) FROM sessions WHERE deleted = 0"
                ).fetchone()
                if live >= max_sessions:
                    raise session_limit(max_sessions, int(live))
            if max_tenant_sessions is not None:
                (mine,) = connection.execute(
                    "SELECT COUNT(*) FROM sessions WHERE deleted = 0 AND tenant = ?",
                    (record.tenant,),
                ).fetchone()
                if mine >= max_tenant_sessions:
                    raise tenant_session_limit(max_tenant_sessions, int(mine))
            connection.execute(
                "INSERT INTO sessions (id, config, token_hash, created_at, deleted, tenant)"
                " VALUES (?, ?, ?, ?, ?, ?)",
                (
                    record.id,
                    dumps(record.config),
                    record.token_hash,
                    record.created_at.isoformat(),
                    int(record.deleted),
                    record.tenant,
                ),
            )

    def get_session(self, session_id: str) -> SessionRecord | None:
        return self._read(lambda connection: self._live_record(connection, session_id))

    def list_sessions(self) -> list[SessionRecord]:
        def read(connection: sqlite3.Connection) -> list[SessionRecord]:
            records = []
            for row in connection.execute(
                "SELECT * FROM sessions WHERE deleted = 0 ORDER BY created_at, id"
            ):
                with contextlib.suppress(SessionUnreadable):  # session_ids() has it
                    records.append(_record(row))
            return records

        return self._read(read)

    def session_ids(self) -> list[str]:
        return self._read(
            lambda connection: [
                str(row[0])
                for row in connection.execute(
                    "SELECT id FROM sessions WHERE deleted = 0 ORDER BY created_at, id"
                )
            ]
        )

    def count_sessions(self) -> int:
        return self._read(
            lambda connection: int(
                connection.execute("SELECT count(*) FROM sessions WHERE deleted = 0").fetchone()[0]
            )
        )

    def delete_session(self, session_id: str) -> bool:
        with self._write() as connection:  # nothing decoded: an unreadable session goes too
            live = (
                connection.execute(
                    "SELECT 1 FROM sessions WHERE id = ? AND deleted = 0", (session_id,)
                ).fetchone()
                is not None
            )
            for table in ("inputs", "snapshots", "sessions"):
                connection.execute(f"DELETE FROM {table} WHERE {_ID[table]} = ?", (session_id,))
            return live

    def append(
        self, session_id: str, seq: int, entry_input: Mapping[str, Any], received_at: datetime
    ) -> bool:
        """Log an input; returns once the transaction holding it is committed (group commit:
        module docstring). Its own refusal (:class:`SequenceConflict`, 404) is raised to it
        alone; a failed commit to every input of the batch, none of which is then logged."""
        pending = _Append(session_id, seq, received_at, entry_input)
        with self._queue_lock:
            self._queue.append(pending)
        with self._write_lock:  # the leader commits every queued append, its own included
            if not pending.done:
                self._commit_queued()
        if pending.error is not None:
            raise pending.error
        # shared by the worker processes of one serve (app.cluster.peers), the file cannot
        # count their subscribers: every result goes to the other workers
        return self.shared

    def append_queued(
        self,
        session_id: str,
        seq: int,
        entry_input: Mapping[str, Any],
        received_at: datetime,
        settled: Settled,
    ) -> None:
        """Queue an input for the store's committer thread and return at once; ``settled`` is
        called (on that thread) once the transaction holding it has ended: what
        :meth:`append` would have returned or raised. So the event loop logs an input without
        a worker thread of its own: encoding, statements and commit run on the committer,
        which commits everything queued meanwhile in one transaction (one fsync) and settles
        it all; the input is to be acknowledged only when ``settled`` says it is logged."""
        pending = _Append(session_id, seq, received_at, entry_input, settled)
        with self._queued:
            if self._closed:
                pending.error = RuntimeError("the store is closed")
            else:
                self._queue.append(pending)
                if self._committer is None or not self._committer.is_alive():
                    self._committer = threading.Thread(
                        target=self._commit_loop, name="sqlite-committer", daemon=True
                    )
                    self._committer.start()
                self._queued.notify()
                return
        self._settle(pending)

    def _commit_loop(self) -> None:
        """The committer: waits for queued inputs, commits each batch (:meth:`_commit_queued`)."""
        while True:
            with self._queued:
                while not self._queue and not self._closed:
                    self._queued.wait()
                if self._closed:
                    return
            with self._write_lock:
                if not self._closed:
                    self._commit_queued()

    def _commit_queued(self) -> None:
        """One commit (one fsync) for every append queued now (under the write lock): a lone
        append is one statement, its own transaction; several share ``BEGIN IMMEDIATE`` …
        ``COMMIT``. Each sqlite call lets the event loop's thread take the GIL, which this
        thread must then wait to get back: the fewer calls, the fewer waits (and futex
        round trips) per input."""
        with self._queue_lock:
            batch, self._queue = self._queue, []
        committed = False
        try:
            if len(batch) == 1:
                with _faults():
                    writer = self._writer()
                    if writer.in_transaction:  # never acknowledge a statement left uncommitted
                        writer.execute("ROLLBACK")
                    self._insert(writer, batch[0])
            else:
                with self._transaction() as connection:
                    for pending in batch:
                        self._insert(connection, pending)
            committed = True
        except Exception as error:  # nothing of the batch is logged
            for pending in batch:
                pending.error = error
        finally:
            for pending in batch:
                if not committed and pending.error is None:  # interrupted: not logged either
                    pending.error = StoreUnavailable("sqlite", "the commit was interrupted")
                pending.done = True
            for pending in batch:
                self._settle(pending)

    def _settle(self, pending: _Append) -> None:
        """Tell :meth:`append_queued`'s caller how its input's batch ended (never raises: the
        committer thread goes on whatever a caller's callback does)."""
        if pending.settled is not None:
            try:
                pending.settled(self.shared, pending.error)
            except Exception:
                logger.exception("sqlite: an append's callback failed")

    def _insert(self, connection: sqlite3.Connection, pending: _Append) -> None:
        """Log ``pending`` if its session is live and its seq the next one (one statement: the
        check and the insert), else set its refusal."""
        try:
            text = dumps(pending.entry_input)
        except (TypeError, ValueError) as error:  # not plain data: refused alone
            pending.error = error
            return
        row = (pending.session_id, pending.seq, pending.received_at.isoformat(), text)
        if connection.execute(_APPEND, row).rowcount != 1:
            pending.error = self._refusal(connection, pending.session_id, pending.seq)

    def _refusal(self, connection: sqlite3.Connection, session_id: str, seq: int) -> Exception:
        """Why ``_APPEND`` did not log input ``seq`` of ``session_id`` (read on the connection
        that tried, under the write lock)."""
        live = connection.execute(
            "SELECT 1 FROM sessions WHERE id = ? AND deleted = 0", (session_id,)
        ).fetchone()
        if live is None:
            return SessionNotFound(session_id)
        try:
            check_seq(session_id, seq, self._last_seq(connection, session_id))
        except SequenceConflict as conflict:
            return conflict
        return StoreUnavailable("sqlite", "the session's log changed during the append")

    def last_seq(self, session_id: str) -> int:
        def read(connection: sqlite3.Connection) -> int:
            require(self._live_record(connection, session_id), session_id)
            return self._last_seq(connection, session_id)

        return self._read(read)

    def entries(self, session_id: str, after: int = 0, limit: int | None = None) -> list[LogEntry]:
        def read(connection: sqlite3.Connection) -> list[LogEntry]:
            require(self._live_record(connection, session_id), session_id)
            rows = connection.execute(
                "SELECT seq, received_at, input FROM inputs WHERE session_id = ? AND seq > ?"
                " ORDER BY seq LIMIT ?",
                (session_id, after, -1 if limit is None else limit),
            )
            return [_entry(session_id, row) for row in rows]

        return self._read(read)

    def save_snapshot(self, session_id: str, snapshot: Snapshot) -> None:
        text = dumps(snapshot.state)
        with self._write() as connection:
            require(self._live_record(connection, session_id), session_id)
            connection.execute(
                "INSERT OR REPLACE INTO snapshots (session_id, seq, taken_at, state) VALUES (?, ?, ?, ?)",
                (session_id, snapshot.seq, snapshot.taken_at.isoformat(), text),
            )
            connection.execute(
                "DELETE FROM snapshots WHERE session_id = ? AND seq NOT IN"
                " (SELECT seq FROM snapshots WHERE session_id = ? ORDER BY seq DESC LIMIT ?)",
                (session_id, session_id, SNAPSHOTS_KEPT),
            )

    def load(self, session_id: str) -> SessionLoad:
        """The record, the newest snapshot and the inputs after it, read in one (deferred) read
        transaction: in WAL its first read fixes the snapshot of the file every later read
        sees, so a writer's commit in between (a snapshot, a compaction) never shows half."""
        return self._read(lambda connection: self._load(connection, session_id))

    def _load(self, connection: sqlite3.Connection, session_id: str) -> SessionLoad:
        connection.execute("BEGIN")
        try:
            record = require(self._live_record(connection, session_id), session_id)
            row = connection.execute(
                "SELECT seq, taken_at, state FROM snapshots WHERE session_id = ? ORDER BY seq DESC LIMIT 1",
                (session_id,),
            ).fetchone()
            snapshot = None
            if row is not None:
                with readable(session_id, f"snapshot {row['seq']}"):
                    snapshot = Snapshot(
                        seq=row["seq"],
                        taken_at=datetime.fromisoformat(row["taken_at"]),
                        state=loads(row["state"]),
                    )
            after = snapshot.seq if snapshot is not None else 0
            rows = connection.execute(
                "SELECT seq, received_at, input FROM inputs WHERE session_id = ? AND seq > ? ORDER BY seq",
                (session_id, after),
            )
            entries = [_entry(session_id, entry) for entry in rows]
        finally:
            if connection.in_transaction:
                connection.execute("COMMIT")
        return SessionLoad(session=record, snapshot=snapshot, entries=entries)

    def compact(self, session_id: str, through: int) -> int:
        with self._write() as connection:
            require(self._live_record(connection, session_id), session_id)
            cursor = connection.execute(
                "DELETE FROM inputs WHERE session_id = ? AND seq <= min(?, coalesce("
                "(SELECT max(seq) FROM snapshots WHERE session_id = ?), 0))",
                (session_id, through, session_id),
            )
            return cursor.rowcount

    def usage(self) -> StoreUsage:
        def read(connection: sqlite3.Connection) -> StoreUsage:
            def count(sql: str) -> int:
                return int(connection.execute(sql).fetchone()[0])

            pages = count("PRAGMA page_count") - count("PRAGMA freelist_count")
            return StoreUsage(
                sessions=count("SELECT count(*) FROM sessions WHERE deleted = 0"),
                inputs=count("SELECT count(*) FROM inputs"),
                snapshots=count("SELECT count(*) FROM snapshots"),
                bytes=pages * count("PRAGMA page_size"),
            )

        return self._read(read)

    def ping(self) -> None:
        self._read(lambda connection: connection.execute("SELECT 1").fetchone())

    def close(self) -> None:
        with self._queued:
            self._closed = True
            self._queued.notify_all()
            left, self._queue = self._queue, []
        committer = self._committer
        if committer is not None and committer is not threading.current_thread():
            committer.join()
        for pending in left:  # queued, never committed: not logged
            pending.error = StoreUnavailable("sqlite", "the store was closed")
            pending.done = True
            self._settle(pending)
        # under the write lock: never close the shared writer inside another thread's write
        with self._write_lock, self._connections_lock:
            for connection in self._connections:
                connection.close()
            self._connections.clear()
