"""The log form of accepted inputs: ``{"type": "tracks"|"detections", "report": {...}}``.

The store keeps this JSON per sequence number; ``GET …/events`` and replay
turn it back into the typed events of :mod:`api_schemas.events`.
"""

from __future__ import annotations

from datetime import datetime
from typing import Any

from pydantic import TypeAdapter

from api_schemas.events import DetectionsEvent, TracksEvent
from api_schemas.limits import CEILINGS, limits_of
from api_schemas.reports import DetectionReport, TrackReport
from app.outputs.text import dumps, itemwise
from app.stores import LogEntry

TIMESTAMP: TypeAdapter[datetime] = TypeAdapter(datetime)


def log_input(report: TrackReport | DetectionReport) -> dict[str, Any]:
    """The JSON logged for an accepted input."""
    kind = "tracks" if isinstance(report, TrackReport) else "detections"
    return {"type": kind, "report": report.model_dump(mode="json", exclude_none=True)}


def event_from_entry(entry: LogEntry) -> TracksEvent | DetectionsEvent:
    """A logged input as its typed event (read under the hard ceilings, not today's limits)."""
    with limits_of(CEILINGS):
        return _event(entry)


def event_json(entry: LogEntry) -> str:
    """A logged input as the JSON text of its event (the log holds validated JSON already)."""
    received_at = TIMESTAMP.dump_python(entry.received_at, mode="json")
    kind = dumps(entry.input["type"])
    return (
        f'{{"type":{kind},"seq":{entry.seq},"received_at":"{received_at}",'
        f'"report":{itemwise(entry.input["report"])}}}'  # a track at a time
    )


EVENTS: dict[str, type[TracksEvent] | type[DetectionsEvent]] = {
    "tracks": TracksEvent,
    "detections": DetectionsEvent,
}
"""A logged input's ``type`` → the event it is read as."""


def _event(entry: LogEntry) -> TracksEvent | DetectionsEvent:
    kind = entry.input["type"]
    event = EVENTS.get(kind)
    if event is None:
        raise ValueError(f"log entry {entry.seq}: unknown input type {kind!r}")
    return event.model_validate(
        {
            "type": kind,
            "seq": entry.seq,
            "received_at": entry.received_at,
            "report": entry.input["report"],
        }
    )
