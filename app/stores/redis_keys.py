"""Key and channel names of the redis store, its session leases and its result fan-out.

Every name starts with a configurable prefix (``CREDAL_REDIS_PREFIX``, default
``credal-fusion``), so several deployments — or several test runs — can share
one Redis database and each can delete exactly its own keys.

The per-session keys carry the session id as a hash tag (``{sid}``): on Redis
Cluster they all land in one slot, so the Lua scripts that touch a session's
record, log and snapshots together stay legal there.

=============================  ======  ================================================
name                           type    holds
=============================  ======  ================================================
``P:sessions``                 zset    live session ids, score = creation time (µs)
``P:tenant-sessions``          hash    tenant → its live sessions (the tenant quota)
``P:quota:…``                  string  the tenants' input and work counters (limits library)
``P:{sid}:session``            hash    id, config (JSON), token_hash, created_at,
                                       deleted, last_seq, snapshot_seq, tenant
``P:{sid}:log``                stream  one entry per input, id ``<seq>-0``, fields
                                       ``received_at`` and ``input`` (JSON)
``P:{sid}:snapshots``          hash    seq → snapshot JSON (the two latest)
``P:{sid}:lease``              string  the owner holding the session's lease (PX TTL)
``P:{sid}:results`` (channel)  pubsub  result JSON of each input, while subscribed
=============================  ======  ================================================

Deleting a session unlinks its record, log and snapshots and removes it from
the index (its lease expires by itself); compaction trims the log stream.
"""

from __future__ import annotations

from dataclasses import dataclass

DEFAULT_PREFIX = "credal-fusion"
_GLOB_SPECIALS = "*?[]\\"


@dataclass(frozen=True)
class RedisKeys:
    """The names under one prefix."""

    prefix: str = DEFAULT_PREFIX

    def __post_init__(self) -> None:
        if not self.prefix or any(char.isspace() for char in self.prefix):
            raise ValueError(f"redis prefix {self.prefix!r}: must be non-empty, without spaces")

    def sessions(self) -> str:
        """The sorted set of live session ids."""
        return f"{self.prefix}:sessions"

    def tenants(self) -> str:
        """The hash of each tenant's live-session count."""
        return f"{self.prefix}:tenant-sessions"

    def quotas(self) -> str:
        """The start of the tenants' quota counters' keys."""
        return f"{self.prefix}:quota"

    def session(self, session_id: str) -> str:
        """The session's record (a hash)."""
        return f"{self.prefix}:{{{session_id}}}:session"

    def log(self, session_id: str) -> str:
        """The session's input log (a stream)."""
        return f"{self.prefix}:{{{session_id}}}:log"

    def snapshots(self, session_id: str) -> str:
        """The session's latest snapshots (a hash keyed by seq)."""
        return f"{self.prefix}:{{{session_id}}}:snapshots"

    def lease(self, session_id: str) -> str:
        """The session's lease (a string: the owner, with a TTL)."""
        return f"{self.prefix}:{{{session_id}}}:lease"

    def results(self, session_id: str) -> str:
        """The pub/sub channel of the session's results."""
        return f"{self.prefix}:{{{session_id}}}:results"

    def pattern(self) -> str:
        """A ``SCAN MATCH`` pattern of every key under the prefix."""
        escaped = "".join(f"\\{char}" if char in _GLOB_SPECIALS else char for char in self.prefix)
        return f"{escaped}:*"
