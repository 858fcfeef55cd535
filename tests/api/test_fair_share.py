"""Fair shares between tenants, and inputs refused rather than answered late (issues 28, 29):
the engine's turns round-robin between tenants, the per-tenant in-flight cap, the queue-time
limit. In process, with the waits and counts set by hand; the live-server tests are
``tests/e2e/test_fair_share.py``."""

from __future__ import annotations

import asyncio
import time
from datetime import UTC, datetime

import pytest

from app.errors import LimitExceeded, TooLate
from app.http.errors import problem_for
from app.inputs import parse_input
from app.metrics import ServiceMetrics
from app.sessions.live import new_session
from app.sessions.registry import SessionRegistry
from app.sessions.turns import Turns
from app.sessions.work import Receipt, StepCount
from app.stores import MemoryStore, SessionRecord
from tests.api.conftest import make_settings
from tests.api.scenario import reports, session_config


def test_turns_go_round_robin_between_tenants_not_first_come_first_served() -> None:
    """One slot, held; then six inputs of a flooding tenant, one of a polite tenant and one
    of a third queue in this order: F1 F2 F3 P1 F4 T1 F5 F6. Round-robin by hand: each tenant
    in the order it first queued (F, P, T), one input each per round: F1 P1 T1 F2 F3… — F takes
    one turn, P and T one each, then F again; once P and T are served F has the rest."""
    order: list[str] = []

    async def scene() -> None:
        turns = Turns(slots=1)
        holder = turns.turn("holder", alone=True)
        await holder.__aenter__()

        async def step(tenant: str, name: str) -> None:
            async with turns.turn(tenant):
                order.append(name)
                await asyncio.sleep(0)  # a step that awaits (a worker thread)

        queued = [
            ("F", "F1"),
            ("F", "F2"),
            ("F", "F3"),
            ("P", "P1"),
            ("F", "F4"),
            ("T", "T1"),
            ("F", "F5"),
            ("F", "F6"),
        ]
        tasks = []
        for tenant, name in queued:
            tasks.append(asyncio.create_task(step(tenant, name)))
            await asyncio.sleep(0)  # each reaches its queue before the next is created
        assert turns.waiting() == len(queued)
        await holder.__aexit__(None, None, None)
        await asyncio.gather(*tasks)
        assert turns.free == 1 and turns.waiting() == 0

    asyncio.run(scene())
    assert order == ["F1", "P1", "T1", "F2", "F3", "F4", "F5", "F6"]


def test_keyed_tenants_take_the_turns_before_a_crowd_of_addresses() -> None:
    """One slot, held; a crowd of three addresses queues first (A1 B1 C1 A2), then two keyed
    tenants (k1 twice, k2 once) and one more address (D1). By hand: the keyed tenants in turn
    while one waits (k1, k2, k1), then the addresses in the order they first queued, one input
    each per round (A1 B1 C1 D1 A2)."""
    order: list[str] = []

    async def scene() -> None:
        turns = Turns(slots=1)
        holder = turns.turn("address:127.0.0.1", alone=True)
        await holder.__aenter__()

        async def step(tenant: str, name: str) -> None:
            async with turns.turn(tenant):
                order.append(name)
                await asyncio.sleep(0)

        queued = [
            ("address:10.0.0.1", "A1"),
            ("address:10.0.0.2", "B1"),
            ("address:10.0.0.3", "C1"),
            ("address:10.0.0.1", "A2"),
            ("key:one", "k1a"),
            ("key:one", "k1b"),
            ("key:two", "k2"),
            ("address:10.0.0.4", "D1"),
        ]
        tasks = []
        for tenant, name in queued:
            tasks.append(asyncio.create_task(step(tenant, name)))
            await asyncio.sleep(0)
        assert turns.waiting() == len(queued)
        await holder.__aexit__(None, None, None)
        await asyncio.gather(*tasks)
        assert turns.free == 1 and turns.waiting() == 0

    asyncio.run(scene())
    assert order == ["k1a", "k2", "k1b", "A1", "B1", "C1", "D1", "A2"]


def test_a_cancelled_keyed_waiter_leaves_its_queue() -> None:
    """A keyed input cancelled while it waits leaves the keyed queue; the address's input then
    takes the slot, and no slot is lost or made."""
    order: list[str] = []

    async def scene() -> tuple[int, int]:
        turns = Turns(slots=1)
        holder = turns.turn("address:10.0.0.9", alone=True)
        await holder.__aenter__()

        async def step(tenant: str, name: str) -> None:
            async with turns.turn(tenant):
                order.append(name)

        anonymous = asyncio.create_task(step("address:10.0.0.1", "A1"))
        await asyncio.sleep(0)
        keyed = asyncio.create_task(step("key:one", "k1"))
        await asyncio.sleep(0)
        keyed.cancel()
        with pytest.raises(asyncio.CancelledError):
            await keyed
        await holder.__aexit__(None, None, None)
        await anonymous
        return turns.free, turns.waiting()

    assert asyncio.run(scene()) == (1, 0)
    assert order == ["A1"]


def test_a_cancelled_waiter_gives_its_turn_on() -> None:
    """An input cancelled while it waits (its client went away) leaves the queue; the slot goes
    to the next waiter, and no slot is lost or made."""

    async def scene() -> list[str]:
        turns = Turns(slots=1)
        served: list[str] = []
        holder = turns.turn("a", alone=True)
        await holder.__aenter__()

        async def step(name: str) -> None:
            async with turns.turn("b"):
                served.append(name)

        gone = asyncio.create_task(step("gone"))
        stays = asyncio.create_task(step("stays"))
        await asyncio.sleep(0)
        gone.cancel()
        await holder.__aexit__(None, None, None)
        await stays
        with pytest.raises(asyncio.CancelledError):
            await gone
        assert turns.free == 1 and turns.waiting() == 0
        return served

    assert asyncio.run(scene()) == ["stays"]


