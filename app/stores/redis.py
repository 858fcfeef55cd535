"""The ``redis`` store: sessions as hashes, each input log a Redis Stream, snapshots by seq.

For several service instances sharing one Redis (see :mod:`app.cluster.lease`
for who may apply a session's inputs and :mod:`app.cluster.fanout` for
results reaching subscribers on any instance). The key layout is in
:mod:`app.stores.redis_keys`; every value is JSON text, nothing is pickled.

Atomicity: every write that checks something first — create (the id is
free), delete (the session is live), append (``seq == last_seq + 1``) and
snapshot (the session is live, prune to the two latest) — is one Lua script.
A script runs atomically on the server in one round trip, so 8 writers racing
on a session cost no retries; ``MULTI``/``WATCH`` would be optimistic, abort
every transaction whose watched key moved meanwhile and make each writer loop
and resend, the more often the more writers there are. Reads that need a
consistent view (:meth:`RedisStore.load`) are a script too; the others are a
``MULTI`` pipeline (a live check and a read in one transaction).

Sequence numbers: the stream entry of input ``seq`` has the id ``<seq>-0``,
so the log cannot hold two entries of one seq even if the check were skipped
(``XADD`` refuses an id that is not above the last one). An append whose
reply was lost and that the client resends (redis-py retries on connection
errors) finds its own entry at ``last_seq`` with the same ``received_at`` and
input and succeeds again without writing; any other input at a taken seq is
a :class:`~app.stores.base.SequenceConflict`.

Retention: deleting a session unlinks its record, log and snapshots;
:meth:`RedisStore.compact` trims the log stream (``XTRIM MINID``) behind the
latest snapshot. Outages: a command not answered within 2 s (a frozen Redis)
fails at once, and one whose connection broke (a restarted Redis) is sent
again twice on a new connection; then the error is raised as
:class:`~app.errors.StoreUnavailable` (503). An input whose append timed
out may still be logged once Redis thaws: the client tells from the session's
``seq`` (README, "Clients and failures").

Durability: an append returns once Redis has applied it. That is durable in
the sense of the sqlite store only if Redis persists before answering
(``appendonly yes`` with ``appendfsync always``, as ``docker/compose.yaml``
runs it); with ``everysec`` a crash of Redis itself may lose the last second.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping
from datetime import UTC, datetime, timedelta
from typing import Any, cast

import redis
from redis.backoff import ExponentialWithJitterBackoff
from redis.client import Pipeline
from redis.retry import Retry

from app.errors import SessionNotFound, SessionUnreadable
from app.stores.base import (
    LogEntry,
    SequenceConflict,
    SessionExists,
    SessionLoad,
    SessionRecord,
    Snapshot,
    StoreUsage,
    dumps,
    loads,
    readable,
    session_limit,
    tenant_session_limit,
    unavailable_on,
)
from app.stores.redis_keys import DEFAULT_PREFIX, RedisKeys

SNAPSHOTS_KEPT = 2
DEFAULT_URL = "redis://127.0.0.1:6379/0"
_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)
_SCAN_BATCH = 500
CONNECT_TIMEOUT_S = 2.0
SOCKET_TIMEOUT_S = 2.0
"""A command not answered by then fails (a frozen Redis: 503 within it, not after it thaws)."""
RECONNECT = Retry(ExponentialWithJitterBackoff(base=0.05, cap=0.5), 2, (redis.ConnectionError,))
"""A command whose connection broke (Redis restarted) is sent again on a new one, twice at
most; a timeout is not retried: a frozen Redis would hold the request a timeout per try."""
UNREACHABLE = (redis.ConnectionError, redis.TimeoutError)
"""redis-py's errors of a server that does not answer (after its retries)."""

