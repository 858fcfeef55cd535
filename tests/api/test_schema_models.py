"""The wire models accept docs/design.md's examples and resolve defaults."""

from __future__ import annotations

import copy

import pytest
from pydantic import ValidationError

from api_schemas.associate import AssociateRequest
from api_schemas.config import SessionConfig
from api_schemas.consistency import detection_report_issues, track_report_issues
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import StepResult
from api_schemas.ws import server_message_adapter
from app.inputs import client_messages
from tests.api.examples import (
    DETECTION_REPORT,
    LIKELIHOOD_EVIDENCE,
    SESSION_CONFIG,
    STEP_RESULT,
    TRACK_REPORT,
)


def test_design_examples_validate() -> None:
    config = SessionConfig.model_validate(SESSION_CONFIG)
    report = TrackReport.model_validate(TRACK_REPORT)
    detections = DetectionReport.model_validate(DETECTION_REPORT)
    assert track_report_issues(report, config) == []
    assert detection_report_issues(detections, config) == []
    assert StepResult.model_validate(STEP_RESULT).tracks[0].classification is not None


def test_likelihood_evidence_is_accepted() -> None:
    body = copy.deepcopy(TRACK_REPORT)
    body["tracks"][0]["classification"] = LIKELIHOOD_EVIDENCE
    report = TrackReport.model_validate(body)
    assert report.tracks[0].classification is not None
    assert report.tracks[0].classification.likelihoods == LIKELIHOOD_EVIDENCE["likelihoods"]


def test_resolved_config_fills_defaults_and_round_trips() -> None:
    resolved = SessionConfig.model_validate(
        {"state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]}}
    )
    assert resolved.association.method == "denoeux"
    assert resolved.association.options.gate_probability == 0.999
    assert resolved.association.options.distance == "sum"
    assert resolved.tracking.association.method == "gnn"
    assert resolved.fusion.state == "covariance_intersection"
    plain = resolved.model_dump(mode="json")
    assert SessionConfig.model_validate(plain).model_dump(mode="json") == plain


def test_exclusive_defaults_are_not_filled() -> None:
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "association": {"method": "gnn", "options": {"threshold": 9.0}},
        }
    )
    assert config.association.options.threshold == 9.0
    assert config.association.options.gate_probability is None


def test_cross_field_errors_are_located() -> None:
    body = copy.deepcopy(SESSION_CONFIG)
    body["sensors"][0]["measurement"]["r"] = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    with pytest.raises(ValidationError) as caught:
        SessionConfig.model_validate(body)
    assert [error["loc"] for error in caught.value.errors()] == [("sensors", 0, "measurement", "r")]


def test_associate_rejects_mixed_dimensions() -> None:
    track = TRACK_REPORT["tracks"][0]
    small = {"id": "x", "state": [1.0, 2.0], "covariance": [[1, 0], [0, 1]]}
    with pytest.raises(ValidationError) as caught:
        AssociateRequest.model_validate(
            {"known": [track], "incoming": [small], "classes": ["liner", "bomber", "fighter"]}
        )
    assert caught.value.errors()[0]["loc"] == ("incoming", 0, "state")


def test_websocket_messages_need_their_tag() -> None:
    message = {"type": "tracks", "ref": "r1", **TRACK_REPORT}
    assert client_messages().validate_python(message).ref == "r1"
    untagged = {key: value for key, value in message.items() if key != "type"}
    with pytest.raises(ValidationError):
        client_messages().validate_python(untagged)
    ack = server_message_adapter.validate_python({"type": "ack", "ref": None, "seq": 0})
    assert ack.type == "ack"
