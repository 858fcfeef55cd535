"""The wire's enums and defaults are the core's: a value added on one side fails here first.

Each ``Literal`` of ``api_schemas`` that names a core concept is compared with
the core's own list (its enum or its method table), and the defaults the wire
fills in are compared with the core's defaults. ``openapi.json`` lists
``reason`` as an enum, from the same ``Literal``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, get_args

from api_schemas.association import METHOD_DEFAULTS, AssociationMethod
from api_schemas.config import StateFusionMethod
from api_schemas.results import ClassificationState, StatusReason, TrackStatus
from core.association import DEFAULT_DISTANCE, LOCAL_TRACKING_DEFAULT, TRACK_TO_TRACK_DEFAULT
from core.association.associate import METHODS
from core.association.denoeux import DEFAULT_GATE_PROBABILITY
from core.fusion.classes import ClassState
from core.fusion.state import StateFusion
from core.lifecycle import StatusReason as CoreStatusReason
from core.lifecycle import TrackStatus as CoreTrackStatus

OPENAPI = Path(__file__).resolve().parents[2] / "openapi.json"


def values(literal: Any) -> set[str]:
    return {str(value) for value in get_args(literal)}


def test_track_status_and_reason_are_the_cores() -> None:
    assert values(TrackStatus) == {status.value for status in CoreTrackStatus}
    assert values(StatusReason) == {reason.value for reason in CoreStatusReason}


def test_classification_state_and_state_fusion_are_the_cores() -> None:
    assert values(ClassificationState) == {state.value for state in ClassState}
    assert values(StateFusionMethod) == {rule.value for rule in StateFusion}


def test_association_methods_are_the_cores() -> None:
    assert values(AssociationMethod) == set(METHODS)


def test_wire_defaults_are_the_cores() -> None:
    for method, distance in DEFAULT_DISTANCE.items():
        assert METHOD_DEFAULTS[method]["distance"] == distance, method
    method, options, _ = TRACK_TO_TRACK_DEFAULT
    assert {key: METHOD_DEFAULTS[method][key] for key in options} == options
    local_method, local_options, _ = LOCAL_TRACKING_DEFAULT
    assert {key: METHOD_DEFAULTS[local_method][key] for key in local_options} == local_options
    assert METHOD_DEFAULTS["denoeux"]["gate_probability"] == DEFAULT_GATE_PROBABILITY


def test_reason_is_an_enum_in_openapi() -> None:
    schemas = json.loads(OPENAPI.read_text(encoding="utf-8"))["components"]["schemas"]
    reason = schemas["FusedTrack"]["properties"]["reason"]
    options = reason.get("anyOf", [reason])
    enums = [option for option in options if "enum" in option or "$ref" in option]
    assert enums, reason
    listed: set[str] = set()
    for option in enums:
        target = schemas[option["$ref"].rsplit("/", 1)[1]] if "$ref" in option else option
        listed |= set(target["enum"])
    assert listed == {reason.value for reason in CoreStatusReason}
