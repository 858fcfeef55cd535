"""Times on the wire: seconds of the session's clock, or RFC 3339 timestamps.

A ``time`` is either a number — seconds on the session's clock, whose epoch
is the client's to choose (0 at the start of a recording, seconds of the day,
Unix time …) — or an RFC 3339 timestamp such as ``"2026-12-03T08:00:00Z"``
(a UTC offset is required: ``Z`` or ``±hh:mm``), which the service turns into
seconds since the Unix epoch (1970-01-01T00:00:00Z, leap seconds not
counted, as POSIX time). The models keep a time as it was given (the log and
``GET …/events`` give it back so); :func:`seconds` is what the engine sees.

A session keeps to one way, its first input's (:data:`TimeEpoch`,
``time_epoch`` in ``GET /v1/sessions/{sid}``): a timestamp after numbers, or a
number after timestamps, is refused (422 at ``/time``), as 12.0 after
1 796 284 800.0 would be a 57-year jump.
"""

from __future__ import annotations

import math
import re
from datetime import UTC, datetime
from typing import Annotated, Literal

from pydantic import PlainValidator, WithJsonSchema

from core.numerics import MAX_TIME

TimeEpoch = Literal["arbitrary", "unix"]
"""``arbitrary``: times were numbers (seconds of the client's epoch); ``unix``: RFC 3339
timestamps, as seconds since 1970-01-01T00:00:00Z."""

EXAMPLE_TIMESTAMP = "2026-12-03T08:00:00Z"
ANSWER_TIME = (
    "seconds on the session's clock: since the Unix epoch (1970-01-01T00:00:00Z) when the "
    "session's inputs give RFC 3339 timestamps (time_epoch 'unix' in GET /v1/sessions/{sid}), "
    "else of the client's own epoch"
)
"""What an answer's ``time`` is (answers always give seconds, never timestamps)."""
RFC3339 = re.compile(
    r"(?P<date>\d{4}-\d{2}-\d{2})[Tt ](?P<clock>\d{2}:\d{2}:\d{2})(?P<fraction>\.\d{1,9})?"
    r"(?P<offset>[Zz]|[+-]\d{2}:\d{2})"
)
UNIX_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)
WHAT = (
    "a time is seconds (a finite number) or an RFC 3339 timestamp with its UTC offset, "
    f"e.g. {EXAMPLE_TIMESTAMP!r}"
)


def timestamp_seconds(text: str) -> float:
    """Seconds since the Unix epoch of the RFC 3339 timestamp ``text`` (fractions to 1 ns);
    :class:`ValueError` naming what is wrong if it is not one."""
    match = RFC3339.fullmatch(text)
    if match is None:
        raise ValueError(f"{text[:40]!r} is not an RFC 3339 timestamp: {WHAT}")
    offset = match["offset"].upper()
    try:
        whole = datetime.fromisoformat(f"{match['date']}T{match['clock']}{offset}")
    except ValueError as error:  # 2026-13-40, 25:00:00, a leap second's :60
        raise ValueError(f"{text[:40]!r} is not a valid date and time ({error})") from None
    fraction = float(match["fraction"]) if match["fraction"] else 0.0
    return (whole - UNIX_EPOCH).total_seconds() + fraction


def _session_time(value: object) -> float | str:
    """A wire time as given: a finite number (as a float) or a valid RFC 3339 string."""
    if isinstance(value, str):
        timestamp_seconds(value)
        return value
    if isinstance(value, int | float) and not isinstance(value, bool):
        number = float(value)
        if math.isfinite(number):
            return number
    raise ValueError(WHAT)


SessionTime = Annotated[
    float | str,
    PlainValidator(_session_time),
    WithJsonSchema(
        {
            "anyOf": [
                {"type": "number"},
                {"type": "string", "format": "date-time", "examples": [EXAMPLE_TIMESTAMP]},
            ],
            "description": (
                "seconds on the session's clock (any epoch), or an RFC 3339 timestamp "
                "(converted to seconds since the Unix epoch); a session keeps to the way of "
                f"its first input; at most {MAX_TIME:g} s in magnitude"
            ),
        }
    ),
]
"""A ``time`` of the wire (module docstring)."""


def seconds(time: float | str) -> float:
    """The seconds a wire time stands for (a timestamp: since the Unix epoch)."""
    return timestamp_seconds(time) if isinstance(time, str) else time


def epoch_of(time: float | str) -> TimeEpoch:
    """How a wire time counts: ``unix`` for a timestamp, ``arbitrary`` for a number."""
    return "unix" if isinstance(time, str) else "arbitrary"


def _query_time(value: object) -> float | str:
    """A time of the query string: a number's text (seconds, at most :data:`MAX_TIME` in
    magnitude) or an RFC 3339 timestamp (kept as given)."""
    if not isinstance(value, str):
        return _session_time(value)
    try:
        number = float(value)
    except ValueError:
        timestamp_seconds(value)
        return value
    if not math.isfinite(number) or abs(number) > MAX_TIME:
        raise ValueError(f"{WHAT}, at most {MAX_TIME:g} s in magnitude")
    return number


QueryTime = Annotated[
    float | str,
    PlainValidator(_query_time),
    WithJsonSchema(
        {
            "anyOf": [
                {"type": "number", "minimum": -MAX_TIME, "maximum": MAX_TIME},
                {"type": "string", "format": "date-time", "examples": [EXAMPLE_TIMESTAMP]},
            ]
        }
    ),
]
"""A ``time`` of a query (``GET …/tracks?time=``): seconds or an RFC 3339 timestamp."""
