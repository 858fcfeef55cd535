"""``GET /v1/sessions/{sid}/events``: the accepted inputs, in order, for export and replay."""

from __future__ import annotations

from typing import Annotated, Literal

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


class EventLog(WireModel):
    """A page of the log: events with ``seq > after``, oldest first; ``last_seq`` is the session's latest."""

    session: str
    events: list[SessionEvent]
    last_seq: int
