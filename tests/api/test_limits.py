"""Per-input and per-config limits name the setting that was exceeded."""

from __future__ import annotations

import copy

import pytest

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport, TrackReport
from app.errors import LimitExceeded
from app.limits import check_config_limits, check_report_limits
from tests.api.conftest import make_settings
from tests.api.examples import DETECTION_REPORT, SESSION_CONFIG, TRACK_REPORT


def test_tracks_per_input() -> None:
    body = copy.deepcopy(TRACK_REPORT)
    body["tracks"] = [dict(body["tracks"][0], id=str(index)) for index in range(3)]
    report = TrackReport.model_validate(body)
    check_report_limits(report, make_settings(max_tracks_per_input=3))
    with pytest.raises(LimitExceeded) as caught:
        check_report_limits(report, make_settings(max_tracks_per_input=2))
    assert caught.value.extensions == {"limit": "max_tracks_per_input", "maximum": 2, "actual": 3}
    assert caught.value.status_code == 422


def test_detections_per_input_use_the_same_limit() -> None:
    report = DetectionReport.model_validate(DETECTION_REPORT)
    with pytest.raises(LimitExceeded, match="detections"):
        check_report_limits(report, make_settings(max_tracks_per_input=1))


def test_classes_limit_below_the_frame_maximum() -> None:
    config = SessionConfig.model_validate(SESSION_CONFIG)
    check_config_limits(config, make_settings(max_classes=3))
    with pytest.raises(LimitExceeded) as caught:
        check_config_limits(config, make_settings(max_classes=2))
    assert caught.value.extensions["limit"] == "max_classes"


def test_settings_refuse_more_than_20_classes() -> None:
    with pytest.raises(ValueError, match="max_classes"):
        make_settings(max_classes=21)
