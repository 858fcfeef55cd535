"""Limits: body size (checked before anything parses the body), sessions, sensors, classes, items."""

from __future__ import annotations

from http import HTTPStatus

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport, TrackReport
from app.errors import LimitExceeded, problem_response
from app.settings import Settings

BODY_LIMIT = "max_body_bytes"
DRAIN_BYTES = 8 * 1024 * 1024
"""An oversize body is read and discarded up to this size before the 413 is sent."""


class BodySizeLimit:
    """ASGI middleware: a request body larger than ``max_bytes`` gets 413 naming the limit.

    The body is read (chunked bodies included) only up to the limit and then
    replayed to the application, so no parser ever sees an oversize body.
    After a refusal the rest of the body is read and discarded, up to
    :data:`DRAIN_BYTES`, so the client can read the answer instead of a
    connection reset; a ``Content-Length`` beyond that is refused at once
    and the connection closed.
    """

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        declared_text = dict(scope["headers"]).get(b"content-length")
        declared = (
            int(declared_text) if declared_text is not None and declared_text.isdigit() else None
        )
        if declared is not None and declared > self.max_bytes:
            ended = declared <= DRAIN_BYTES and await _drain(receive, DRAIN_BYTES)
            await self._refuse(scope, receive, send, declared, ended)
            return
        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            chunk: bytes = message.get("body", b"")
            size += len(chunk)
            more = bool(message.get("more_body", False))
            if size > self.max_bytes:
                ended = not more or await _drain(receive, DRAIN_BYTES)
                await self._refuse(scope, receive, send, declared, ended)
                return
            chunks.append(chunk)
            if not more:
                break
        body = b"".join(chunks)
        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)

    async def _refuse(
        self, scope: Scope, receive: Receive, send: Send, declared: int | None, ended: bool
    ) -> None:
        got = "" if declared is None else f" (Content-Length {declared})"
        response = problem_response(
            None,
            status=HTTPStatus.REQUEST_ENTITY_TOO_LARGE,
            slug="body-too-large",
            title="Body too large",
            detail=f"request body exceeds limit {BODY_LIMIT} = {self.max_bytes} bytes{got}",
            instance=scope.get("path"),
            limit=BODY_LIMIT,
            maximum=self.max_bytes,
        )
        if not ended:
            response.headers["Connection"] = "close"
        await response(scope, receive, send)


async def _drain(receive: Receive, budget: int) -> bool:
    """Read and discard the rest of a body, at most ``budget`` bytes; whether it ended."""
    drained = 0
    while drained <= budget:
        message = await receive()
        if message["type"] != "http.request":
            return False
        drained += len(message.get("body", b""))
        if not message.get("more_body", False):
            return True
    return False


def check_config_limits(config: SessionConfig, settings: Settings) -> None:
    """Sensors and classes of a session config within the configured limits."""
    if len(config.sensors) > settings.max_sensors:
        raise LimitExceeded(
            "max_sensors", settings.max_sensors, len(config.sensors), what="sensors"
        )
    if len(config.classes) > settings.max_classes:
        raise LimitExceeded(
            "max_classes", settings.max_classes, len(config.classes), what="classes"
        )


def check_report_limits(report: TrackReport | DetectionReport, settings: Settings) -> None:
    """Items of one input within ``max_tracks_per_input``."""
    items = len(report.tracks) if isinstance(report, TrackReport) else len(report.detections)
    if items > settings.max_tracks_per_input:
        what = "tracks" if isinstance(report, TrackReport) else "detections"
        raise LimitExceeded("max_tracks_per_input", settings.max_tracks_per_input, items, what=what)
