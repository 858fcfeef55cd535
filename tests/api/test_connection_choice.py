"""The connection closed to make room at ``max_connections`` (:class:`app.http.transport.Connections`):
its indexed choice against a scan of every address, over a random life of connections."""

from __future__ import annotations

import asyncio
import random
from typing import cast

from app.http.transport import Connections
from app.settings import TransportLimits


class FakeTransport:
    def __init__(self) -> None:
        self.closed = False

    def close(self) -> None:
        self.closed = True


def scanned_heaviest_count(guard: Connections) -> int | None:
    """The most connections held by an address with one waiting: a scan of every address."""
    counts = [guard.per_client[address] for address, waiting in guard.waiting.items() if waiting]
    return max(counts, default=None)


def test_the_connection_closed_is_of_the_heaviest_waiting_address() -> None:
    rng = random.Random(7)
    guard = Connections(TransportLimits(max_connections=60, max_connections_per_client=12))
    open_: dict[int, tuple[str, FakeTransport]] = {}
    states: dict[int, str] = {}  # "waiting" or "busy"
    addresses = [f"10.0.0.{index}" for index in range(9)]
    evictions = 0
    for _ in range(20_000):
        # connection_lost of a closed connection (the protocol calls release)
        for number, (address, transport) in list(open_.items()):
            if transport.closed:
                guard.release(address, cast(asyncio.BaseTransport, transport))
                del open_[number], states[number]
        action = rng.random()
        if action < 0.45 or not open_:
            address = rng.choice(addresses)
            at_limit = guard.total >= 60
            expected = scanned_heaviest_count(guard)
            counts_before = dict(guard.per_client)
            closed_before = {number for number, (_, t) in open_.items() if t.closed}
            transport = FakeTransport()
            refusal = guard.admit(cast(asyncio.BaseTransport, transport), address)
            closed_now = [
                (victim_address, number)
                for number, (victim_address, t) in open_.items()
                if t.closed and number not in closed_before
            ]
            if at_limit and expected is None:
                assert refusal is not None and not closed_now  # nobody waits: 503
            elif at_limit and counts_before.get(address, 0) < 12:
                assert refusal is None and len(closed_now) == 1
                victim_address, victim = closed_now[0]
                assert counts_before[victim_address] == expected  # the heaviest's
                assert states[victim] == "waiting"
                evictions += 1
            else:
                assert not closed_now
            if refusal is None:
                number = id(transport)
                open_[number] = (address, transport)
                guard.wait_for_head(address, cast(asyncio.BaseTransport, transport))
                states[number] = "waiting"
        else:
            number = rng.choice(list(open_))
            address, transport = open_[number]
            if transport.closed:
                continue
            if action < 0.65:
                guard.busy(address, cast(asyncio.BaseTransport, transport))
                states[number] = "busy"
            elif action < 0.85:
                guard.wait_for_head(address, cast(asyncio.BaseTransport, transport))
                states[number] = "waiting"
            else:
                transport.close()
        # the index agrees with a scan at every step
        chosen = guard._heaviest()
        expected_count = scanned_heaviest_count(guard)
        if expected_count is None:
            assert chosen is None
        else:
            assert chosen is not None and guard.per_client[chosen] == expected_count
        assert guard.total == len(open_)
    assert evictions > 100