# KEYS: session, index, tenants. ARGV: id, config, token_hash, created_at, deleted, score,
# the session limit ('' for none), tenant, the tenant's limit ('' for none). Replies
# {1} (created), {0} (the id exists), {-1, live} (the index holds `limit` live sessions
# already) or {-2, live} (the tenant has its limit): counting and creating are one step.
_CREATE = """
if redis.call('EXISTS', KEYS[1]) == 1 then return {0} end
if ARGV[7] ~= '' then
  local live = redis.call('ZCARD', KEYS[2])
  if live >= tonumber(ARGV[7]) then return {-1, live} end
end
if ARGV[9] ~= '' then
  local mine = tonumber(redis.call('HGET', KEYS[3], ARGV[8]) or '0')
  if mine >= tonumber(ARGV[9]) then return {-2, mine} end
end
redis.call('HSET', KEYS[1], 'id', ARGV[1], 'config', ARGV[2], 'token_hash', ARGV[3],
           'created_at', ARGV[4], 'deleted', ARGV[5], 'last_seq', '0', 'tenant', ARGV[8])
if ARGV[5] == '0' then
  redis.call('ZADD', KEYS[2], ARGV[6], ARGV[1])
  redis.call('HINCRBY', KEYS[3], ARGV[8], 1)
end
return {1}
"""

# KEYS: session, index, log, snapshots, tenants. ARGV: id. Frees everything the session held.
_DELETE = """
local live = redis.call('HGET', KEYS[1], 'deleted') == '0'
if live then
  local tenant = redis.call('HGET', KEYS[1], 'tenant') or ''
  if redis.call('HINCRBY', KEYS[5], tenant, -1) <= 0 then redis.call('HDEL', KEYS[5], tenant) end
end
redis.call('ZREM', KEYS[2], ARGV[1])
redis.call('UNLINK', KEYS[1], KEYS[3], KEYS[4])
if live then return 1 end
return 0
"""

# KEYS: session, snapshots, log. ARGV: through. Trims the log to seq > min(through, latest
# snapshot); replies how many entries went, or -1 without a live session.
_COMPACT = """
if redis.call('HGET', KEYS[1], 'deleted') ~= '0' then return -1 end
local latest = 0
for _, seq in ipairs(redis.call('HKEYS', KEYS[2])) do
  if tonumber(seq) > latest then latest = tonumber(seq) end
end
local through = math.min(tonumber(ARGV[1]), latest)
if through < 1 then return 0 end
return redis.call('XTRIM', KEYS[3], 'MINID', '=', (through + 1) .. '-0')
"""

# KEYS: session, log. ARGV: seq, received_at, input, the session's results channel.
# Replies {'appended', listeners}, {'replayed', listeners} (this very entry is already
# logged), {'missing'} (no live session) or {'conflict', next_seq}; listeners: the channel's
# subscribers now (a pattern subscription is not counted).
_APPEND = """
if redis.call('HGET', KEYS[1], 'deleted') ~= '0' then return {'missing'} end
local last = tonumber(redis.call('HGET', KEYS[1], 'last_seq'))
local seq = tonumber(ARGV[1])
if seq == last + 1 then
  redis.call('XADD', KEYS[2], ARGV[1] .. '-0', 'received_at', ARGV[2], 'input', ARGV[3])
  redis.call('HSET', KEYS[1], 'last_seq', ARGV[1])
  return {'appended', tostring(redis.call('PUBSUB', 'NUMSUB', ARGV[4])[2])}
end
if seq == last then
  local logged = redis.call('XRANGE', KEYS[2], ARGV[1] .. '-0', ARGV[1] .. '-0')
  if #logged == 1 then
    local fields = logged[1][2]
    if fields[2] == ARGV[2] and fields[4] == ARGV[3] then
      return {'replayed', tostring(redis.call('PUBSUB', 'NUMSUB', ARGV[4])[2])}
    end
  end
end
return {'conflict', tostring(last + 1)}
"""

# KEYS: session, snapshots. ARGV: seq, snapshot JSON, how many to keep.
_SNAPSHOT = """
if redis.call('HGET', KEYS[1], 'deleted') ~= '0' then return 0 end
redis.call('HSET', KEYS[2], ARGV[1], ARGV[2])
local seqs = redis.call('HKEYS', KEYS[2])
table.sort(seqs, function(a, b) return tonumber(a) > tonumber(b) end)
for index = tonumber(ARGV[3]) + 1, #seqs do redis.call('HDEL', KEYS[2], seqs[index]) end
if tonumber(ARGV[1]) > tonumber(redis.call('HGET', KEYS[1], 'last_seq')) then
  redis.call('HSET', KEYS[1], 'last_seq', ARGV[1])
end
return 1
"""

