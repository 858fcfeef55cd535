"""Coordination of service instances that share one store: session leases and result fan-out.

Chosen by the store's capabilities, not its class: a store whose ``shared``
flag is set must also give its Redis connection (:class:`RedisBacked`); the
instances then take per-session leases (:mod:`app.cluster.lease`) and publish
results through Redis pub/sub (:mod:`app.cluster.fanout`). Any other store
gets the in-process equivalents, with the same rules.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import redis

from app.stores.base import Store
from app.stores.redis_keys import RedisKeys


@runtime_checkable
class RedisBacked(Protocol):
    """A store kept in a Redis server that several instances share."""

    url: str
    keys: RedisKeys
    client: redis.Redis


def shared_redis(store: Store) -> RedisBacked | None:
    """The Redis connection of a shared store; ``None`` for a store of one process."""
    if not store.shared:
        return None
    if not isinstance(store, RedisBacked):
        raise TypeError(f"the {store.kind} store is shared but gives no Redis connection")
    return store
