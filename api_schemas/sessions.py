"""Session lifecycle: creation answer, summary, listing."""

from __future__ import annotations

from pydantic import Field

from api_schemas.base import FiniteFloat, Identifier, Timestamp, WireModel
from api_schemas.config import SessionConfig
from api_schemas.timing import TimeEpoch
from api_schemas.warnings import SitePlacement, Warnings

SITES_DESCRIPTION = "each configured sensor's site in the session frame and its distance"
WARNINGS_DESCRIPTION = (
    "implausible but legal values of the config (README 'Warnings'): the session uses them as given"
)


class SessionCreated(WireModel):
    """``201`` of ``POST /v1/sessions``: the id, the bearer token (shown once), the resolved config."""

    id: str
    token: str
    config: SessionConfig
    created_at: Timestamp
    sites: list[SitePlacement] = Field(default_factory=list, description=SITES_DESCRIPTION)
    warnings: Warnings = Field(default_factory=list, description=WARNINGS_DESCRIPTION)


class DetectionTally(WireModel):
    """What a detecting sensor's detections did in its local tracker, summed over its scans
    (docs/algorithms.md §8.8): the answer to "why is nothing tracked"."""

    detections: int = Field(description="detections received")
    joined_established: int = Field(description="detections that updated a confirmed track")
    joined_tentative: int = Field(description="detections that updated a tentative track")
    started: int = Field(description="detections that started a track")
    unused: int = Field(
        description=(
            "detections that did neither (two-point seeds, left out by the association, "
            "pairs scored at the delete threshold)"
        )
    )
    confirmed: int = Field(description="tracks confirmed")
    refuted: int = Field(description="tentative tracks ended without being confirmed")
    refuted_detections: int = Field(description="the detections of those tracks")
    ended: int = Field(description="confirmed tracks ended")
    ended_reasons: dict[str, int] = Field(description="why they ended: reason → count")
    clutter_density: FiniteFloat | None = Field(
        description=(
            "the clutter density the sensor's scans are scored with: given, or its current "
            "estimate (null before the first scan)"
        )
    )


class SensorActivity(WireModel):
    """What the session has received from one sensor."""

    id: Identifier
    inputs: int
    last_time: FiniteFloat | None
    detections: DetectionTally | None = Field(
        default=None, description="a detecting sensor's tally (null for a track-list source)"
    )


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
    time: FiniteFloat | None = Field(
        description="the fusion time (s; null before the first input): seconds since the Unix "
        "epoch when time_epoch is unix"
    )
    time_epoch: TimeEpoch | None = Field(
        default=None,
        description="how the session's times count, as its first input gave them: 'arbitrary' "
        "(numbers: seconds of the client's own epoch) or 'unix' (RFC 3339 timestamps, as seconds "
        "since 1970-01-01T00:00:00Z); null before the first input. The other way is refused (422)",
    )
    sensors: list[SensorActivity]
    counts: TrackCounts
    sites: list[SitePlacement] = Field(default_factory=list, description=SITES_DESCRIPTION)
    warnings: Warnings = Field(default_factory=list, description=WARNINGS_DESCRIPTION)


class SessionListItem(WireModel):
    """One entry of ``GET /v1/sessions``."""

    id: str
    name: str | None
    created_at: Timestamp
    seq: int


class SessionList(WireModel):
    """``GET /v1/sessions`` (admin)."""

    sessions: list[SessionListItem]