# KEYS: session, snapshots, log. Replies {} (no live session) or
# {record fields, latest snapshot JSON or nil, log entries after it}.
_LOAD = """
if redis.call('HGET', KEYS[1], 'deleted') ~= '0' then return {} end
local latest = nil
for _, seq in ipairs(redis.call('HKEYS', KEYS[2])) do
  if latest == nil or tonumber(seq) > tonumber(latest) then latest = seq end
end
local snapshot = false
local start = '-'
if latest ~= nil then
  snapshot = redis.call('HGET', KEYS[2], latest)
  start = '(' .. latest .. '-0'
end
return {redis.call('HGETALL', KEYS[1]), snapshot, redis.call('XRANGE', KEYS[3], start, '+')}
"""


def creation_score(created_at: datetime) -> int:
    """Microseconds since the epoch (naive times taken as UTC): the index's sort key."""
    aware = created_at if created_at.tzinfo is not None else created_at.replace(tzinfo=UTC)
    return (aware - _EPOCH) // timedelta(microseconds=1)


def _pairs(flat: list[str]) -> dict[str, str]:
    return dict(zip(flat[::2], flat[1::2], strict=True))


def _record(session_id: str, fields: Mapping[str, str]) -> SessionRecord:
    with readable(session_id, "record"):
        return SessionRecord(
            id=fields["id"],
            config=loads(fields["config"]),
            token_hash=fields["token_hash"],
            created_at=datetime.fromisoformat(fields["created_at"]),
            deleted=fields["deleted"] == "1",
            tenant=fields.get("tenant", ""),
        )


def _entry(session_id: str, stream_id: str, fields: Mapping[str, str]) -> LogEntry:
    with readable(session_id, f"input {stream_id}"):
        return LogEntry(
            seq=int(stream_id.split("-", 1)[0]),
            received_at=datetime.fromisoformat(fields["received_at"]),
            input=loads(fields["input"]),
        )


def _snapshot(session_id: str, text: str) -> Snapshot:
    with readable(session_id, "snapshot"):
        document = loads(text)
        return Snapshot(
            seq=int(document["seq"]),
            taken_at=datetime.fromisoformat(document["taken_at"]),
            state=document["state"],
        )


