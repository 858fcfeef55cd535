"""Per-input and per-config limits are checked on the raw list, before its items, and name the setting."""

from __future__ import annotations

import copy
from collections.abc import Iterator
from contextlib import contextmanager

import pytest
from pydantic import ValidationError

from api_schemas.associate import AssociateRequest
from api_schemas.config import SessionConfig
from api_schemas.limits import ACTIVE_LIMITS, LIMIT_EXCEEDED, WireLimits
from api_schemas.reports import DetectionReport, TrackReport
from tests.api.conftest import make_settings
from tests.api.examples import DETECTION_REPORT, SESSION_CONFIG, TRACK_REPORT


@contextmanager
def limits(**values: int) -> Iterator[None]:
    token = ACTIVE_LIMITS.set(make_settings(**values).wire_limits())
    try:
        yield
    finally:
        ACTIVE_LIMITS.reset(token)


def breaches(error: ValidationError) -> list[dict[str, object]]:
    return [dict(entry) for entry in error.errors() if entry["type"] == LIMIT_EXCEEDED]


def test_tracks_per_input() -> None:
    body = copy.deepcopy(TRACK_REPORT)
    body["tracks"] = [dict(body["tracks"][0], id=str(index)) for index in range(3)]
    with limits(max_tracks_per_input=3):
        TrackReport.model_validate(body)
    with limits(max_tracks_per_input=2), pytest.raises(ValidationError) as caught:
        TrackReport.model_validate(body)
    (breach,) = breaches(caught.value)
    assert breach["loc"] == ("tracks",)
    assert breach["ctx"] == {
        "what": "tracks",
        "limit": "max_tracks_per_input",
        "maximum": 2,
        "actual": 3,
    }


def test_the_length_is_checked_before_any_item() -> None:
    """100 000 invalid tracks: one error (the length), not 700 000 item errors."""
    with pytest.raises(ValidationError) as caught:
        AssociateRequest.model_validate({"known": [{}] * 100_000, "incoming": []})
    assert len(caught.value.errors()) == 1
    assert breaches(caught.value)[0]["ctx"]["actual"] == 100_000  # type: ignore[index]


def test_detections_per_input_use_the_same_limit() -> None:
    with limits(max_tracks_per_input=1), pytest.raises(ValidationError) as caught:
        DetectionReport.model_validate(DETECTION_REPORT)
    assert breaches(caught.value)[0]["loc"] == ("detections",)


def test_sensors_are_counted_before_they_are_validated() -> None:
    config = dict(SESSION_CONFIG, sensors=[{}] * 200_000)
    with pytest.raises(ValidationError) as caught:
        SessionConfig.model_validate(config)
    assert len(caught.value.errors()) == 1
    assert breaches(caught.value)[0]["ctx"]["limit"] == "max_sensors"  # type: ignore[index]


def test_classes_limit_below_the_frame_maximum() -> None:
    with limits(max_classes=3):
        SessionConfig.model_validate(SESSION_CONFIG)
    with limits(max_classes=2), pytest.raises(ValidationError) as caught:
        SessionConfig.model_validate(SESSION_CONFIG)
    assert breaches(caught.value)[0]["ctx"]["limit"] == "max_classes"  # type: ignore[index]


def test_focal_sets_per_mass() -> None:
    body = copy.deepcopy(TRACK_REPORT)
    with limits(max_focal_sets=1), pytest.raises(ValidationError) as caught:
        TrackReport.model_validate(body)
    (breach,) = breaches(caught.value)
    assert breach["loc"] == ("tracks", 0, "classification", "mass")


def test_settings_refuse_limits_above_the_schema_ceilings() -> None:
    with pytest.raises(ValueError, match="max_classes"):
        make_settings(max_classes=21)
    with pytest.raises(ValueError, match="max_focal_sets"):
        make_settings(max_focal_sets=1025)


def test_default_limits_are_the_settings_defaults() -> None:
    assert make_settings().wire_limits() == WireLimits()
