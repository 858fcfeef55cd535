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
"""

from __future__ import annotations

import gc

YOUNG_THRESHOLD = 20_000
"""Allocations (minus deallocations) of container objects before a young collection."""
MIDDLE_THRESHOLD = 20
OLD_THRESHOLD = 50


def tune_garbage_collector() -> None:
    """Freeze what start-up allocated and raise the collection thresholds (call once, before serving)."""
    gc.collect()
    gc.freeze()
    gc.set_threshold(YOUNG_THRESHOLD, MIDDLE_THRESHOLD, OLD_THRESHOLD)
