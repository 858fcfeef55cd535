"""The fan-out between the worker processes of one ``serve`` (app.cluster.peers.PeerFanout):
a result crosses to another worker only while that worker has a subscriber of its session.

Two workers' fan-outs run in this process (named, as the pids of two workers would be),
linked over real Unix sockets in a directory of their own and counting their listeners in
the shared sqlite file, as ``serve --workers 2`` does (``tests/e2e/test_workers.py`` runs the
real processes)."""

from __future__ import annotations

import asyncio
import json
import sqlite3
from collections.abc import Callable
from pathlib import Path

from app.cluster.peers import PeerFanout

WAIT_S = 10.0


async def settle(condition: Callable[[], bool]) -> None:
    """Wait (at most :data:`WAIT_S`) until ``condition()``: the other side's frames arrive."""
    async with asyncio.timeout(WAIT_S):
        while not condition():
            await asyncio.sleep(0.01)


def result(seq: int) -> str:
    return json.dumps({"seq": seq})


def test_results_cross_to_a_worker_only_while_it_listens(tmp_path: Path) -> None:
    async def main() -> None:
        a = PeerFanout(tmp_path, name="101")
        b = PeerFanout(tmp_path, name="102")
        await a.start()
        await b.start()  # links to a
        await settle(lambda: a.peers == 1 and b.peers == 1)
        try:
            assert await a.publish("s1", result(1)) == 0
            assert a.forwarded == 0  # nobody listens on b: nothing sent

            async with b.subscribe("s1") as on_b:
                assert await a.publish("s1", result(2)) == 0  # none of a's own
                assert await a.publish("s2", result(1)) == 0  # nobody listens to s2
                assert a.forwarded == 1
                received = await asyncio.wait_for(anext(on_b), WAIT_S)
                assert json.loads(received) == {"seq": 2}

                async with b.subscribe("s1"), a.subscribe("s1") as on_a:
                    assert await b.publish("s1", result(3)) == 2  # b's two subscriptions
                    assert b.forwarded == 1 and a.forwarded == 1
                    assert json.loads(await asyncio.wait_for(anext(on_a), WAIT_S)) == {"seq": 3}
                # one of b's two subscriptions ended: b still listens
                assert await a.publish("s1", result(4)) == 0
                assert a.forwarded == 2
                assert json.loads(await asyncio.wait_for(anext(on_b), WAIT_S)) == {"seq": 3}
                assert json.loads(await asyncio.wait_for(anext(on_b), WAIT_S)) == {"seq": 4}

            assert await a.publish("s1", result(5)) == 0
            assert a.forwarded == 2  # b's last subscription ended: nothing sent
            assert a.dropped == b.dropped == 0
        finally:
            await b.aclose()
            await a.aclose()

    asyncio.run(main())


def test_a_worker_that_stopped_leaves_no_listener(tmp_path: Path) -> None:
    """A worker's counts go with it (closed), and a new process given its pid starts with none
    (a stale count of a dead worker would only cost sends to a link that is gone)."""

    async def main() -> None:
        a = PeerFanout(tmp_path, name="201")
        b = PeerFanout(tmp_path, name="202")
        await a.start()
        await b.start()
        await settle(lambda: a.peers == 1)
        subscription = b.subscribe("s1")
        await subscription.start()
        assert a.listeners.elsewhere("s1") == ["202"]
        await b.aclose()
        assert a.listeners.elsewhere("s1") == []
        again = PeerFanout(tmp_path, name="202")  # a leftover count of that name is cleared
        again.listeners.add("s9")
        assert a.listeners.elsewhere("s9") == ["202"]
        again.listeners._connection.close()  # killed: no cleanup
        restarted = PeerFanout(tmp_path, name="202")
        assert a.listeners.elsewhere("s9") == []
        await restarted.aclose()
        await a.aclose()

    asyncio.run(main())


def test_a_listener_count_that_cannot_be_read_sends_to_every_linked_worker(
    tmp_path: Path,
) -> None:
    """While the listeners file cannot be read (another worker stalled holding its lock), a
    result goes to every linked worker rather than to none: a subscriber loses nothing."""

    async def main() -> None:
        a = PeerFanout(tmp_path, name="301")
        b = PeerFanout(tmp_path, name="302")
        await a.start()
        await b.start()
        await settle(lambda: a.peers == 1 and b.peers == 1)
        try:
            async with b.subscribe("s1") as on_b:
                a.listeners.elsewhere = unreadable  # type: ignore[method-assign]
                assert await a.publish("s1", result(1)) == 0
                assert a.forwarded == 1
                assert json.loads(await asyncio.wait_for(anext(on_b), WAIT_S)) == {"seq": 1}
        finally:
            await b.aclose()
            await a.aclose()

    asyncio.run(main())


def unreadable(session_id: str) -> list[str]:
    raise sqlite3.OperationalError("database is locked")
