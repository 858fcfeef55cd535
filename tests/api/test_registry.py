"""The session registry and the hub, without HTTP: restore, expiry, open sensors, fan-out."""

from __future__ import annotations

import asyncio
import contextlib
import json
import threading
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import pytest
from prometheus_client import CollectorRegistry, Histogram

from app.errors import Overloaded
from app.inputs import parse_input
from app.metrics import ServiceMetrics
from app.outputs import JSON
from app.runtime import LoopLag
from app.sessions.hub import SESSION_ENDED, Hub, Published
from app.sessions.live import new_session as live_session
from app.sessions.registry import SessionRegistry
from app.stores import MemoryStore, SessionRecord
from app.stores.base import StoreUsage
from app.stores.redis import RedisStore
from app.stores.sqlite import SqliteStore
from tests.api.conftest import make_settings
from tests.api.scenario import reports, session_config

STEPS = 9


def registry(**settings: Any) -> SessionRegistry:
    return SessionRegistry(MemoryStore(), make_settings(**settings), ServiceMetrics.create())


def new_session(target: SessionRegistry, config: dict[str, Any], sid: str = "s1") -> SessionRecord:
    record = SessionRecord(
        id=sid, config=config, token_hash="sha256:0", created_at=datetime.now(UTC)
    )
    target.store.create_session(record)
    target.add(live_session(record))
    return record


async def feed(target: SessionRegistry, sid: str, bodies: list[dict[str, Any]]) -> list[Any]:
    session = await target.get(sid)
    return [
        json.loads(await target.submit(session, parse_input("tracks", body))) for body in bodies
    ]


def test_rebuilt_session_equals_the_live_one() -> None:
    async def scenario() -> None:
        live = registry(snapshot_every=4)
        new_session(live, session_config())
        await feed(live, "s1", reports(STEPS))
        session = await live.get("s1")
        picture = await live.picture(session, None)
        load = live.store.load("s1")
        assert load.snapshot is not None and load.snapshot.seq == 8 and len(load.entries) == 1
        live.discard("s1")  # forget it in memory: the next use rebuilds it from the store
        rebuilt = await live.get("s1")
        assert rebuilt is not session and rebuilt.seq == STEPS
        assert await live.picture(rebuilt, None) == picture
        assert rebuilt.sensor_inputs == session.sensor_inputs
        assert rebuilt.last_input_at == session.last_input_at

    asyncio.run(scenario())


def test_session_without_sensors_accepts_any_sensor_up_to_the_limit() -> None:
    async def scenario() -> None:
        target = registry(max_sensors=2, snapshot_every=2)
        config = session_config()
        config["sensors"] = []
        new_session(target, config)
        results = await feed(target, "s1", reports(4))
        assert {track["status"] for track in results[-1]["tracks"]} == {"confirmed"}
        session = await target.get("s1")
        assert session.sensor_ids() == ["radar-1", "radar-2"]
        third = reports(5, sensors=["radar-1", "radar-2", "radar-3"])[2]
        try:
            await feed(target, "s1", [third])
        except Exception as error:
            assert getattr(error, "extensions", {}).get("limit") == "max_sensors"
        else:
            raise AssertionError("a third sensor should exceed max_sensors")
        assert session.seq == 4
        target.discard("s1")
        rebuilt = await target.get("s1")
        assert rebuilt.sensor_ids() == ["radar-1", "radar-2"]
        assert await target.picture(rebuilt, None) == await target.picture(session, None)

    asyncio.run(scenario())


def test_idle_sessions_expire() -> None:
    async def scenario() -> None:
        target = registry(session_idle_seconds=60)
        new_session(target, session_config(), "idle")
        new_session(target, session_config(), "busy")
        await feed(target, "busy", reports(1))
        later = datetime.now(UTC) + timedelta(seconds=61)
        busy = await target.get("busy")
        busy.last_input_at = later - timedelta(seconds=5)
        assert await target.expire_idle(later) == ["idle"]
        assert target.store.get_session("idle") is None
        assert target.store.get_session("busy") is not None
        busy.last_input_at = None  # idle since its creation: it expires too, and frees it all
        assert await target.expire_idle(later) == ["busy"]
        assert len(target) == 0
        assert target.store.usage() == StoreUsage(sessions=0, inputs=0, snapshots=0, bytes=0)

    asyncio.run(scenario())


def test_slow_subscriber_gets_the_latest_results_never_a_backlog() -> None:
    async def scenario() -> None:
        hub = Hub()
        slow = hub.subscribe(capacity=4)
        for seq in range(1, 101):
            hub.publish(Published({JSON: f"result {seq}"}))
        assert slow.queue.qsize() == 4 and slow.dropped == 96
        assert [await slow.next() for _ in range(4)] == [
            Published({JSON: f"result {n}"}) for n in range(97, 101)
        ]
        hub.publish(Published({JSON: "result 101"}))
        assert await slow.next() == Published({JSON: "result 101"})
        hub.close()
        assert await slow.next() == SESSION_ENDED and len(hub) == 0

    asyncio.run(scenario())


