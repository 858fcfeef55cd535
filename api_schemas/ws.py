"""WebSocket messages (``/v1/sessions/{sid}/stream`` and ``/subscribe``), documented in docs/asyncapi.yaml.

Every message is a JSON object with a required ``type`` tag. The client sends
``tracks`` and ``detections`` (the REST bodies plus ``type`` and an optional
``ref`` echoed in the answer; the union of the registered input kinds' messages is
``app.inputs.client_messages``); the server sends ``result``, ``error`` and ``ack``.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, StringConstraints, TypeAdapter

from api_schemas.base import WireModel
from api_schemas.problem import Problem
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import FusedFeatureCollection, StepResult

ClientRef = Annotated[str, StringConstraints(min_length=1, max_length=128)]
IDEMPOTENCY_KEY_MAX = 128
IDEMPOTENCY_KEY_PATTERN = r"^[!-~]+$"
"""An idempotency key: 1 to 128 visible ASCII characters (as the REST ``Idempotency-Key``)."""
IdempotencyKey = Annotated[
    str,
    StringConstraints(
        min_length=1, max_length=IDEMPOTENCY_KEY_MAX, pattern=IDEMPOTENCY_KEY_PATTERN
    ),
    Field(
        description="names this input, as the REST Idempotency-Key header: sent again with the "
        "same key (a resend after a lost answer or a reconnection), it is not applied twice and "
        "its first result is sent again (an error 409 idempotency-key-reused if the key came "
        "with another input); keys are kept with the session's log, so any instance knows them"
    ),
]


class TracksMessage(TrackReport):
    """Client → server: a track list."""

    type: Literal["tracks"]
    ref: ClientRef | None = None
    idempotency_key: IdempotencyKey | None = None


class DetectionsMessage(DetectionReport):
    """Client → server: a detection batch."""

    type: Literal["detections"]
    ref: ClientRef | None = None
    idempotency_key: IdempotencyKey | None = None


class ResultMessage(WireModel):
    """Server → client: the fused result of an input (``ref`` echoes the input's), in the
    connection's ``format`` (``json``: a ``StepResult``; ``geojson``: a FeatureCollection)."""

    type: Literal["result"]
    ref: str | None
    result: StepResult | FusedFeatureCollection


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


ServerMessage = Annotated[
    ResultMessage | ErrorMessage | AckMessage | GapMessage, Field(discriminator="type")
]

server_message_adapter: TypeAdapter[ResultMessage | ErrorMessage | AckMessage | GapMessage] = (
    TypeAdapter(ServerMessage)
)
