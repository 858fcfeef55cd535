"""The worker processes of one ``serve`` sharing a sqlite store: leases and results between them.

``credal-fusion serve --workers N`` (:mod:`app.workers`) runs N processes on one
listening socket; the kernel gives each new connection to one of them. They
share the sessions as several instances share a Redis store
(:mod:`app.cluster.link`): the store's ``shared`` flag is set, an input is
applied only by the worker holding the session's lease, reads catch up with
the store's log, and results reach subscribers on every worker. With the redis
store Redis does all of that already; with the sqlite store the workers meet
in a directory of their own (one per ``serve``, removed when it stops):

- :class:`FileLeases`: the leases in a sqlite file there (``leases.db``). A lease
  need not outlive the machine, so nothing is fsynced; its deadline is on the
  machine's monotonic clock (``CLOCK_MONOTONIC``, one clock for every process
  of a Linux machine). Each call is one statement, atomic under sqlite's file
  lock.
- :class:`PeerFanout`: each worker listens on a Unix socket there
  (``<pid>.sock``) and links to every other worker; a result goes to this
  worker's subscribers and, as one frame, to the linked workers that have
  subscribers of its session, which hand it to them: results are published
  only where someone listens. Which workers listen to which session is
  counted in a second sqlite file there (:class:`FileListeners`).

The store's sequence check stays the fence (``BEGIN IMMEDIATE`` takes the
file's write lock in whichever process), so a session's ``seq`` never breaks
even if a lease were wrong. Tenant quotas and the rate limit are counted per
worker (each process its own counters).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import sqlite3
import struct
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from limits.aio.storage import MemoryStorage

from app.cluster.fanout import (
    DEFAULT_MAX_PENDING,
    LocalFanout,
    ResultFanout,
    Subscription,
    _LocalSubscription,
)
from app.cluster.lease import SessionLeases, _check_ttl
from app.cluster.quotas import TenantQuotas
from app.settings import Settings
from app.stores.base import Store

logger = logging.getLogger("credal_fusion.workers")

LEASES_FILE = "leases.db"
LISTENERS_FILE = "listeners.db"
LISTENERS_TIMEOUT_S = 1.0
"""How long a call on the event loop waits for another worker's lock on the listeners file."""
_FRAME = struct.Struct("!II")
"""A result between workers: the session id's and the text's lengths (UTF-8 bytes), then both."""
MAX_LINK_BUFFER = 16 * 1024 * 1024
"""Bytes a link to a worker may hold unsent; results beyond it are dropped for that worker (a
worker that stopped reading: its subscribers are slow subscribers, who skip to the latest)."""


