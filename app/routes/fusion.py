"""Inputs and the fused picture of a session: ``/v1/sessions/{sid}/tracks`` and ``…/detections``."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import orjson
from fastapi import APIRouter, Path, Query
from fastapi.responses import Response

from api_schemas.base import FiniteFloat
from api_schemas.config import SessionConfig
from api_schemas.issues import FieldIssue
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import FusedPicture, FusedTrackDetail, StepResult
from app.geo.geodesy import LocalFrame
from app.geo.geojson import GEOJSON_MEDIA_TYPE, feature_collection, with_geodetic
from app.http.deps import CurrentSessionDep, LiveSessionDep, RegistryDep
from app.http.errors import (
    TrackNotFound,
    problem_responses,
    request_validation_error,
)
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse, PlainJSONResponse, dumps
from app.sessions.translate import session_origin

router = APIRouter(prefix="/v1/sessions", tags=["fusion"], route_class=WireRoute)

TrackId = Annotated[str, Path(min_length=1, max_length=64, description="A fused track id.")]
OutputFrame = Annotated[
    Literal["session", "geodetic"],
    Query(description="geodetic: add geodetic {lat, lon, alt} to each fused track (needs origin)"),
]


def origin_of(config: SessionConfig, parameter: str) -> LocalFrame:
    """The session's origin frame, or a 422 at the query ``parameter``: it has none."""
    frame = session_origin(config)
    if frame is None:
        raise request_validation_error(
            [FieldIssue((parameter,), "the session has no origin: geodetic output needs one")],
            prefix="query",
        )
    return frame


def geodetic_result(result: str, frame: LocalFrame, config: SessionConfig) -> str:
    """A step result's JSON text with ``geodetic`` added to each fused track."""
    document: dict[str, Any] = orjson.loads(result)
    document["tracks"] = with_geodetic(document["tracks"], frame, tuple(config.state.position))
    return dumps(document)


@router.post(
    "/{sid}/tracks",
    response_model=StepResult,
    responses=problem_responses(401, 403, 404, 409, 413, 422, 503),
)
async def submit_tracks(
    report: TrackReport,
    session: LiveSessionDep,
    registry: RegistryDep,
    explain: Annotated[
        bool, Query(description="add the association method's score matrix")
    ] = False,
    frame: OutputFrame = "session",
) -> JSONTextResponse:
    """One sensor's track list → the fused result of that step (acknowledged once logged).

    409 ``stale-report`` (with ``time`` and ``last_time``) for a report not
    newer than the sensor's previous one.
    """
    # refused before anything is applied
    origin = origin_of(session.config, "frame") if frame == "geodetic" else None
    result = await registry.submit_tracks(session, report, explain=explain)
    if origin is not None:
        result = geodetic_result(result, origin, session.config)
    return JSONTextResponse(result)


@router.post(
    "/{sid}/detections",
    response_model=StepResult,
    responses=problem_responses(401, 403, 404, 409, 413, 422, 503),
)
async def submit_detections(
    report: DetectionReport,
    session: LiveSessionDep,
    registry: RegistryDep,
    explain: Annotated[bool, Query(description="add the association score matrix")] = False,
    frame: OutputFrame = "session",
) -> JSONTextResponse:
    """One sensor's detections → the fused result of that step.

    The session's local tracker for that sensor (configured by its
    ``measurement`` model and ``tracking``) updates its tracks; its confirmed
    tracks updated by this scan enter the fusion step like a track list.
    409 ``stale-report`` when the batch is not newer than the sensor's
    previous input (scans may come at any increasing times, on no grid);
    422 for a sensor without a measurement model.
    """
    # refused before anything is applied
    origin = origin_of(session.config, "frame") if frame == "geodetic" else None
    result = await registry.submit_detections(session, report, explain=explain)
    if origin is not None:
        result = geodetic_result(result, origin, session.config)
    return JSONTextResponse(result)


@router.get(
    "/{sid}/tracks",
    response_model=FusedPicture,
    responses=problem_responses(401, 403, 404, 422, 503),
)
async def list_fused_tracks(
    session: CurrentSessionDep,
    registry: RegistryDep,
    time: Annotated[
        FiniteFloat | None,
        Query(description="predict the tracks to this time (default: the fusion time)"),
    ] = None,
    frame: OutputFrame = "session",
    format: Annotated[
        Literal["json", "geojson"],
        Query(description="geojson: an application/geo+json FeatureCollection (needs origin)"),
    ] = "json",
) -> Response:
    """The live fused tracks (not terminated), optionally predicted to ``time``.

    ``frame=geodetic`` adds ``geodetic: {lat, lon, alt}`` to each track;
    ``format=geojson`` answers a GeoJSON FeatureCollection of Point features
    (``[lon, lat, alt]``; id, status, decision, BetP and ENU velocity as
    properties). Both need the session's ``origin`` (else 422).
    """
    config = session.config
    if format == "geojson":
        origin = origin_of(config, "format")
        _, _, tracks = await registry.picture(session, time)
        collection = feature_collection(
            tracks, origin, tuple(config.state.position), tuple(config.state.velocity)
        )
        return Response(dumps(collection), media_type=GEOJSON_MEDIA_TYPE)
    if frame == "geodetic":
        origin = origin_of(config, "frame")
        seq, time_of, tracks = await registry.picture(session, time)
        geodetic = with_geodetic(tracks, origin, tuple(config.state.position))
        return JSONTextResponse(dumps({"seq": seq, "time": time_of, "tracks": geodetic}))
    return JSONTextResponse(await registry.picture_json(session, time))


@router.get(
    "/{sid}/tracks/{tid}",
    response_model=FusedTrackDetail,
    responses=problem_responses(401, 403, 404, 422, 503),
)
async def get_fused_track(
    tid: TrackId,
    session: CurrentSessionDep,
    registry: RegistryDep,
    frame: OutputFrame = "session",
) -> PlainJSONResponse:
    """One live fused track with its recent history (fused states, oldest first).

    ``frame=geodetic`` adds ``geodetic: {lat, lon, alt}`` to the track and to
    each history point (needs the session's ``origin``, else 422); their
    ``state`` stays in the session frame.
    """
    config = session.config
    origin = origin_of(config, "frame") if frame == "geodetic" else None
    detail = await registry.track_detail(session, tid)
    if detail is None:
        raise TrackNotFound(session.id, tid)
    if origin is not None:
        positions = tuple(config.state.position)
        (track,) = with_geodetic([detail["track"]], origin, positions)
        detail = {
            **detail,
            "track": track,
            "history": with_geodetic(detail["history"], origin, positions),
        }
    return PlainJSONResponse(detail)
