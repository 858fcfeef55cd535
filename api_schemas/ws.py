"""WebSocket messages (``/v1/sessions/{sid}/stream`` and ``/subscribe``), documented in docs/asyncapi.yaml.

Every message is a JSON object with a required ``type`` tag. The client sends
``tracks`` and ``detections`` (the REST bodies plus ``type`` and an optional
``ref`` echoed in the answer); the server sends ``result``, ``error`` and ``ack``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, StringConstraints, TypeAdapter

from api_schemas.base import WireModel
from api_schemas.problem import Problem
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import StepResult

ClientRef = Annotated[str, StringConstraints(min_length=1, max_length=128)]


class TracksMessage(TrackReport):
    """Client → server: a track list."""

    type: Literal["tracks"]
    ref: ClientRef | None = None

    def report(self) -> TrackReport:
        """The track list alone, every field of it (``frame`` too), without ``type`` and ``ref``."""
        return TrackReport.model_construct(**_fields_of(self, TrackReport))


class DetectionsMessage(DetectionReport):
    """Client → server: a detection batch."""

    type: Literal["detections"]
    ref: ClientRef | None = None

    def report(self) -> DetectionReport:
        """The detection batch alone, without ``type`` and ``ref``."""
        return DetectionReport.model_construct(**_fields_of(self, DetectionReport))


def _fields_of(message: WireModel, report: type[WireModel]) -> dict[str, Any]:
    """The values of ``report``'s fields in ``message`` (validated already: not again)."""
    return {name: getattr(message, name) for name in report.model_fields}


class ResultMessage(WireModel):
    """Server → client: the fused result of an input (``ref`` echoes the input's)."""

    type: Literal["result"]
    ref: str | None
    result: StepResult


class ErrorMessage(WireModel):
    """Server → client: a message was rejected; the connection stays open."""

    type: Literal["error"]
    ref: str | None
    problem: Problem


class AckMessage(WireModel):
    """Server → client: the connection is ready; ``seq`` is the session's latest sequence number."""

    type: Literal["ack"]
    ref: str | None
    seq: int


class GapMessage(WireModel):
    """Server → subscriber: the results after ``after`` and before ``next`` were not delivered
    (the subscriber fell behind, or an instance died between logging an input and publishing
    its result): read ``GET …/tracks`` for the current picture (or ``GET …/events?after=``
    for the inputs). Sent just before the result numbered ``next``."""

    type: Literal["gap"]
    ref: str | None
    after: int
    next: int


ClientMessage = Annotated[TracksMessage | DetectionsMessage, Field(discriminator="type")]
ServerMessage = Annotated[
    ResultMessage | ErrorMessage | AckMessage | GapMessage, Field(discriminator="type")
]

client_message_adapter: TypeAdapter[TracksMessage | DetectionsMessage] = TypeAdapter(ClientMessage)
server_message_adapter: TypeAdapter[ResultMessage | ErrorMessage | AckMessage | GapMessage] = (
    TypeAdapter(ServerMessage)
)
