"""A tiny FastAPI app that validates bodies with the wire models and the service's error handlers."""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI

from api_schemas.associate import AssociateRequest
from api_schemas.config import SessionConfig
from api_schemas.consistency import detection_report_issues, track_report_issues
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.ws import ClientMessage
from app.errors import install_error_handlers, request_validation_error
from tests.api.examples import SESSION_CONFIG

CONFIG = SessionConfig.model_validate(SESSION_CONFIG)


def build_validation_app() -> FastAPI:
    """Routes that only validate: a session config, a track list, detections, an associate request, a WS message."""
    app = FastAPI()
    install_error_handlers(app)

    @app.post("/sessions")
    def post_config(config: SessionConfig) -> dict[str, Any]:
        return {"ok": True, "sensors": len(config.sensors)}

    @app.post("/tracks")
    def post_tracks(report: TrackReport) -> dict[str, Any]:
        issues = track_report_issues(report, CONFIG)
        if issues:
            raise request_validation_error(issues)
        return {"ok": True}

    @app.post("/detections")
    def post_detections(report: DetectionReport) -> dict[str, Any]:
        issues = detection_report_issues(report, CONFIG)
        if issues:
            raise request_validation_error(issues)
        return {"ok": True}

    @app.post("/associate")
    def post_associate(request: AssociateRequest) -> dict[str, Any]:
        return {"ok": True, "method": request.method}

    @app.post("/message")
    def post_message(message: ClientMessage) -> dict[str, Any]:
        return {"ok": True, "type": message.type}

    return app
