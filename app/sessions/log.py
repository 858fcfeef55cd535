"""The log form of accepted inputs: ``{"type": <input kind's tag>, "report": {...}}``.

The store keeps this JSON per sequence number; ``GET …/events`` and replay
turn it back into the typed events of :mod:`api_schemas.events`.
"""

from __future__ import annotations

from datetime import datetime

from pydantic import TypeAdapter

from api_schemas.base import WireModel
from api_schemas.limits import CEILINGS, limits_of
from app.inputs import INPUT_KINDS, Input
from app.outputs.text import dumps, itemwise
from app.stores import LogEntry

TIMESTAMP: TypeAdapter[datetime] = TypeAdapter(datetime)


def event_from_entry(entry: LogEntry) -> WireModel:
    """A logged input as its typed event (read under the hard ceilings, not today's limits)."""
    with limits_of(CEILINGS):
        return _event(entry)


def logged_input(entry: LogEntry) -> Input:
    """A logged input, to be applied again (replay, catch-up)."""
    event = event_from_entry(entry)
    return Input(INPUT_KINDS[entry.input["type"]], event.report)  # type: ignore[attr-defined]


def event_json(entry: LogEntry) -> str:
    """A logged input as the JSON text of its event (the log holds validated JSON already)."""
    received_at = TIMESTAMP.dump_python(entry.received_at, mode="json")
    kind = dumps(entry.input["type"])
    return (
        f'{{"type":{kind},"seq":{entry.seq},"received_at":"{received_at}",'
        f'"report":{itemwise(entry.input["report"])}}}'  # a track at a time
    )


def _event(entry: LogEntry) -> WireModel:
    kind = INPUT_KINDS.get(entry.input["type"])
    if kind is None:
        raise ValueError(f"log entry {entry.seq}: unknown input type {entry.input['type']!r}")
    return kind.event_model.model_validate(
        {
            "type": kind.tag,
            "seq": entry.seq,
            "received_at": entry.received_at,
            "report": entry.input["report"],
        }
    )