def test_a_waiter_cancelled_as_its_turn_is_handed_over_gives_the_slot_back() -> None:
    """The slot is handed to a waiter (its future given its result) and, before its task
    resumes, the task is cancelled (its client went away at that moment): the task ends
    cancelled without its step, the slot it was handed comes back, and the next waiter takes
    it. The order is fixed by the event loop's FIFO of ready callbacks, not by time: releasing
    the holder schedules the hand-out (``call_soon``), the cancel is scheduled right after
    it, and the hand-out's wake-up of the waiter comes after both."""

    async def scene() -> tuple[list[str], list[int], int, int]:
        loop = asyncio.get_running_loop()
        turns = Turns(slots=1)
        served: list[str] = []
        free_seen: list[int] = []
        holder = turns.turn("a", alone=True)
        await holder.__aenter__()

        async def step(tenant: str, name: str) -> None:
            async with turns.turn(tenant):
                served.append(name)

        handed = asyncio.create_task(step("b", "handed"))
        await asyncio.sleep(0)  # queued first: the hand-out's first choice
        later = asyncio.create_task(step("c", "later"))
        await asyncio.sleep(0)
        assert turns.waiting() == 2 and turns.free == 0
        (waiter,) = turns.queues["b"]

        def cancel_after_hand_out() -> None:
            # the hand-out ran: the waiter holds the slot, its task has not resumed yet
            assert waiter.done() and not waiter.cancelled()
            free_seen.append(turns.free)
            handed.cancel()

        await holder.__aexit__(None, None, None)  # schedules the hand-out
        loop.call_soon(cancel_after_hand_out)
        with pytest.raises(asyncio.CancelledError):
            await handed
        for _ in range(5):  # loop turns, not time: the next hand-out, then the step
            await asyncio.sleep(0)
        if not later.done():  # a lost slot: nobody would ever serve it
            later.cancel()
        return served, free_seen, turns.free, turns.waiting()

    served, free_seen, free, waiting = asyncio.run(scene())
    assert free_seen == [0]  # the cancelled task had been handed the only slot
    assert (served, free, waiting) == (["later"], 1, 0)


def registry_of(**settings: object) -> tuple[SessionRegistry, SessionRecord]:
    target = SessionRegistry(MemoryStore(), make_settings(**settings), ServiceMetrics.create())
    record = SessionRecord(
        id="s1",
        config=session_config(),
        token_hash="sha256:0",
        created_at=datetime.now(UTC),
        tenant="polite",
    )
    target.store.create_session(record)
    target.add(new_session(record))
    return target, record


def test_a_tenant_beyond_its_inputs_in_flight_is_refused_429_and_nothing_changes() -> None:
    """``tenant_max_in_flight`` = 3: with 3 of its own in flight the next is refused (429,
    ``Retry-After``, the limit named); with 2 of its own, or 50 of another tenant's, applied."""
    target, record = registry_of(tenant_max_in_flight=3)
    bodies = iter(reports(4))

    async def scene() -> list[object]:
        session = await target.get("s1")
        outcomes: list[object] = []
        for in_flight in ({"polite": 3}, {"polite": 2}, {"flood": 50}, {"polite": 4}):
            target.pipeline.tenant_in_flight = dict(in_flight)
            target.pipeline.in_flight = sum(in_flight.values())
            seq = session.seq
            try:
                await target.submit(session, parse_input("tracks", next(bodies)))
                outcomes.append(session.seq)
            except LimitExceeded as refused:
                assert session.seq == seq and target.store.last_seq("s1") == seq
                problem = problem_for(refused).model_dump(exclude_none=True)
                assert (problem["status"], problem["limit"], problem["maximum"]) == (
                    429,
                    "tenant_max_in_flight",
                    3,
                )
                assert refused.headers() == {"Retry-After": "1"}
                outcomes.append("refused")
        return outcomes

    assert asyncio.run(scene()) == ["refused", 1, 2, "refused"]
    assert record.tenant == "polite"


def test_an_input_that_waited_beyond_max_queue_ms_is_refused_before_its_step() -> None:
    """``max_queue_ms`` = 500: an input received 2 s ago, other inputs' steps having started
    since, is refused (503 ``overloaded``, limit ``max_queue_ms``, ``queued_ms`` ≥ 2 000) and
    changes nothing; one received now is applied; one received 2 s ago with no step started
    since (its wait was the machine's) is applied."""
    target, _ = registry_of(max_queue_ms=500)
    bodies = iter(reports(3))

    async def scene() -> list[object]:
        session = await target.get("s1")
        outcomes: list[object] = []
        for age_s, steps_since in ((2.0, 1), (0.0, 3), (2.0, 0)):
            seq, engine_seq = session.seq, session.engine.seq if session.engine else None
            received = Receipt(time.monotonic() - age_s, StepCount.started - steps_since)
            try:
                await target.submit(
                    session, parse_input("tracks", next(bodies)), received_at=received
                )
                outcomes.append(session.seq)
            except TooLate as refused:
                assert session.seq == seq and target.store.last_seq("s1") == seq
                assert (session.engine.seq if session.engine else None) == engine_seq
                problem = problem_for(refused).model_dump(exclude_none=True)
                assert (problem["status"], problem["type"], problem["limit"]) == (
                    503,
                    "urn:credal-fusion:problem:overloaded",
                    "max_queue_ms",
                )
                assert problem["queued_ms"] >= 2000
                assert refused.headers() == {"Retry-After": "1"}
                outcomes.append("refused")
        return outcomes

    assert asyncio.run(scene()) == ["refused", 1, 2]
