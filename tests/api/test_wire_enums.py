"""The wire's enums and defaults are the core's: a value added on one side fails here first.

Each ``Literal`` of ``api_schemas`` that names a core concept is compared with
the core's own list (its enum). The association methods and their options are
not here: the wire generates them from the core's registry (one source,
``api_schemas.association``). ``openapi.json`` lists
``reason`` as an enum, from the same ``Literal``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, get_args, get_origin

import pytest

from api_schemas.association import ImmDistanceKind
from api_schemas.config import (
    MeasurementModel,
    MotionModel,
    SessionConfig,
    SinglePointInitiation,
    StateFusionMethod,
    TrackingConfig,
    TrackingPreset,
    TwoPointInitiation,
)
from api_schemas.reports import DetectionReport
from api_schemas.results import (
    ClassificationState,
    DecisionState,
    PairBasis,
    StatusReason,
    TrackStatus,
)
from app.inputs.detections import core_detection_report
from app.sessions.translate import fusion_config
from core.belief.decision import DecisionState as CoreDecisionState
from core.fusion.classes import ClassState
from core.fusion.motion import MotionKind
from core.fusion.state import StateFusion
from core.lifecycle import StatusReason as CoreStatusReason
from core.lifecycle import TrackStatus as CoreTrackStatus
from core.tracking.config import IMM_DISTANCES, INITIATIONS, LocalTrackerConfig
from core.tracking.presets import PRESETS

OPENAPI = Path(__file__).resolve().parents[2] / "openapi.json"


def values(literal: Any) -> set[str]:
    return {str(value) for value in get_args(literal)}


def field_values(model: Any, name: str) -> set[str]:
    """The values of a model field's ``Literal``."""
    return values(model.model_fields[name].annotation)


def test_track_status_and_reason_are_the_cores() -> None:
    assert values(TrackStatus) == {status.value for status in CoreTrackStatus}
    assert values(StatusReason) == {reason.value for reason in CoreStatusReason}


def test_classification_state_and_state_fusion_are_the_cores() -> None:
    assert values(ClassificationState) == {state.value for state in ClassState}
    assert values(StateFusionMethod) == {rule.value for rule in StateFusion}


def test_decision_state_and_motion_models_are_the_cores() -> None:
    assert values(DecisionState) == {state.value for state in CoreDecisionState}
    assert field_values(MotionModel, "model") == {kind.value for kind in MotionKind}


def test_local_tracking_vocabulary_is_the_cores() -> None:
    assert values(ImmDistanceKind) == set(IMM_DISTANCES)
    assert values(TrackingPreset) == set(PRESETS)
    initiations = field_values(TwoPointInitiation, "kind") | field_values(
        SinglePointInitiation, "kind"
    )
    assert initiations == set(INITIATIONS)


def test_local_tracking_defaults_are_the_cores() -> None:
    core = LocalTrackerConfig
    assert TrackingConfig().time_interval == core.time_interval
    assert TwoPointInitiation(kind="two_point").max_speed == core.max_speed
    assert SinglePointInitiation().velocity_std is core.initial_velocity_std is None
    paper = LocalTrackerConfig.paper()
    assert TwoPointInitiation(kind="two_point").velocity_std == paper.initial_velocity_std


MEASUREMENTS: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {
    "cartesian": ({"kind": "cartesian", "r": [[4.0, 0.0], [0.0, 4.0]]}, {"z": [300.0, 400.0]}),
    "polar": (
        {"kind": "polar", "sigma_range": 2.0, "sigma_azimuth_deg": 0.1},
        {"range": 500.0, "azimuth_deg": 36.86989764584402},
    ),
}


def union_models(annotation: Any) -> list[Any]:
    """The models of a (tagged) union annotation, ``Annotated`` wrappers taken off."""
    while get_origin(annotation) is Annotated:
        annotation = get_args(annotation)[0]
    if isinstance(annotation, type):
        return [annotation]
    return [model for member in get_args(annotation) for model in union_models(member)]


MEASUREMENT_KINDS = {
    kind for model in union_models(MeasurementModel) for kind in field_values(model, "kind")
}


def test_measurement_kinds_are_a_tagged_union() -> None:
    assert {"cartesian", "polar"} == MEASUREMENT_KINDS


@pytest.mark.parametrize("kind", sorted(MEASUREMENT_KINDS))
def test_every_measurement_kind_becomes_the_cores_cartesian_position(kind: str) -> None:
    """The core knows one measurement, a position (and its noise): every wire kind is turned
    into it (a polar detection at 500 m, azimuth atan(3/4) from north, is at (300, 400))."""
    measurement, detection = MEASUREMENTS[kind]
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "sensors": [{"id": "radar", "measurement": measurement}],
        }
    )
    report = DetectionReport.model_validate(
        {"sensor": "radar", "time": 1.0, "detections": [detection]}
    )
    core = core_detection_report(report, config, fusion_config(config))
    assert core.measurements.shape == (1, 2)
    assert core.measurements[0].tolist() == pytest.approx([300.0, 400.0], abs=1e-9)


WIRE_ENUMS = [
    ("FusedTrack", "status", {status.value for status in CoreTrackStatus}),
    ("FusedTrack", "reason", {reason.value for reason in CoreStatusReason}),
    ("FusedClassification", "state", {state.value for state in ClassState}),
    ("FusedClassification", "decision_state", {state.value for state in CoreDecisionState}),
    ("FusedPair", "basis", values(PairBasis)),
]


@pytest.mark.parametrize(("schema", "name", "expected"), WIRE_ENUMS)
def test_result_enums_are_enums_in_openapi(schema: str, name: str, expected: set[str]) -> None:
    """``reason`` and its kin are listed as enums in ``openapi.json``, with the core's values."""
    schemas = json.loads(OPENAPI.read_text(encoding="utf-8"))["components"]["schemas"]
    field = schemas[schema]["properties"][name]
    options = field.get("anyOf", [field])
    enums = [option for option in options if "enum" in option or "$ref" in option]
    assert enums, field
    listed: set[str] = set()
    for option in enums:
        target = schemas[option["$ref"].rsplit("/", 1)[1]] if "$ref" in option else option
        listed |= set(target["enum"])
    assert listed == expected