class FileLeases:
    """:class:`~app.cluster.lease.SessionLeases` in a sqlite file shared by the worker processes."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._local = threading.local()
        with self._connection() as connection:
            connection.execute(
                "CREATE TABLE IF NOT EXISTS leases (session_id TEXT PRIMARY KEY,"
                " owner TEXT NOT NULL, deadline REAL NOT NULL) WITHOUT ROWID"
            )

    def _connection(self) -> sqlite3.Connection:
        connection: sqlite3.Connection | None = getattr(self._local, "connection", None)
        if connection is None:
            connection = sqlite3.connect(
                self.path, isolation_level=None, check_same_thread=False, timeout=30.0
            )
            connection.execute("PRAGMA journal_mode = WAL")
            connection.execute("PRAGMA synchronous = OFF")  # a lease outlives no crash
            self._local.connection = connection
        return connection

    def _change(self, sql: str, *parameters: Any) -> bool:
        return self._connection().execute(sql, parameters).rowcount > 0

    def acquire(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        _check_ttl(ttl_ms)
        now = time.monotonic()
        return self._change(
            "INSERT INTO leases VALUES (?, ?, ?) ON CONFLICT (session_id) DO UPDATE SET"
            " owner = excluded.owner, deadline = excluded.deadline"
            " WHERE leases.owner = excluded.owner OR leases.deadline <= ?",
            session_id,
            owner,
            now + ttl_ms / 1000,
            now,
        )

    def renew(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        _check_ttl(ttl_ms)
        now = time.monotonic()
        return self._change(
            "UPDATE leases SET deadline = ? WHERE session_id = ? AND owner = ? AND deadline > ?",
            now + ttl_ms / 1000,
            session_id,
            owner,
            now,
        )

    def release(self, session_id: str, owner: str) -> bool:
        return self._change(
            "DELETE FROM leases WHERE session_id = ? AND owner = ? AND deadline > ?",
            session_id,
            owner,
            time.monotonic(),
        )

    def _held(self, session_id: str) -> tuple[str, float] | None:
        row = (
            self._connection()
            .execute(
                "SELECT owner, deadline FROM leases WHERE session_id = ? AND deadline > ?",
                (session_id, time.monotonic()),
            )
            .fetchone()
        )
        return None if row is None else (str(row[0]), float(row[1]))

    def holder(self, session_id: str) -> str | None:
        held = self._held(session_id)
        return None if held is None else held[0]

    def remaining_ms(self, session_id: str) -> int:
        held = self._held(session_id)
        return 0 if held is None else max(0, int((held[1] - time.monotonic()) * 1000))


class FileListeners:
    """How many subscriptions each worker holds of each session, in a sqlite file the worker
    processes share (nothing fsynced: a count outlives no crash of its ``serve``). Used on the
    event loop's thread: each call is one statement on a small file in the page cache.

    A subscription is counted before its subscriber reads the session's ``seq`` from the store,
    and a worker reads the count after logging the input whose result it publishes. So a
    result that a worker sends nowhere (its count read before the subscription was counted)
    was logged before that ``seq`` was read: the subscriber waits for no result that is not
    sent to it (as with Redis's ``PUBSUB NUMSUB`` read in the append script)."""

    def __init__(self, path: Path, worker: str) -> None:
        self.worker = worker
        self._connection = sqlite3.connect(
            path, isolation_level=None, check_same_thread=False, timeout=LISTENERS_TIMEOUT_S
        )
        self._connection.execute("PRAGMA journal_mode = WAL")
        self._connection.execute("PRAGMA synchronous = OFF")  # a count outlives no crash
        self._connection.execute(
            "CREATE TABLE IF NOT EXISTS listeners (session_id TEXT NOT NULL, worker TEXT NOT NULL,"
            " subscriptions INTEGER NOT NULL, PRIMARY KEY (session_id, worker)) WITHOUT ROWID"
        )
        # a process that had this pid before, in this serve, is gone: its counts are not ours
        self._connection.execute("DELETE FROM listeners WHERE worker = ?", (worker,))

    def add(self, session_id: str) -> None:
        """One more subscription of this worker to ``session_id``."""
        self._connection.execute(
            "INSERT INTO listeners VALUES (?, ?, 1) ON CONFLICT (session_id, worker)"
            " DO UPDATE SET subscriptions = subscriptions + 1",
            (session_id, self.worker),
        )

    def remove(self, session_id: str) -> None:
        """One subscription fewer of this worker to ``session_id``."""
        self._connection.execute(
            "UPDATE listeners SET subscriptions = subscriptions - 1"
            " WHERE session_id = ? AND worker = ?",
            (session_id, self.worker),
        )
        self._connection.execute(
            "DELETE FROM listeners WHERE session_id = ? AND worker = ? AND subscriptions <= 0",
            (session_id, self.worker),
        )

    def elsewhere(self, session_id: str) -> list[str]:
        """The other workers with subscriptions to ``session_id``."""
        rows = self._connection.execute(
            "SELECT worker FROM listeners WHERE session_id = ? AND worker != ?",
            (session_id, self.worker),
        )
        return [str(row[0]) for row in rows]

    def close(self) -> None:
        self._connection.execute("DELETE FROM listeners WHERE worker = ?", (self.worker,))
        self._connection.close()


class _PeerSubscription(_LocalSubscription):
    """A subscription of one worker, counted in :class:`FileListeners` while it lasts."""

    def __init__(self, fanout: PeerFanout, session_id: str) -> None:
        super().__init__(fanout.local, session_id, fanout.local.max_pending)
        self._listeners = fanout.listeners
        self._counted = False

    async def start(self) -> None:
        await super().start()
        self._listeners.add(self.session_id)
        self._counted = True

    async def aclose(self) -> None:
        if self._counted:
            self._counted = False
            self._listeners.remove(self.session_id)
        await super().aclose()


class PeerFanout:
    """:class:`~app.cluster.fanout.ResultFanout` among the worker processes of one ``serve``."""

    def __init__(
        self, directory: Path, max_pending: int = DEFAULT_MAX_PENDING, name: str | None = None
    ) -> None:
        self.directory = directory
        self.name = name or str(os.getpid())
        """This worker's name among the others (its pid)."""
        self.local = LocalFanout(max_pending)
        self.listeners = FileListeners(directory / LISTENERS_FILE, self.name)
        self.dropped = 0
        """Results not sent to a worker whose link was full."""
        self.forwarded = 0
        """Results sent to other workers (one per worker sent to)."""
        self._links: dict[str, asyncio.StreamWriter] = {}
        self._readers: set[asyncio.Task[None]] = set()
        self._server: asyncio.Server | None = None

    @property
    def peers(self) -> int:
        """Workers linked to this one."""
        return len(self._links)

    async def start(self) -> None:
        """Listen, then link to every worker already listening (one that starts later links
        to this one): from then on every result a linked worker publishes of a session this
        one listens to arrives here."""
        own = self.directory / f"{self.name}.sock"
        self._server = await asyncio.start_unix_server(self._accepted, path=str(own))
        for path in sorted(self.directory.glob("*.sock")):
            if path != own:
                await self._connect(path)

    async def _connect(self, path: Path) -> None:
        try:
            reader, writer = await asyncio.open_unix_connection(str(path))
        except OSError:  # a worker that is gone: its socket file stays until the serve ends
            return
        name = self.name.encode()
        writer.write(_FRAME.pack(len(name), 0) + name)
        self._link(path.stem, reader, writer)

    async def _accepted(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        with contextlib.suppress(asyncio.IncompleteReadError, ConnectionError):
            size, _ = _FRAME.unpack(await reader.readexactly(_FRAME.size))
            name = (await reader.readexactly(size)).decode()
            self._link(name, reader, writer)

    def _link(self, name: str, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._links[name] = writer  # two links to one worker (both connected): either sends
        task = asyncio.create_task(self._read(name, reader, writer), name=f"peer:{name}")
        self._readers.add(task)
        task.add_done_callback(self._readers.discard)

    async def _read(
        self, name: str, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        try:
            while True:
                sid_size, text_size = _FRAME.unpack(await reader.readexactly(_FRAME.size))
                body = await reader.readexactly(sid_size + text_size)
                await self.local.publish(body[:sid_size].decode(), body[sid_size:].decode())
        except (asyncio.IncompleteReadError, ConnectionError):
            pass  # that worker stopped
        finally:
            if self._links.get(name) is writer:
                del self._links[name]
            writer.close()

    async def publish(self, session_id: str, result_json: str) -> int:
        """To this worker's subscribers of the session, and to the linked workers that have
        some (:class:`FileListeners`); how many subscriptions of this worker got it."""
        delivered = await self.local.publish(session_id, result_json)
        if self._links:
            try:
                names: Iterable[str] = self.listeners.elsewhere(session_id)
            except sqlite3.Error:  # the count unreadable (a worker stalled holding its lock):
                names = list(self._links)  # every linked worker, as before counts existed
            links = [self._links[name] for name in names if name in self._links]
            if links:
                sid, text = session_id.encode(), result_json.encode()
                frame = _FRAME.pack(len(sid), len(text)) + sid + text
                for writer in links:
                    if writer.transport.get_write_buffer_size() > MAX_LINK_BUFFER:
                        self.dropped += 1
                    else:
                        writer.write(frame)
                        self.forwarded += 1
        return delivered

    def subscribe(self, session_id: str) -> Subscription:
        return _PeerSubscription(self, session_id)

    async def ping(self) -> None:
        return None

    async def aclose(self) -> None:
        if self._server is not None:
            self._server.close()
        for writer in list(self._links.values()):
            writer.close()
        for task in list(self._readers):
            task.cancel()
        await self.local.aclose()
        self.listeners.close()


@dataclass(frozen=True)
class WorkerGroup:
    """Where the worker processes of one ``serve`` meet (a directory of that ``serve``)."""

    directory: Path

    async def join(self, store: Store, settings: Settings) -> dict[str, Any]:
        """Share ``store`` with the other workers; the registry's parts that do it
        (``leases``, ``fanout``, ``quotas``: keyword arguments of
        :class:`~app.sessions.registry.SessionRegistry`), none for a store shared already."""
        if store.shared:  # redis: its leases, fan-out and quotas are every worker's already
            return {}
        if store.kind != "sqlite":
            raise RuntimeError(f"the {store.kind} store cannot be shared by worker processes")
        store.shared = True
        fanout = PeerFanout(self.directory)
        await fanout.start()
        leases: SessionLeases = FileLeases(self.directory / LEASES_FILE)
        shared: ResultFanout = fanout
        quotas = TenantQuotas(  # this worker's counters
            MemoryStorage(), settings.tenant_inputs_per_second, settings.tenant_work_per_minute
        )
        return {"leases": leases, "fanout": shared, "quotas": quotas}
