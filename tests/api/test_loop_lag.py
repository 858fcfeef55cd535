"""The event loop's lag is measured: a stall shows in ``credal_event_loop_lag_seconds``."""

from __future__ import annotations

import asyncio
import time

import httpx
from prometheus_client import CollectorRegistry, Histogram

from app.metrics import LOOP_LAG_BUCKETS
from app.runtime import LoopLag
from tests.api.conftest import LiveServer


def _bucket_counts(histogram: Histogram) -> dict[float, float]:
    (metric,) = histogram.collect()
    return {
        float(sample.labels["le"]): sample.value
        for sample in metric.samples
        if sample.name.endswith("_bucket")
    }


def test_a_blocked_loop_is_measured_as_late_by_at_least_the_stall_less_one_period() -> None:
    lag = Histogram("lag", "lag", buckets=LOOP_LAG_BUCKETS, registry=CollectorRegistry())
    monitor = LoopLag(lag, period=0.005)

    async def scene() -> float:
        sampling = asyncio.create_task(monitor.run())
        await asyncio.sleep(0.05)
        started = time.perf_counter()
        time.sleep(0.3)  # a callback that blocks the loop
        stalled = time.perf_counter() - started
        await asyncio.sleep(0.05)
        sampling.cancel()
        return stalled

    stalled = asyncio.run(scene())
    counts = _bucket_counts(lag)
    assert stalled >= 0.3
    # one wake-up was late by at least the stall less a period (0.295 s): above 0.25 s
    assert counts[float("inf")] - counts[0.25] == 1
    assert counts[float("inf")] >= 10  # it kept sampling before and after


def test_the_live_server_exposes_its_loop_lag(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        time.sleep(0.1)
        text = client.get("/metrics").text
    (count,) = [
        float(line.rsplit(" ", 1)[1])
        for line in text.splitlines()
        if line.startswith("credal_event_loop_lag_seconds_count ")
    ]
    assert count >= 5  # sampled every 5 ms since the server started
    assert 'credal_event_loop_lag_seconds_bucket{le="0.05"}' in text


def test_the_smoothed_lag_needs_a_loop_late_sample_after_sample_to_cross_twice_its_ceiling() -> (
    None
):
    """The overload guard's measure (limit 0.2 s, ceiling 0.4 s): an exponential moving average
    with weight 1/4 of samples capped at the ceiling, computed here independently."""
    lag = Histogram("lag2", "lag", buckets=LOOP_LAG_BUCKETS, registry=CollectorRegistry())
    monitor = LoopLag(lag, ceiling=0.4)
    monitor.observe(3.0)  # one long stall (a process left without a CPU): counts as 0.4
    assert abs(monitor.smoothed - 0.1) < 1e-12
    for _ in range(20):  # then a loop on time again
        monitor.observe(0.0)
    expected = 0.1 * 0.75**20
    assert abs(monitor.smoothed - expected) < 1e-12
    crossed = []
    for _ in range(5):  # a loop that stays behind: 0.5 s a sample
        monitor.observe(0.5)
        expected = expected + 0.25 * (0.4 - expected)
        crossed.append(monitor.smoothed > 0.2)
        assert abs(monitor.smoothed - expected) < 1e-12
    assert crossed == [False, False, True, True, True]
