"""``bench/service.py``'s measuring helpers: the kernel's CPU counters and the service's
step totals (from ``/metrics`` of a real server). No timing is asserted, only counting."""

from __future__ import annotations

import os
import time
from types import ModuleType

import httpx
import pytest

from tests.api.conftest import make_settings, serving
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT
from tests.bench_scripts import load_bench


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return load_bench("service")


def _spin(cpu_seconds: float) -> None:
    started = time.thread_time()
    while time.thread_time() - started < cpu_seconds:
        pass


def test_cpu_counters_of_a_process_grow_with_its_work(bench: ModuleType) -> None:
    """This process's main thread, read as the bench reads a server's: 0.2 s of CPU work
    shows up in the scheduler's on-CPU time (ns) and in user + system time (ticks)."""
    on_cpu, waited = bench.loop_thread_times(os.getpid())
    process = bench.process_cpu_s(os.getpid())
    _spin(0.2)
    on_cpu_after, waited_after = bench.loop_thread_times(os.getpid())
    assert on_cpu_after - on_cpu >= 0.19
    assert waited_after >= waited
    assert bench.process_cpu_s(os.getpid()) - process >= 0.15  # clock ticks: coarser


def test_step_totals_count_the_applied_inputs(bench: ModuleType) -> None:
    with (
        serving(make_settings()) as server,
        httpx.Client(base_url=server.url) as client,
    ):
        created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        before = bench.step_totals(server.url)
        for time_s in (12.5, 13.5):
            answer = client.post(
                f"/v1/sessions/{created['id']}/tracks",
                json=TRACK_REPORT | {"time": time_s},
                headers=headers,
            )
            assert answer.status_code == 200, answer.text
        applied = bench.step_totals(server.url).since(before)
    assert before.count == 0 and applied.count == 2
    assert applied.apply_s > 0.0 and applied.engine_cpu_s > 0.0
    assert applied.mean_ms(applied.apply_s) == pytest.approx(1e3 * applied.apply_s / 2)
