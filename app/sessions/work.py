"""Where the sessions' work runs: inline when tiny, in a worker thread otherwise."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import anyio

from app.runtime import without_collection

TINY_WORK = 64
"""Report tracks + live fused tracks up to which a step runs on the event loop.

Such a step costs about 2 ms of engine time: less than what a worker-thread
hop adds under load. Larger steps run in a worker thread."""

T = TypeVar("T")


async def compute(size: int, function: Callable[[], T]) -> T:
    """Numeric work: inline when tiny, in a worker thread otherwise (without garbage
    collection: :func:`app.runtime.collection_paused`)."""
    if size <= TINY_WORK:
        return function()
    return await anyio.to_thread.run_sync(without_collection(function))
