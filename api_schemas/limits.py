"""The configurable bounds on one body, checked before any item of a list is validated.

The schema's ``max_length`` values are hard ceilings (documented in
``openapi.json``); the service's configured limits (``CREDAL_MAX_*``, see
``app/settings.py``) are at most those and are checked by :func:`bounded`
on the raw list, before its items are validated: a body of 200 000 sensors
costs one length check, not 200 000 validations. The service puts its limits
in :data:`ACTIVE_LIMITS` for each request; outside a request the defaults apply.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

from pydantic import BeforeValidator
from pydantic_core import PydanticCustomError

from api_schemas.base import MAX_CLASSES

MAX_ITEMS = 100_000
"""Hard ceiling on tracks or detections per input (and per side of ``/v1/associate``)."""
MAX_SENSORS = 1024
"""Hard ceiling on sensors per session config."""
MAX_FOCAL_SETS = 1024
"""Hard ceiling on focal sets per class mass."""
LIMIT_EXCEEDED = "limit_exceeded"
"""The error type of a breached configurable limit (its ``ctx`` names the limit)."""


@dataclass(frozen=True)
class WireLimits:
    """The configurable bounds on one body (defaults are the service's defaults)."""

    max_tracks_per_input: int = 2000
    max_sensors: int = 64
    max_classes: int = MAX_CLASSES
    max_focal_sets: int = 64


DEFAULT_LIMITS = WireLimits()
ACTIVE_LIMITS: ContextVar[WireLimits] = ContextVar(
    "wire_limits",
    default=DEFAULT_LIMITS,
)
"""The limits of the request being validated (set by the service per request)."""


CEILINGS = WireLimits(
    max_tracks_per_input=MAX_ITEMS,
    max_sensors=MAX_SENSORS,
    max_classes=MAX_CLASSES,
    max_focal_sets=MAX_FOCAL_SETS,
)
"""The hard ceilings: what stored data (logged inputs, session configs) is read back under,
so that limits lowered after a restart never refuse what was accepted before."""


@contextmanager
def limits_of(limits: WireLimits) -> Iterator[None]:
    """Validate under ``limits`` within the block."""
    token = ACTIVE_LIMITS.set(limits)
    try:
        yield
    finally:
        ACTIVE_LIMITS.reset(token)


def bounded(limit: str, what: str) -> BeforeValidator:
    """A check that a list (or object) has at most the configured ``limit`` entries."""

    def check(value: object) -> object:
        if isinstance(value, list | dict):
            maximum = getattr(ACTIVE_LIMITS.get(), limit)
            if len(value) > maximum:
                raise PydanticCustomError(
                    LIMIT_EXCEEDED,
                    "{what}: at most {maximum} (limit {limit}), got {actual}",
                    {"what": what, "limit": limit, "maximum": maximum, "actual": len(value)},
                )
        return value

    checker: Callable[[object], object] = check
    return BeforeValidator(checker)
