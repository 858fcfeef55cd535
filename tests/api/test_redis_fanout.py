"""Result fan-out: subscribers on two instances (two Redis clients) receive every result."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import AsyncExitStack, asynccontextmanager

import pytest

from app.cluster.fanout import (
    LocalFanout,
    RedisFanout,
    ResultFanout,
    Subscription,
    open_fanout,
)
from app.stores import MemoryStore, RedisStore
from tests.api.redis_support import REDIS_URL, redis_prefix

RECEIVE_TIMEOUT_S = 5.0
FanoutPair = tuple[ResultFanout, ResultFanout]


@asynccontextmanager
async def two_instances(kind: str, max_pending: int = 64) -> AsyncIterator[FanoutPair]:
    """Two instances' fan-outs of one deployment (local: one process, one fan-out)."""
    if kind == "local":
        shared = LocalFanout(max_pending)
        yield shared, shared
        await shared.aclose()
        return
    with redis_prefix("fanout") as prefix:
        first = RedisFanout(REDIS_URL, prefix, max_pending)
        second = RedisFanout(REDIS_URL, prefix, max_pending)
        try:
            yield first, second
        finally:
            await first.aclose()
            await second.aclose()


def run(kind: str, scenario: Callable[[FanoutPair], Awaitable[None]], **options: int) -> None:
    async def main() -> None:
        async with two_instances(kind, **options) as pair:
            await asyncio.wait_for(scenario(pair), timeout=RECEIVE_TIMEOUT_S * 2)

    asyncio.run(main())


def result(session_id: str, seq: int) -> str:
    return json.dumps({"session": session_id, "seq": seq})


async def take(subscription: Subscription, count: int) -> list[int]:
    seqs = []
    for _ in range(count):
        text = await asyncio.wait_for(anext(subscription), RECEIVE_TIMEOUT_S)
        seqs.append(json.loads(text)["seq"])
    return seqs


async def settle(condition: Callable[[], bool]) -> None:
    async with asyncio.timeout(RECEIVE_TIMEOUT_S):
        while not condition():
            await asyncio.sleep(0.01)


KINDS = pytest.mark.parametrize("kind", ["redis", "local"])


@KINDS
def test_subscribers_on_both_instances_get_every_result_in_order(kind: str) -> None:
    async def scenario(pair: FanoutPair) -> None:
        one, two = pair
        async with one.subscribe("s1") as near, two.subscribe("s1") as far:
            other = await two.publish("s2", result("s2", 1))
            assert other == 0
            for seq in range(1, 21):
                assert await two.publish("s1", result("s1", seq)) == 2
            assert await take(near, 20) == list(range(1, 21))
            assert await take(far, 20) == list(range(1, 21))
            assert near.dropped == far.dropped == 0

    run(kind, scenario)


@KINDS
def test_a_slow_subscriber_keeps_only_the_latest(kind: str) -> None:
    async def scenario(pair: FanoutPair) -> None:
        one, two = pair
        async with one.subscribe("s1") as slow:
            for seq in range(1, 11):
                await two.publish("s1", result("s1", seq))
            await settle(lambda: slow.pending + slow.dropped == 10)
            assert slow.pending == 3 and slow.dropped == 7
            assert await take(slow, 3) == [8, 9, 10]

    run(kind, scenario, max_pending=3)


@KINDS
def test_leaving_unsubscribes_and_ends_the_iteration(kind: str) -> None:
    async def scenario(pair: FanoutPair) -> None:
        one, two = pair
        subscription = one.subscribe("s1")
        async with subscription:
            assert await two.publish("s1", result("s1", 1)) == 1
            assert await take(subscription, 1) == [1]
        assert await two.publish("s1", result("s1", 2)) == 0
        assert [text async for text in subscription] == []

    run(kind, scenario)


def test_a_subscription_ends_when_its_fanout_closes() -> None:
    async def scenario() -> None:
        with redis_prefix("close") as prefix:
            fanout = RedisFanout(REDIS_URL, prefix)
            publisher = RedisFanout(REDIS_URL, prefix)
            async with AsyncExitStack() as stack:
                stack.push_async_callback(publisher.aclose)
                subscription = await stack.enter_async_context(fanout.subscribe("s1"))
                await publisher.publish("s1", result("s1", 1))
                await settle(lambda: subscription.pending == 1)
                await fanout.aclose()
                assert [json.loads(text)["seq"] async for text in subscription] == [1]

    asyncio.run(scenario())


def test_open_fanout_follows_the_store() -> None:
    assert isinstance(open_fanout(MemoryStore()), LocalFanout)

    async def scenario(prefix: str) -> None:
        store = RedisStore(REDIS_URL, prefix=prefix)
        fanout = open_fanout(store, max_pending=5)
        assert isinstance(fanout, RedisFanout) and fanout.keys == store.keys
        async with fanout.subscribe("s1") as results:
            await fanout.publish("s1", result("s1", 1))
            assert await take(results, 1) == [1]
        await fanout.aclose()
        store.close()

    with redis_prefix("open") as prefix:
        asyncio.run(scenario(prefix))
