"""``bench/capacity.py``: its sensor's messages are what the service takes, its verdicts count
what they say, and ``--quick`` runs end to end (a real echo, a real memory server, and a real
``serve`` of 1 and of 2 workers on sqlite). No timing is asserted."""

from __future__ import annotations

import subprocess
import sys
from types import ModuleType

import numpy as np
import pytest

from api_schemas.config import SessionConfig
from app.inputs import client_messages
from tests.bench_scripts import BENCH, load_bench


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return load_bench("capacity")


def test_the_sensor_sends_valid_scans_of_its_targets_and_clutter(bench: ModuleType) -> None:
    SessionConfig.model_validate(bench.sensor_config())
    scans = bench.Scans(seed=3)
    sizes = []
    for index in range(200):
        message = client_messages().validate_json(scans.next())
        assert (message.sensor, message.time) == ("radar", bench.SCAN_PERIOD_S * (index + 1))
        sizes.append(len(message.detections))
    # 20 targets at P_D 0.9 plus Poisson(2) clutter: 20 a scan on average (an independent sum)
    expected = bench.TARGETS * bench.P_DETECT + bench.CLUTTER_PER_SCAN
    assert abs(np.mean(sizes) - expected) < 0.5


def test_a_cell_is_within_capacity_only_if_it_keeps_up_under_the_p99_limit(
    bench: ModuleType,
) -> None:
    def cell(answered_per_s: float, p99_ms: float, errors: int = 0) -> object:
        return bench.Cell(10, 10.0, 800, answered_per_s, 5.0, p99_ms, 1.0, 100.0, errors, 8.0)

    assert cell(100.0, 20.0).within
    assert not cell(90.0, 20.0).within  # 720 of 800 sent in the window: fell behind
    assert not cell(100.0, 60.0).within
    assert not cell(100.0, 20.0, errors=1).within
    assert bench.capacity([cell(100.0, 20.0), cell(300.0, 70.0), cell(200.0, 30.0)]) == 200.0


def test_quick_run_prints_every_configuration() -> None:
    done = subprocess.run(
        [sys.executable, str(BENCH / "capacity.py"), "--quick", "--stores", "memory", "sqlite"],
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    for server in ("bare echo", "memory × 1"):
        assert any(line.startswith(server) and "4 × 2" in line for line in lines), done.stdout
    assert any("memory × 1" in line and "per core" in line for line in lines), done.stdout
    assert any(line.startswith("sqlite at saturation") for line in lines), done.stdout
    assert lines[-1].startswith("machine load"), done.stdout
