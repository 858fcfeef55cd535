"""The WebSocket per-connection message rate (``ws_messages_per_second``) against the ``limits``
library's moving window, the limiter it replaces (which started a timer thread per hit)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from limits import RateLimitItemPerSecond
from limits.storage import MemoryStorage
from limits.strategies import MovingWindowRateLimiter

from app.http.rate_limit import MessageRate


class Clock:
    """A clock the test moves: both ``time.time`` (the library's) and ``time.monotonic``."""

    def __init__(self) -> None:
        self.now = 1_000.0

    def __call__(self) -> float:
        return self.now


@pytest.mark.parametrize("per_second", [1, 3, 10])
def test_same_decisions_as_the_librarys_moving_window(
    monkeypatch: pytest.MonkeyPatch, per_second: int
) -> None:
    clock = Clock()
    monkeypatch.setattr(time, "time", clock)
    monkeypatch.setattr(time, "monotonic", clock)
    storage = MemoryStorage()
    reference = MovingWindowRateLimiter(storage)
    item = RateLimitItemPerSecond(per_second)
    rate = MessageRate(per_second)
    rng = np.random.default_rng(per_second)
    # bursts and pauses: gaps from 1 ms to 1.5 s, exact one-second edges among them
    gaps = rng.choice(
        [0.001, 0.05, 0.2, 0.5, 1.0, 1.5], size=400, p=[0.4, 0.2, 0.15, 0.1, 0.1, 0.05]
    )
    decisions, expected = [], []
    for gap in gaps:
        clock.now += float(gap)
        decisions.append(rate.admit())
        expected.append(reference.hit(item, "connection"))
    storage.timer.cancel()
    assert decisions == expected
    assert not all(decisions) and any(decisions)  # both answers were met


def test_admitting_starts_no_thread() -> None:
    rate = MessageRate(5)
    before = threading.active_count()
    assert [rate.admit() for _ in range(7)] == [True] * 5 + [False] * 2
    assert threading.active_count() == before
