"""The real Redis server of the tests: its URL, unique key prefixes, stores that clean up.

The tests talk to ``CREDAL_TEST_REDIS_URL`` (default ``redis://127.0.0.1:6379/0``)
and FAIL when it does not answer: a missing Redis is a broken test machine,
never a reason to skip. Each test works under its own prefix and deletes
every key under it afterwards, so tests (and other users of the server) never
see each other's data.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager

import redis

from app.stores import RedisStore
from app.stores.redis_keys import RedisKeys

REDIS_URL = os.environ.get("CREDAL_TEST_REDIS_URL", "redis://127.0.0.1:6379/0")


def unique_prefix(name: str = "test") -> str:
    """A key prefix no other test run uses."""
    return f"credal-fusion-test:{name}:{uuid.uuid4().hex[:12]}"


def require_redis() -> redis.Redis:
    """A client of the test server; an AssertionError (a failure) when it does not answer."""
    client = redis.Redis.from_url(REDIS_URL, decode_responses=True, socket_connect_timeout=2)
    try:
        client.ping()
    except redis.RedisError as error:
        client.close()
        raise AssertionError(
            f"the tests need a Redis server at {REDIS_URL} (CREDAL_TEST_REDIS_URL): {error}"
        ) from error
    return client


def remaining_keys(prefix: str) -> list[str]:
    """The keys still under ``prefix``."""
    client = require_redis()
    try:
        return list(client.scan_iter(match=RedisKeys(prefix).pattern()))
    finally:
        client.close()


def purge(prefix: str) -> None:
    """Delete every key under ``prefix``."""
    client = require_redis()
    try:
        keys = list(client.scan_iter(match=RedisKeys(prefix).pattern()))
        if keys:
            client.unlink(*keys)
    finally:
        client.close()


@contextmanager
def redis_prefix(name: str = "test") -> Iterator[str]:
    """A unique prefix whose keys are deleted afterwards (the server must answer)."""
    require_redis().close()
    prefix = unique_prefix(name)
    try:
        yield prefix
    finally:
        purge(prefix)


@contextmanager
def redis_store(name: str = "store") -> Iterator[RedisStore]:
    """A :class:`RedisStore` under a unique prefix, closed and purged afterwards."""
    with redis_prefix(name) as prefix:
        store = RedisStore(REDIS_URL, prefix=prefix)
        try:
            yield store
        finally:
            store.close()
