"""The ``geojson`` output format: fused tracks as an ``application/geo+json`` FeatureCollection.

Point features ``[lon°, lat°, alt m]`` on WGS84 (RFC 7946) with each track's
id, status, sources (sensor ids), decision and decision state, BetP, velocity
east/north(/up) and 2-σ position ellipse at its point
(:func:`app.geo.geojson.feature_collection`); the answer's ``seq`` and
``time`` (and a step's ``sensor``) are foreign members of the collection
(RFC 7946 §6.1). ``api_schemas.results.FusedFeatureCollection`` documents it.
It needs the session's ``origin``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from api_schemas.results import FusedFeatureCollection
from api_schemas.warnings import FieldWarning
from app.geo.geojson import GEOJSON_MEDIA_TYPE, GeodeticOutput, feature_collection
from app.outputs.base import OutputFormat, PlainObject
from app.outputs.json_results import check_finite
from app.outputs.text import itemwise
from core.fusion.classes import ClassAssessment
from core.fusion.reports import FusedTrackView
from core.fusion.reports import StepResult as CoreStepResult


class GeoJsonFormat(OutputFormat):
    """``application/geo+json`` (module docstring)."""

    name = "geojson"
    media_type = GEOJSON_MEDIA_TYPE
    step_model = FusedFeatureCollection
    picture_model = FusedFeatureCollection
    needs_geodetic = True
    description = "an application/geo+json FeatureCollection of the tracks (needs origin)"

    def step(
        self,
        step: CoreStepResult,
        seq: int,
        geodetic: GeodeticOutput | None,
        warnings: Sequence[FieldWarning] = (),
    ) -> str:
        assert geodetic is not None
        header: dict[str, Any] = {
            "seq": seq,
            "time": step.time,
            "sensor": step.sensor,
            "warnings": [entry.model_dump() for entry in warnings],
        }
        return _collection(header, step.tracks, geodetic)

    def picture(
        self,
        seq: int,
        time: float | None,
        views: Sequence[FusedTrackView],
        geodetic: GeodeticOutput | None,
    ) -> str:
        assert geodetic is not None
        return _collection({"seq": seq, "time": time}, views, geodetic)

    def from_plain(self, result: PlainObject, geodetic: GeodeticOutput | None) -> str:
        assert geodetic is not None
        header: dict[str, Any] = {
            k: result[k] for k in ("seq", "time", "sensor", "warnings") if k in result
        }
        return itemwise({**header, **feature_collection(result["tracks"], geodetic)})


def _collection(
    header: dict[str, Any], views: Sequence[FusedTrackView], geodetic: GeodeticOutput
) -> str:
    """The tracks as a FeatureCollection after ``header``'s members, written a feature at a time."""
    check_finite(views)
    tracks = [
        {
            "id": view.id,
            "status": view.status.value,
            "state": view.state,
            "covariance": view.covariance,
            "sources": view.sources,
            "classification": _decision(view.classification),
        }
        for view in views
    ]
    return itemwise({**header, **feature_collection(tracks, geodetic)})


def _decision(assessment: ClassAssessment | None) -> PlainObject | None:
    """What a GeoJSON feature says of a track's class: its decision, decision state and BetP."""
    if assessment is None:
        return None
    if assessment.mass is None:  # total conflict: no BetP, no decision
        return {"decision": None, "decision_state": assessment.decision_state.value}
    labels = assessment.mass.frame.labels
    return {
        "decision": assessment.decision,
        "decision_state": assessment.decision_state.value,
        "pignistic": dict(zip(labels, assessment.pignistic.tolist(), strict=True)),
    }
