"""Session lifecycle: creation answer, summary, listing."""

from __future__ import annotations

from api_schemas.base import FiniteFloat, Identifier, Timestamp, WireModel
from api_schemas.config import SessionConfig


class SessionCreated(WireModel):
    """``201`` of ``POST /v1/sessions``: the id, the bearer token (shown once), the resolved config."""

    id: str
    token: str
    config: SessionConfig
    created_at: Timestamp


class SensorActivity(WireModel):
    """What the session has received from one sensor."""

    id: Identifier
    inputs: int
    last_time: FiniteFloat | None


class TrackCounts(WireModel):
    """Fused tracks by status."""

    tentative: int
    confirmed: int
    coasting: int
    phantom: int
    terminated: int


class SessionSummary(WireModel):
    """``GET /v1/sessions/{sid}``: config, sensors, counts, session time and latest seq."""

    id: str
    name: str | None
    created_at: Timestamp
    last_input_at: Timestamp | None
    config: SessionConfig
    seq: int
    time: FiniteFloat | None
    sensors: list[SensorActivity]
    counts: TrackCounts


class SessionListItem(WireModel):
    """One entry of ``GET /v1/sessions``."""

    id: str
    name: str | None
    created_at: Timestamp
    seq: int


class SessionList(WireModel):
    """``GET /v1/sessions`` (admin)."""

    sessions: list[SessionListItem]
