"""Inputs and the fused picture of a session: ``/v1/sessions/{sid}/tracks`` and ``…/detections``."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Query

from api_schemas.base import FiniteFloat
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import FusedPicture, FusedTrackDetail, StepResult
from app.deps import CurrentSessionDep, LiveSessionDep, RegistryDep
from app.errors import (
    TrackNotFound,
    problem_responses,
)
from app.requests import WireRoute
from app.responses import JSONTextResponse, PlainJSONResponse

router = APIRouter(prefix="/v1/sessions", tags=["fusion"], route_class=WireRoute)

TrackId = Annotated[str, Path(min_length=1, max_length=64, description="A fused track id.")]


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
) -> JSONTextResponse:
    """One sensor's track list → the fused result of that step (acknowledged once logged).

    409 ``stale-report`` (with ``time`` and ``last_time``) for a report not
    newer than the sensor's previous one.
    """
    result = await registry.submit_tracks(session, report, explain=explain)
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
) -> JSONTextResponse:
    """One sensor's detections → the fused result of that step.

    The session's local tracker for that sensor (configured by its
    ``measurement`` model and ``tracking``) updates its tracks; its confirmed
    tracks updated by this scan enter the fusion step like a track list.
    409 ``stale-report`` when the batch is not newer than the sensor's
    previous input (scans may come at any increasing times, on no grid);
    422 for a sensor without a measurement model.
    """
    result = await registry.submit_detections(session, report, explain=explain)
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
) -> JSONTextResponse:
    """The live fused tracks (not terminated), optionally predicted to ``time``."""
    return JSONTextResponse(await registry.picture_json(session, time))


@router.get(
    "/{sid}/tracks/{tid}",
    response_model=FusedTrackDetail,
    responses=problem_responses(401, 403, 404, 503),
)
async def get_fused_track(
    tid: TrackId, session: CurrentSessionDep, registry: RegistryDep
) -> PlainJSONResponse:
    """One live fused track with its recent history (fused states, oldest first)."""
    detail = await registry.track_detail(session, tid)
    if detail is None:
        raise TrackNotFound(session.id, tid)
    return PlainJSONResponse(detail)