class RedisStore:
    """A :class:`~app.stores.base.Store` in Redis, shareable by several service instances.

    Parameters
    ----------
    url
        ``redis://[[user]:password@]HOST[:PORT][/DB]`` or ``rediss://…`` (TLS).
    prefix
        Start of every key name (``CREDAL_REDIS_PREFIX``).

    The client is redis-py's thread-safe one with a connection pool. The
    constructor does not connect: a server that is down at start (or later)
    makes every call raise :class:`StoreUnavailable` until it answers again
    (``/readyz`` says so; ``credal-fusion serve`` starts anyway).
    """

    kind = "redis"
    shared = True
    """Whether several service instances may share this store (leases, fan-out, fresh reads)."""
    blocking = True
    """Whether a call may wait on I/O (then the registry calls it in a worker thread)."""

    def __init__(self, url: str = DEFAULT_URL, prefix: str = DEFAULT_PREFIX) -> None:
        self.url = url
        self.keys = RedisKeys(prefix)
        self.client: redis.Redis = redis.Redis.from_url(
            url,
            decode_responses=True,
            socket_connect_timeout=CONNECT_TIMEOUT_S,
            socket_timeout=SOCKET_TIMEOUT_S,
            retry=RECONNECT,
            retry_on_timeout=False,
        )
        self._closed = False
        self._create = self.client.register_script(_CREATE)
        self._delete = self.client.register_script(_DELETE)
        self._append = self.client.register_script(_APPEND)
        self._snapshot = self.client.register_script(_SNAPSHOT)
        self._load = self.client.register_script(_LOAD)
        self._compact = self.client.register_script(_COMPACT)

    @property
    def prefix(self) -> str:
        """The key prefix."""
        return self.keys.prefix

    def _redis(self) -> redis.Redis:
        if self._closed:
            raise RuntimeError("the store is closed")
        return self.client

    @staticmethod
    def _reachable() -> contextlib.AbstractContextManager[None]:
        return unavailable_on(UNREACHABLE, "redis")

    def create_session(
        self,
        record: SessionRecord,
        max_sessions: int | None = None,
        max_tenant_sessions: int | None = None,
    ) -> None:
        with self._reachable():
            reply: list[int] = self._create(
                keys=[self.keys.session(record.id), self.keys.sessions(), self.keys.tenants()],
                args=[
                    record.id,
                    dumps(record.config),
                    record.token_hash,
                    record.created_at.isoformat(),
                    "1" if record.deleted else "0",
                    creation_score(record.created_at),
                    "" if max_sessions is None else str(max_sessions),
                    record.tenant,
                    "" if max_tenant_sessions is None else str(max_tenant_sessions),
                ],
                client=self._redis(),
            )
        outcome = int(reply[0])
        if outcome == -1:
            assert max_sessions is not None
            raise session_limit(max_sessions, int(reply[1]))
        if outcome == -2:
            assert max_tenant_sessions is not None
            raise tenant_session_limit(max_tenant_sessions, int(reply[1]))
        if not outcome:
            raise SessionExists(record.id)

    def get_session(self, session_id: str) -> SessionRecord | None:
        with self._reachable():
            fields = cast(dict[str, str], self._redis().hgetall(self.keys.session(session_id)))
        if not fields or fields.get("deleted") == "1":
            return None
        return _record(session_id, fields)

    def list_sessions(self) -> list[SessionRecord]:
        client = self._redis()
        with self._reachable():
            ids = cast(list[str], client.zrange(self.keys.sessions(), 0, -1))
            pipeline = client.pipeline(transaction=False)
            for session_id in ids:
                pipeline.hgetall(self.keys.session(session_id))
            rows: list[dict[str, str]] = pipeline.execute()
        records = []
        for session_id, fields in zip(ids, rows, strict=True):
            if fields and fields.get("deleted") != "1":
                with contextlib.suppress(SessionUnreadable):  # session_ids() has it
                    records.append(_record(session_id, fields))
        return records

    def session_ids(self) -> list[str]:
        with self._reachable():
            return cast(list[str], self._redis().zrange(self.keys.sessions(), 0, -1))

    def count_sessions(self) -> int:
        with self._reachable():
            return int(self._redis().zcard(self.keys.sessions()))

    def delete_session(self, session_id: str) -> bool:
        with self._reachable():
            deleted = self._delete(
                keys=[
                    self.keys.session(session_id),
                    self.keys.sessions(),
                    self.keys.log(session_id),
                    self.keys.snapshots(session_id),
                    self.keys.tenants(),
                ],
                args=[session_id],
                client=self._redis(),
            )
        return bool(deleted)

    def append(
        self, session_id: str, seq: int, entry_input: Mapping[str, Any], received_at: datetime
    ) -> bool:
        text = dumps(entry_input)
        with self._reachable():
            reply: list[str] = self._append(
                keys=[self.keys.session(session_id), self.keys.log(session_id)],
                args=[seq, received_at.isoformat(), text, self.keys.results(session_id)],
                client=self._redis(),
            )
        outcome = reply[0]
        if outcome == "missing":
            raise SessionNotFound(session_id)
        if outcome == "conflict":
            raise SequenceConflict(session_id, seq, int(reply[1]))
        return int(reply[1]) > 0

    def _live_then(self, session_id: str, read: Callable[[Pipeline], object]) -> Any:
        """``read``'s reply, run in one MULTI after the live check; else SessionNotFound."""
        with self._reachable():
            pipeline = self._redis().pipeline(transaction=True)
            pipeline.hget(self.keys.session(session_id), "deleted")
            read(pipeline)
            deleted, answer = pipeline.execute()
        if deleted != "0":
            raise SessionNotFound(session_id)
        return answer

    def last_seq(self, session_id: str) -> int:
        key = self.keys.session(session_id)
        return int(self._live_then(session_id, lambda pipeline: pipeline.hget(key, "last_seq")))

    def entries(self, session_id: str, after: int = 0, limit: int | None = None) -> list[LogEntry]:
        key = self.keys.log(session_id)
        start = f"{after + 1}-0" if after >= 0 else "-"
        rows: list[tuple[str, dict[str, str]]] = self._live_then(
            session_id, lambda pipeline: pipeline.xrange(key, min=start, max="+", count=limit)
        )
        return [_entry(session_id, stream_id, fields) for stream_id, fields in rows]

    def save_snapshot(self, session_id: str, snapshot: Snapshot) -> None:
        document = {
            "seq": snapshot.seq,
            "taken_at": snapshot.taken_at.isoformat(),
            "state": snapshot.state,
        }
        with self._reachable():
            saved = self._snapshot(
                keys=[self.keys.session(session_id), self.keys.snapshots(session_id)],
                args=[snapshot.seq, dumps(document), SNAPSHOTS_KEPT],
                client=self._redis(),
            )
        if not saved:
            raise SessionNotFound(session_id)

    def load(self, session_id: str) -> SessionLoad:
        with self._reachable():
            reply: list[Any] = self._load(
                keys=[
                    self.keys.session(session_id),
                    self.keys.snapshots(session_id),
                    self.keys.log(session_id),
                ],
                client=self._redis(),
            )
        if not reply:
            raise SessionNotFound(session_id)
        fields, snapshot, rows = reply
        with readable(session_id, "record"):
            record = _pairs(fields)
        return SessionLoad(
            session=_record(session_id, record),
            snapshot=_snapshot(session_id, snapshot) if snapshot is not None else None,
            entries=[_entry(session_id, stream_id, _pairs(entry)) for stream_id, entry in rows],
        )

    def compact(self, session_id: str, through: int) -> int:
        with self._reachable():
            dropped = int(
                self._compact(
                    keys=[
                        self.keys.session(session_id),
                        self.keys.snapshots(session_id),
                        self.keys.log(session_id),
                    ],
                    args=[through],
                    client=self._redis(),
                )
            )
        if dropped < 0:
            raise SessionNotFound(session_id)
        return dropped

    def usage(self) -> StoreUsage:
        client = self._redis()
        with self._reachable():
            keys = list(client.scan_iter(match=self.keys.pattern(), count=_SCAN_BATCH))
            pipeline = client.pipeline(transaction=False)
            for key in keys:
                pipeline.memory_usage(key, samples=0)
            logs = [key for key in keys if key.endswith(":log")]
            snapshots = [key for key in keys if key.endswith(":snapshots")]
            for key in logs:
                pipeline.xlen(key)
            for key in snapshots:
                pipeline.hlen(key)
            pipeline.zcard(self.keys.sessions())
            replies: list[Any] = pipeline.execute()
        sizes = replies[: len(keys)]
        lengths = replies[len(keys) : len(keys) + len(logs)]
        counts = replies[len(keys) + len(logs) : -1]
        return StoreUsage(
            sessions=int(replies[-1]),
            inputs=sum(int(length) for length in lengths),
            snapshots=sum(int(count) for count in counts),
            bytes=sum(int(size or 0) for size in sizes),
        )

    def ping(self) -> None:
        with self._reachable():
            self._redis().ping()

    def purge(self) -> int:
        """Delete every key under the prefix (tests, decommissioning); how many there were."""
        client = self._redis()
        removed = 0
        batch: list[str] = []
        for key in client.scan_iter(match=self.keys.pattern(), count=_SCAN_BATCH):
            batch.append(key)
            if len(batch) >= _SCAN_BATCH:
                removed += int(client.unlink(*batch))
                batch.clear()
        if batch:
            removed += int(client.unlink(*batch))
        return removed

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.client.close()
