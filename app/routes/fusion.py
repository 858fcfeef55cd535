"""Inputs and the fused picture of a session: ``/v1/sessions/{sid}/tracks`` and ``…/detections``."""

from __future__ import annotations

import functools
from typing import Annotated, Literal

from fastapi import APIRouter, Header, Path, Query
from fastapi.responses import Response

from api_schemas.base import FiniteFloat
from api_schemas.config import SessionConfig
from api_schemas.issues import FieldIssue
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import FusedPicture, FusedTrackDetail, StepResult
from app.geo.geojson import GEOJSON_MEDIA_TYPE, GeodeticOutput, with_geodetic
from app.http.deps import CurrentSessionDep, LiveSessionDep, RegistryDep
from app.http.errors import (
    TrackNotFound,
    problem_responses,
    request_validation_error,
)
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse
from app.sessions.translate import picture_geojson, picture_json, session_geodetic, wire_json
from core.numerics import MAX_TIME

router = APIRouter(prefix="/v1/sessions", tags=["fusion"], route_class=WireRoute)

EXPLAIN = (
    "add the association's score matrix: (known + reported) × reported cells, at most "
    "max_explain_cells (422 before the work beyond)"
)
IdempotencyKey = Annotated[
    str | None,
    Header(
        alias="Idempotency-Key",
        min_length=1,
        max_length=128,
        pattern=r"^[!-~]+$",
        description="names this input: sent again with the same key (a retry after a lost "
        "answer), the same input is not applied twice, its first answer is given again (409 if "
        "the key came with another input); the session remembers its latest 256 keys",
    ),
]
TrackId = Annotated[str, Path(min_length=1, max_length=64, description="A fused track id.")]
OutputFrame = Annotated[
    Literal["session", "geodetic"],
    Query(description="geodetic: add geodetic {lat, lon, alt} to each fused track (needs origin)"),
]


def geodetic_output(config: SessionConfig, parameter: str) -> GeodeticOutput:
    """The session's origin frame, for geodetic positions, or a 422 at the query
    ``parameter``: the session has none."""
    geodetic = session_geodetic(config)
    if geodetic is None:
        raise request_validation_error(
            [FieldIssue((parameter,), "the session has no origin: geodetic output needs one")],
            prefix="query",
        )
    return geodetic


@router.post(
    "/{sid}/tracks",
    response_model=StepResult,
    responses=problem_responses(401, 403, 404, 409, 408, 413, 422, 503),
)
async def submit_tracks(
    report: TrackReport,
    session: LiveSessionDep,
    registry: RegistryDep,
    explain: Annotated[bool, Query(description=EXPLAIN)] = False,
    frame: OutputFrame = "session",
    idempotency_key: IdempotencyKey = None,
) -> JSONTextResponse:
    """One sensor's track list → the fused result of that step (acknowledged once logged).

    409 ``stale-report`` (with ``time`` and ``last_time``) for a report not
    newer than the sensor's previous one.
    """
    # refused before anything is applied
    geodetic = geodetic_output(session.config, "frame") if frame == "geodetic" else None
    return JSONTextResponse(
        await registry.submit(
            session, report, explain=explain, geodetic=geodetic, idempotency_key=idempotency_key
        )
    )


@router.post(
    "/{sid}/detections",
    response_model=StepResult,
    responses=problem_responses(401, 403, 404, 409, 408, 413, 422, 503),
)
async def submit_detections(
    report: DetectionReport,
    session: LiveSessionDep,
    registry: RegistryDep,
    explain: Annotated[bool, Query(description=EXPLAIN)] = False,
    frame: OutputFrame = "session",
    idempotency_key: IdempotencyKey = None,
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
    geodetic = geodetic_output(session.config, "frame") if frame == "geodetic" else None
    return JSONTextResponse(
        await registry.submit(
            session, report, explain=explain, geodetic=geodetic, idempotency_key=idempotency_key
        )
    )


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
        Query(
            ge=-MAX_TIME,
            le=MAX_TIME,
            description="predict the tracks to this time (default: the fusion time); at most "
            "1e12 s in magnitude, as the inputs' times",
        ),
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
        geodetic = geodetic_output(config, "format")
        velocity = tuple(config.state.velocity)
        text = await registry.picture(
            session, time, lambda _seq, _time, views: picture_geojson(views, geodetic, velocity)
        )
        return JSONTextResponse(text, media_type=GEOJSON_MEDIA_TYPE)
    if frame == "geodetic":
        write = functools.partial(picture_json, geodetic=geodetic_output(config, "frame"))
        return JSONTextResponse(await registry.picture(session, time, write))
    return JSONTextResponse(await registry.picture(session, time))


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
) -> JSONTextResponse:
    """One live fused track with its recent history (fused states, oldest first).

    ``frame=geodetic`` adds ``geodetic: {lat, lon, alt}`` to the track and to
    each history point (needs the session's ``origin``, else 422); their
    ``state`` stays in the session frame.
    """
    geodetic = geodetic_output(session.config, "frame") if frame == "geodetic" else None
    detail = await registry.track_detail(session, tid)
    if detail is None:
        raise TrackNotFound(session.id, tid)
    if geodetic is not None:
        (track,) = with_geodetic([detail["track"]], geodetic)
        detail = {
            **detail,
            "track": track,
            "history": with_geodetic(detail["history"], geodetic),
        }
    return JSONTextResponse(wire_json(detail))
