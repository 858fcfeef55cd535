"""Session leases: two instances (two clients) share a session through the real Redis, and
two worker processes through their leases file."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from datetime import UTC, datetime

import pytest

from app.cluster.lease import (
    LocalLeases,
    RedisLeases,
    SessionLeases,
    new_owner_id,
    open_leases,
)
from app.cluster.peers import FileLeases
from app.stores import MemoryStore, RedisStore, SequenceConflict, SessionRecord
from tests.api.redis_support import REDIS_URL, redis_prefix, remaining_keys

SHORT_TTL_MS = 150
EXPIRY_WAIT_S = 5.0

# Two instances' views of the same leases: (instance A, instance B).
LeasePair = tuple[SessionLeases, SessionLeases]


@pytest.fixture(params=["redis", "local", "workers"])
def instances(request: pytest.FixtureRequest) -> Iterator[LeasePair]:
    if request.param == "workers":  # two worker processes' views of one leases file
        path = request.getfixturevalue("tmp_path") / "leases.db"
        yield FileLeases(path), FileLeases(path)
        return
    if request.param == "local":
        shared = LocalLeases()
        yield shared, shared
        return
    with redis_prefix("lease") as prefix, ExitStack() as stores:
        a = RedisStore(REDIS_URL, prefix=prefix)
        stores.callback(a.close)
        b = RedisStore(REDIS_URL, prefix=prefix)
        stores.callback(b.close)
        yield RedisLeases(a.client, a.keys), RedisLeases(b.client, b.keys)


def wait_until(condition: Callable[[], bool]) -> None:
    deadline = time.monotonic() + EXPIRY_WAIT_S
    while not condition():
        assert time.monotonic() < deadline, "the lease did not lapse"
        time.sleep(0.02)


def test_one_holder_at_a_time(instances: LeasePair) -> None:
    a, b = instances
    assert a.holder("s1") is None
    assert a.acquire("s1", "A", 10_000)
    assert not b.acquire("s1", "B", 10_000)
    assert b.holder("s1") == "A"
    assert a.acquire("s1", "A", 10_000)  # re-entrant: the holder renews
    assert b.acquire("s2", "B", 10_000)  # leases are per session


def test_renew_and_release_only_by_the_holder(instances: LeasePair) -> None:
    a, b = instances
    assert a.acquire("s1", "A", 10_000)
    assert not b.renew("s1", "B", 10_000)
    assert not b.release("s1", "B")
    assert a.holder("s1") == "A"
    assert a.renew("s1", "A", 10_000)
    assert a.release("s1", "A")
    assert a.holder("s1") is None and not a.release("s1", "A") and not a.renew("s1", "A", 100)
    assert b.acquire("s1", "B", 10_000)  # released: taken over at once


def test_another_instance_takes_over_when_the_lease_lapses(instances: LeasePair) -> None:
    a, b = instances
    assert a.acquire("s1", "A", SHORT_TTL_MS)
    assert not b.acquire("s1", "B", 10_000)
    wait_until(lambda: b.holder("s1") is None)
    assert b.acquire("s1", "B", 10_000)
    assert not a.renew("s1", "A", 10_000)  # A learns it lost the session
    assert not a.release("s1", "A")  # and cannot take it from B
    assert a.holder("s1") == "B"


def test_renewing_keeps_the_lease(instances: LeasePair) -> None:
    a, b = instances
    assert a.acquire("s1", "A", 10_000)
    assert a.renew("s1", "A", SHORT_TTL_MS)
    wait_until(lambda: a.holder("s1") is None)  # a renewal sets the TTL, it can also shorten it
    assert b.acquire("s1", "B", 10_000)


def test_ttl_must_be_positive(instances: LeasePair) -> None:
    a, _ = instances
    with pytest.raises(ValueError):
        a.acquire("s1", "A", 0)


def test_the_sequence_check_fences_a_stale_holder() -> None:
    """A's lease lapses while it stalls; B takes over and logs; A's late append is refused."""
    with redis_prefix("fence") as prefix:
        store_a = RedisStore(REDIS_URL, prefix=prefix)
        store_b = RedisStore(REDIS_URL, prefix=prefix)
        leases_a, leases_b = open_leases(store_a), open_leases(store_b)
        owner_a, owner_b = new_owner_id(), new_owner_id()
        assert owner_a != owner_b
        store_a.create_session(SessionRecord("s1", {}, "sha256:00", datetime.now(UTC)))
        assert leases_a.acquire("s1", owner_a, SHORT_TTL_MS)
        store_a.append("s1", 1, {"by": "A"}, datetime.now(UTC))
        stale_next = store_a.last_seq("s1") + 1

        wait_until(lambda: leases_b.holder("s1") is None)
        assert leases_b.acquire("s1", owner_b, 10_000)
        assert [entry.seq for entry in store_b.load("s1").entries] == [1]
        store_b.append("s1", 2, {"by": "B"}, datetime.now(UTC))

        with pytest.raises(SequenceConflict):
            store_a.append("s1", stale_next, {"by": "A, late"}, datetime.now(UTC))
        assert not leases_a.renew("s1", owner_a, 10_000)
        assert [entry.input["by"] for entry in store_a.entries("s1")] == ["A", "B"]
        assert leases_b.release("s1", owner_b)
        store_a.close()
        store_b.close()
    assert remaining_keys(prefix) == []


def test_open_leases_follows_the_store() -> None:
    assert isinstance(open_leases(MemoryStore()), LocalLeases)
    with redis_prefix("open") as prefix:
        store = RedisStore(REDIS_URL, prefix=prefix)
        leases = open_leases(store)
        assert isinstance(leases, RedisLeases)
        assert leases.acquire("s1", "A", 10_000)
        assert remaining_keys(prefix) == [f"{prefix}:{{s1}}:lease"]
        store.close()
