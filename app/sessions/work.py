"""Where the sessions' work runs: inline when tiny, in a worker thread otherwise."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import anyio

from app.runtime import without_collection

TINY_WORK = 64
"""Report tracks + live fused tracks up to which a step runs on the event loop.

Such a step costs about 2 ms of engine time: less than what a worker-thread
hop adds under load. Larger steps run in a worker thread."""

T = TypeVar("T")


class StepCount:
    """Engine steps this process has started (the pipeline counts them, before each step)."""

    started = 0


@dataclass(frozen=True)
class Receipt:
    """When an input was received whole (``time.monotonic()``), and how many engine steps this
    process had started then: an input whose wait saw none start waited for the machine (its
    other processes), not for other inputs (``max_queue_ms``)."""

    at: float
    steps: int

    def steps_since(self) -> int:
        """Engine steps started since."""
        return StepCount.started - self.steps


def receipt() -> Receipt:
    """The :class:`Receipt` of an input received now."""
    return Receipt(time.monotonic(), StepCount.started)


async def compute(size: int, function: Callable[[], T]) -> T:
    """Numeric work: inline when tiny, in a worker thread otherwise (without garbage
    collection: :func:`app.runtime.collection_paused`)."""
    if size <= TINY_WORK:
        return function()
    return await anyio.to_thread.run_sync(without_collection(function))
