"""Two registries (two instances) on one Redis: the sequence fence, leases and idle expiry."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime, timedelta
from typing import Any

import pytest
import redis.asyncio

from app.http.errors import SessionLeased
from app.inputs import parse_input
from app.metrics import ServiceMetrics
from app.sessions.registry import SessionRegistry
from app.stores import RedisStore, SessionRecord
from tests.api.conftest import make_settings
from tests.api.redis_support import REDIS_URL, redis_prefix
from tests.api.scenario import reports, session_config
from tests.api.test_registry import feed, registry

SID = "shared-1"


class AlwaysGranted:
    """Leases that grant everyone: two holders at once, as when one paused past its TTL."""

    def acquire(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        return True

    def renew(self, session_id: str, owner: str, ttl_ms: int) -> bool:
        return True

    def release(self, session_id: str, owner: str) -> bool:
        return True

    def holder(self, session_id: str) -> str | None:
        return None


@asynccontextmanager
async def two_instances(**options: Any) -> AsyncIterator[tuple[SessionRegistry, SessionRegistry]]:
    with redis_prefix("registry") as prefix:
        stores = [RedisStore(REDIS_URL, prefix=prefix) for _ in range(2)]
        settings = make_settings(store=REDIS_URL, redis_prefix=prefix, lease_ttl_ms=500)
        pair = [
            SessionRegistry(store, settings, ServiceMetrics.create(), owner=name, **options)
            for store, name in zip(stores, "AB", strict=True)
        ]
        record = SessionRecord(
            id=SID, config=session_config(), token_hash="sha256:0", created_at=datetime.now(UTC)
        )
        stores[0].create_session(record)
        try:
            yield pair[0], pair[1]
        finally:
            for instance in pair:
                await instance.aclose()
            for store in stores:
                store.close()


async def reference(bodies: list[dict[str, Any]]) -> list[Any]:
    alone = registry()
    alone.store.create_session(
        SessionRecord(
            id=SID, config=session_config(), token_hash="sha256:0", created_at=datetime.now(UTC)
        )
    )
    return await feed(alone, SID, bodies)


def test_an_overtaken_instance_rebuilds_from_the_store_and_applies_once_more() -> None:
    bodies = reports(4)

    async def scenario() -> None:
        expected = await reference(bodies)
        async with two_instances(leases=AlwaysGranted()) as (a, b):
            stale = await b.get(SID)  # B loads the session at seq 0 ...
            stale.lease_deadline = time.monotonic() + 60  # ... and believes it holds the lease
            assert await feed(a, SID, bodies[:2]) == expected[:2]  # A moves the log on
            # B applies on its stale engine, meets SequenceConflict, rebuilds, applies again
            assert await feed(b, SID, bodies[2:]) == expected[2:]
            assert stale.seq == 4
            assert [entry.seq for entry in b.store.entries(SID)] == [1, 2, 3, 4]

    asyncio.run(scenario())


def test_a_held_lease_refuses_the_other_instance_until_released() -> None:
    bodies = reports(3)

    async def scenario() -> None:
        expected = await reference(bodies)
        async with two_instances() as (a, b):
            assert await feed(a, SID, bodies[:1]) == expected[:1]
            session = await b.get(SID)
            with pytest.raises(SessionLeased) as refused:
                await b.submit(session, parse_input("tracks", bodies[1]))
            assert refused.value.headers() == {"Retry-After": "1"}
            assert session.seq == 1  # loaded after A's input; the refused one changed nothing
            await a.aclose()  # shutdown releases the lease at once
            assert await feed(b, SID, bodies[1:]) == expected[1:]  # caught up from the store

    asyncio.run(scenario())


def test_idle_expiry_spares_a_session_another_instance_keeps_busy() -> None:
    async def scenario() -> None:
        async with two_instances() as (a, b):
            await b.get(SID)
            await feed(a, SID, reports(1))
            later = datetime.now(UTC) + timedelta(seconds=b.settings.session_idle_seconds + 1)
            assert await b.expire_idle(later) == []
            assert b.store.get_session(SID) is not None

    asyncio.run(scenario())


def test_results_are_published_only_while_someone_subscribes() -> None:
    """A pattern subscription (which Redis does not count as a listener of the channel) sees
    what the instances publish: nothing while no instance forwards the session's results,
    every result while one does — and that subscriber receives each of them, in order."""
    bodies = reports(5)

    async def scenario() -> None:
        async with two_instances() as (a, b):
            watcher = redis.asyncio.Redis.from_url(REDIS_URL, decode_responses=True)
            watching = watcher.pubsub()
            await watching.psubscribe(a.store.keys.results("*"))  # type: ignore[attr-defined]

            async def published() -> list[int]:
                seqs = []
                while (message := await watching.get_message(timeout=0.3)) is not None:
                    if message["type"] == "pmessage":
                        seqs.append(json.loads(message["data"])["result"]["seq"])
                return seqs

            try:
                await feed(a, SID, bodies[:2])
                assert await published() == []  # no one listens: nothing sent to Redis
                session = await b.get(SID)
                subscriber = await b.cluster.subscribe(session)
                await feed(a, SID, bodies[2:4])
                assert await published() == [3, 4]
                received = [await subscriber.next() for _ in range(2)]
                seqs = [json.loads(item.text)["result"]["seq"] for item in received]  # type: ignore[union-attr]
                assert seqs == [3, 4]
                b.cluster.unsubscribe(session, subscriber)
                await asyncio.sleep(0.2)  # the forwarder's connection closes
                await feed(a, SID, bodies[4:])
                assert await published() == []
            finally:
                await watching.aclose()  # type: ignore[no-untyped-call]
                await watcher.aclose()

    asyncio.run(scenario())
