"""Per-session leases: only the instance holding a session's lease applies its inputs.

With the redis store several service instances share the sessions. An
instance that is about to apply an input to a session must hold the
session's lease; the lease has a TTL, so when its holder dies (or stalls
past the TTL) another instance takes the session over.

Use in the routes (recipe)
--------------------------
``leases = open_leases(store)`` once in the lifespan, ``owner = new_owner_id()``
once per process, then for each input of session ``sid``::

    if not leases.acquire(sid, owner, LEASE_TTL_MS):
        # another instance applies this session's inputs: answer 409/503 with
        # Retry-After (or proxy to leases.holder(sid)); the load balancer's
        # session affinity makes this rare
        ...
    if the engine in memory was built while another owner held the lease:
        rebuild it from store.load(sid)     # the other instance moved the log on
    seq = store.last_seq(sid) + 1
    store.append(sid, seq, input, received_at)  # SequenceConflict: we were overtaken,
                                                # drop the engine, reload, retry once
    apply, publish the result (app.cluster.fanout)

``acquire`` by the holder renews (it is re-entrant), so calling it before
every input is enough while inputs keep coming; while a ``stream`` WebSocket
is open on a session, its connection renews the lease every ``ttl / 3``
(:meth:`~app.sessions.registry.SessionRegistry.keep_lease`) and closes with
1013 when ``renew`` answers ``False`` (another instance took the session
over: the client reconnects). An idle session's lease lapses after the TTL,
so the session may move to whichever instance its next input reaches. With
the default TTL of 3 s, a dead instance's sessions are taken over within 3 s;
a refused instance's ``Retry-After`` is the lease's time left. ``release`` when the session is
deleted or the instance shuts down, so another takes over at once instead of
after the TTL.

A lease is advisory: a holder paused past its TTL may still try to write.
The store's sequence check is the fence — the taken-over session's log has
moved on, so the stale writer's ``append`` raises ``SequenceConflict`` and
nothing is logged twice.

Two implementations of one protocol: :class:`RedisLeases` (``SET NX PX``
plus Lua compare-and-renew / compare-and-release, for several instances) and
:class:`LocalLeases` (one process: a dictionary and the monotonic clock).
"""

from __future__ import annotations

import os
import socket
import threading
import time
import uuid
from typing import Protocol, runtime_checkable

import redis

from app.cluster import shared_redis
from app.stores.base import Store, unavailable_on
from app.stores.redis import UNREACHABLE
from app.stores.redis_keys import RedisKeys

DEFAULT_LEASE_TTL_MS = 3_000

# KEYS: lease. ARGV: owner, ttl_ms. Takes a free lease, or renews the owner's own.
_ACQUIRE = """
if redis.call('SET', KEYS[1], ARGV[1], 'NX', 'PX', ARGV[2]) then return 1 end
if redis.call('GET', KEYS[1]) == ARGV[1] then
  redis.call('PEXPIRE', KEYS[1], ARGV[2])
  return 1
end
return 0
"""

# KEYS: lease. ARGV: owner, ttl_ms.
_RENEW = """
if redis.call('GET', KEYS[1]) == ARGV[1] then
  redis.call('PEXPIRE', KEYS[1], ARGV[2])
  return 1
end
return 0
"""

# KEYS: lease. ARGV: owner.
_RELEASE = """
if redis.call('GET', KEYS[1]) == ARGV[1] then
  redis.call('DEL', KEYS[1])
  return 1
end
return 0
"""


def new_owner_id() -> str:
    """An owner id unique to this process: host, pid and a random part."""
    return f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:12]}"


def _check_ttl(ttl_ms: int) -> None:
    if ttl_ms < 1:
        raise ValueError(f"lease ttl {ttl_ms} ms: must be at least 1 ms")


@runtime_checkable
class SessionLeases(Protocol):
    """Who applies a session's inputs. Thread-safe."""

    def acquire(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        """Take the lease if it is free or lapsed, or renew it if ``owner`` holds it."""
        ...

    def renew(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        """Extend the lease to ``ttl_ms`` from now; ``False`` if ``owner`` no longer holds it."""
        ...

    def release(self, session_id: str, owner: str) -> bool:
        """Give the lease up; ``False`` (and nothing changed) if ``owner`` did not hold it."""
        ...

    def holder(self, session_id: str) -> str | None:
        """The owner holding the lease now, if any."""
        ...

    def remaining_ms(self, session_id: str) -> int:
        """How long the lease has left unless renewed (0: free)."""
        ...


class RedisLeases:
    """Leases as Redis strings ``P:{sid}:lease`` = owner, with a PX expiry.

    Parameters
    ----------
    client
        A synchronous client created with ``decode_responses=True`` (the
        store's :attr:`~app.stores.redis.RedisStore.client`).
    keys
        The names under the deployment's prefix.
    """

    def __init__(self, client: redis.Redis, keys: RedisKeys) -> None:
        self.client = client
        self.keys = keys
        self._acquire = client.register_script(_ACQUIRE)
        self._renew = client.register_script(_RENEW)
        self._release = client.register_script(_RELEASE)

    def acquire(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        _check_ttl(ttl_ms)
        with unavailable_on(UNREACHABLE, "redis"):
            return bool(self._acquire(keys=[self.keys.lease(session_id)], args=[owner, ttl_ms]))

    def renew(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        _check_ttl(ttl_ms)
        with unavailable_on(UNREACHABLE, "redis"):
            return bool(self._renew(keys=[self.keys.lease(session_id)], args=[owner, ttl_ms]))

    def release(self, session_id: str, owner: str) -> bool:
        with unavailable_on(UNREACHABLE, "redis"):
            return bool(self._release(keys=[self.keys.lease(session_id)], args=[owner]))

    def holder(self, session_id: str) -> str | None:
        with unavailable_on(UNREACHABLE, "redis"):
            value = self.client.get(self.keys.lease(session_id))
        return str(value) if value is not None else None

    def remaining_ms(self, session_id: str) -> int:
        with unavailable_on(UNREACHABLE, "redis"):
            left = int(self.client.pttl(self.keys.lease(session_id)))
        return max(0, left)


class LocalLeases:
    """Leases of one process (memory and sqlite stores): the same rules, in a dictionary."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._held: dict[str, tuple[str, float]] = {}

    def _current(self, session_id: str) -> str | None:
        held = self._held.get(session_id)
        if held is None:
            return None
        owner, deadline = held
        if time.monotonic() >= deadline:
            del self._held[session_id]
            return None
        return owner

    def acquire(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        _check_ttl(ttl_ms)
        with self._lock:
            if self._current(session_id) not in (None, owner):
                return False
            self._held[session_id] = (owner, time.monotonic() + ttl_ms / 1000)
            return True

    def renew(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        _check_ttl(ttl_ms)
        with self._lock:
            if self._current(session_id) != owner:
                return False
            self._held[session_id] = (owner, time.monotonic() + ttl_ms / 1000)
            return True

    def release(self, session_id: str, owner: str) -> bool:
        with self._lock:
            if self._current(session_id) != owner:
                return False
            del self._held[session_id]
            return True

    def holder(self, session_id: str) -> str | None:
        with self._lock:
            return self._current(session_id)

    def remaining_ms(self, session_id: str) -> int:
        with self._lock:
            held = self._held.get(session_id)
            return 0 if held is None else max(0, int((held[1] - time.monotonic()) * 1000))


def open_leases(store: Store) -> SessionLeases:
    """The leases that go with ``store``: through Redis for a shared store, else local."""
    backing = shared_redis(store)
    if backing is not None:
        return RedisLeases(backing.client, backing.keys)
    return LocalLeases()
