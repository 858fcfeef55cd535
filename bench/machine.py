"""What every benchmark prints first: the machine it ran on."""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable


def describe_machine() -> str:
    """Cores, CPU model, Python and numpy versions, on one line."""
    import numpy as np

    model = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return (
        f"machine: {os.cpu_count()} cores, {model}; "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )


def machine_load() -> str:
    """The machine's load average (1, 5, 15 min) and its cores: a load above the cores means
    runnable processes waited for a CPU (every latency measured then includes that wait)."""
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.1f} {five:.1f} {fifteen:.1f} on {os.cpu_count()} cores"


def median_ms(
    call: Callable[[], object], *, repeat: int = 15, budget_s: float = 2.0, minimum: int = 3
) -> float:
    """Median wall time of ``call`` in ms: at least ``minimum`` runs, then more while the
    budget lasts, at most ``repeat`` (after one warm-up call)."""
    call()  # warm-up: caches, lazy imports
    times: list[float] = []
    started = time.perf_counter()
    while len(times) < repeat and (
        len(times) < minimum or time.perf_counter() - started < budget_s
    ):
        t0 = time.perf_counter()
        call()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)
