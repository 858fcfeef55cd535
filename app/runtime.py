"""Process-level tuning of a serving process (``credal-fusion serve``), not of the app itself.

The garbage collector: a fusion step allocates thousands of short-lived
containers, so with CPython's default thresholds (700, 10, 10) a young
collection runs several times per input and every few dozen inputs a full
collection walks every object of the process, the ~140 000 of FastAPI,
pydantic, scipy and the engines included. Measured under the service
benchmark (8 sensors, 20-track reports) that was about 1 ms of collector time
per input, a quarter of the request. :func:`tune_garbage_collector` moves
everything alive after start-up into the permanent generation (never
scanned again: imports, routes, schemas) and lets the young generation grow
larger before it is collected. Reference counting still frees almost
everything at once; only cycles wait a little longer.

A heavy request (a 2 000-track list, a session config of 64 fields of view)
builds hundreds of thousands of short-lived containers: its parsed body, its
validated model, its result. Collected while they are alive, they are walked
for nothing (reference counting frees them when the request ends), and the
collector holds the GIL throughout: a middle-generation collection in a
worker thread stalled the event loop 417 ms. :func:`collection_paused`
suspends automatic collection while such work runs in a worker thread; it
resumes when the last of them ends (cycles made meanwhile wait until then).
"""

from __future__ import annotations

import gc
import math
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

import anyio
from prometheus_client import Histogram

T = TypeVar("T")

YOUNG_THRESHOLD = 20_000
"""Allocations (minus deallocations) of container objects before a young collection."""
MIDDLE_THRESHOLD = 2
"""Young collections before a middle-generation one (CPython collects a generation once its
count exceeds this: after 3). A middle collection walks every container that survived the
young collections since the last, all at once and holding the GIL, and most survivors live
on (sessions' state, logs, caches): at 20 it walked 21 young collections' survivors, a 65 ms
stall of the event loop in ``bench/soak.py --crowd`` (issue #28; an anonymous client's
session flood adds live sessions; a young collection took 2-4 ms). At 2 it walks those of 3:
6-13 ms measured there, seven times as often; the same objects walked, in smaller pieces."""
OLD_THRESHOLD = 500
"""Middle-generation collections before a full one (which CPython also defers until the
objects promoted since the last reach a quarter of the old generation): a full collection
after ~1 500 young ones, as rare as at (20, 50) (~1 070)."""


def tune_garbage_collector() -> None:
    """Freeze what start-up allocated and raise the collection thresholds (call once, before serving)."""
    gc.collect()
    gc.freeze()
    gc.set_threshold(YOUNG_THRESHOLD, MIDDLE_THRESHOLD, OLD_THRESHOLD)


class _Pauses:
    """How many heavy jobs are running, and whether collection was on before the first."""

    lock = threading.Lock()
    running = 0
    resume = False


@contextmanager
def collection_paused() -> Iterator[None]:
    """No automatic garbage collection while the block runs (nor any other paused block)."""
    with _Pauses.lock:
        if _Pauses.running == 0:
            _Pauses.resume = gc.isenabled()
            gc.disable()
        _Pauses.running += 1
    try:
        yield
    finally:
        with _Pauses.lock:
            _Pauses.running -= 1
            if _Pauses.running == 0 and _Pauses.resume:
                gc.enable()


def without_collection(function: Callable[[], T]) -> Callable[[], T]:
    """``function`` run under :func:`collection_paused` (for a worker thread)."""

    def paused() -> T:
        with collection_paused():
            return function()

    return paused


LAG_WEIGHT = 0.25
"""Weight of a new sample in :attr:`LoopLag.smoothed`: one stall moves it by a quarter of its
length (of :attr:`LoopLag.ceiling` at most) and is forgotten within a few samples; a loop that
stays behind (every sample long) reaches its lateness in a few samples (90 % after 8)."""


class LoopLag:
    """Measures how late the event loop wakes a timer, every ``period`` seconds, into ``lag``.

    A late wake-up is the time the loop spent on something else with every
    request on hold: a callback that ran long, or a wait for the GIL held by a
    worker thread (a long C call, a garbage collection). A stall of S seconds
    reads between S − ``period`` and S (``bench/bounds.py`` reads the histogram
    per route)."""

    def __init__(self, lag: Histogram, period: float = 0.005, ceiling: float = math.inf) -> None:
        self.lag = lag
        self.period = period
        self.ceiling = ceiling
        """The most a sample counts in :attr:`smoothed` (seconds)."""
        self.smoothed = 0.0
        """How late the loop runs now (seconds): the exponential moving average of the samples
        (weight :data:`LAG_WEIGHT`, each at most :attr:`ceiling`), what the overload guard
        reads (:meth:`~app.sessions.pipeline.InputPipeline.admit`). With the ceiling at twice
        the guard's limit, one stall (a process the kernel left waiting for a CPU, a
        collection) moves it half-way to the limit at most: only a loop late sample after
        sample (3 at the ceiling, more below) crosses it."""

    async def run(self) -> None:
        """Sample until cancelled."""
        while True:
            started = time.perf_counter()
            await anyio.sleep(self.period)
            self.observe(max(0.0, time.perf_counter() - started - self.period))

    def observe(self, late: float) -> None:
        """One sample: the timer fired ``late`` seconds after it was due."""
        self.lag.observe(late)
        self.smoothed += LAG_WEIGHT * (min(late, self.ceiling) - self.smoothed)


class CollectionTimes:
    """Times every garbage collection into ``pauses`` (by generation), from ``gc.callbacks``.

    A collection holds the GIL from start to stop, in whichever thread allocated
    when a threshold was crossed, so its time is a stall of the event loop too.
    Installed by the serving process (:meth:`install`, :meth:`remove`)."""

    def __init__(self, pauses: Histogram) -> None:
        self._series = [pauses.labels(str(generation)) for generation in range(3)]
        self._started = 0.0

    def __call__(self, phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            self._started = time.perf_counter()
        else:
            self._series[info["generation"]].observe(time.perf_counter() - self._started)

    def install(self) -> None:
        gc.callbacks.append(self)

    def remove(self) -> None:
        if self in gc.callbacks:
            gc.callbacks.remove(self)
