"""``GET /v1/sessions/{sid}/events``: the accepted inputs, in order, for export and replay."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from api_schemas.base import Timestamp, WireModel
from api_schemas.reports import DetectionReport, TrackReport


class TracksEvent(WireModel):
    """An accepted track list with its sequence number and reception time."""

    type: Literal["tracks"]
    seq: int
    received_at: Timestamp
    report: TrackReport


class DetectionsEvent(WireModel):
    """An accepted detection batch with its sequence number and reception time."""

    type: Literal["detections"]
    seq: int
    received_at: Timestamp
    report: DetectionReport


SessionEvent = Annotated[TracksEvent | DetectionsEvent, Field(discriminator="type")]


class SnapshotEvent(WireModel):
    """The session's state after input ``seq`` (the engine export and the service's counters).

    A page starts with one when the log no longer holds the inputs after
    ``after`` (they were compacted behind this snapshot): a replay restores the
    state, then applies the events that follow.
    """

    type: Literal["snapshot"]
    seq: int
    taken_at: Timestamp
    state: dict[str, Any]


class EventLog(WireModel):
    """A page of the log: events with ``seq > after``, oldest first; ``last_seq`` is the session's latest.

    ``snapshot`` is set when inputs after ``after`` were compacted away (see
    ``CREDAL_LOG_RETENTION``): ``events`` then follow the snapshot's ``seq``.
    """

    session: str
    snapshot: SnapshotEvent | None = None
    events: list[SessionEvent]
    last_seq: int