def test_subscriber_receives_published_results() -> None:
    async def scenario() -> None:
        target = registry()
        new_session(target, session_config())
        session = await target.get("s1")
        subscriber = session.hub.subscribe()
        results = await feed(target, "s1", reports(3))
        received = []
        for _ in range(3):
            published = await subscriber.next()
            assert isinstance(published, Published) and set(published.texts) == {JSON}
            received.append(json.loads(published.text)["result"])
        assert received == results

    asyncio.run(scenario())


class ThreadRecordingStore(MemoryStore):
    """A memory store that says whether it blocks and records the thread of each append."""

    def __init__(self, blocking: bool) -> None:
        super().__init__()
        self.blocking = blocking
        self.append_threads: list[int] = []

    def append(self, *args: Any, **kwargs: Any) -> bool:
        self.append_threads.append(threading.get_ident())
        return super().append(*args, **kwargs)


@pytest.mark.parametrize("blocking", [False, True])
def test_store_calls_leave_the_event_loop_only_for_a_store_that_blocks(blocking: bool) -> None:
    """The registry asks the store's ``blocking`` capability, not its class."""
    store = ThreadRecordingStore(blocking)
    target = SessionRegistry(store, make_settings(), ServiceMetrics.create())
    new_session(target, session_config())
    loop_thread = threading.get_ident()  # asyncio.run runs the loop in this thread
    asyncio.run(feed(target, "s1", reports(3)))
    assert len(store.append_threads) == 3
    on_loop = [thread == loop_thread for thread in store.append_threads]
    assert on_loop == [not blocking] * 3


def test_only_the_memory_store_is_called_on_the_event_loop(tmp_path: Path) -> None:
    assert MemoryStore.blocking is False
    assert SqliteStore(tmp_path / "s.db").blocking is True
    assert RedisStore.blocking is True


def test_sensors_joining_an_open_session_equal_the_same_sensors_configured() -> None:
    """A sensor joins an open session in place (no export and restore of the engine): step
    for step the results equal those of a session that names the same sensors in the order
    they joined (default reliability and P_D); an input the engine refuses joins no sensor."""

    async def scenario() -> None:
        target = registry()
        sensors = ["radar-1", "radar-2", "radar-3"]
        named = session_config(sensors)
        for sensor in named["sensors"]:
            sensor.pop("reliability"), sensor.pop("p_detect")  # the defaults, as a joined one
        new_session(target, named, "named")
        new_session(target, session_config(sensors) | {"sensors": []}, "open")
        bodies = reports(9, sensors)
        refused = bodies[1] | {"tracks": [dict(bodies[1]["tracks"][0], state=[1e300] * 4)]}
        session = await target.get("open")
        with contextlib.suppress(Exception):
            await feed(target, "open", [bodies[0], refused])
        assert session.sensor_ids() == ["radar-1"] and session.seq == 1
        expected = await feed(target, "named", bodies)
        assert await feed(target, "open", bodies[1:]) == expected[1:]
        assert session.sensor_ids() == sensors
        target.discard("open")
        rebuilt = await target.get("open")
        assert await target.picture(rebuilt, None) == await target.picture(session, None)

    asyncio.run(scenario())


def test_an_overloaded_instance_refuses_inputs_while_its_loop_runs_late() -> None:
    """The guard reads the loop's smoothed lateness (set here by hand): above the limit (200 ms)
    an input is refused (503, ``Retry-After``) and changes nothing; under it, applied. An input
    that finds no other in flight is applied however late the loop runs, and so is one of a
    tenant holding less than its even share of the inputs in flight (its own × the tenants
    with inputs in flight, itself included, < all of them: hand-worked per row)."""
    lag = LoopLag(Histogram("lag", "lag", registry=CollectorRegistry()))
    target = SessionRegistry(
        MemoryStore(), make_settings(overload_delay_ms=200), ServiceMetrics.create(), loop_lag=lag
    )
    record = new_session(target, session_config())
    mine = record.tenant
    bodies = iter(reports(9))
    rows = [  # (lateness s, in flight per tenant)
        (0.0, {mine: 1}),
        (0.25, {mine: 1}),
        (0.201, {mine: 1}),
        (0.19, {mine: 1}),
        (0.5, {}),
        (0.5, {mine: 1}),
        (0.5, {"other": 3}),  # 0 × 2 < 3: below its share
        (0.5, {mine: 1, "other": 1}),  # 1 × 2 ≥ 2: its share
        (0.5, {mine: 1, "other": 2, "third": 3}),  # 1 × 3 < 6
    ]

    async def scenario() -> list[str]:
        session = await target.get("s1")
        outcomes = []
        for late_s, in_flight in rows:
            lag.smoothed = late_s
            target.pipeline.tenant_in_flight = dict(in_flight)
            target.pipeline.in_flight = sum(in_flight.values())
            seq = session.seq
            try:
                await target.submit(session, parse_input("tracks", next(bodies)))
                outcomes.append("applied")
            except Overloaded as refused:
                assert refused.headers() == {"Retry-After": "1"}
                assert session.seq == seq and target.store.last_seq("s1") == seq
                outcomes.append("refused")
        return outcomes

    assert asyncio.run(scenario()) == [
        "applied",
        "refused",
        "refused",
        "applied",
        "applied",
        "refused",
        "applied",
        "refused",
        "applied",
    ]
