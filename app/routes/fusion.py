"""Inputs and the fused picture of a session: ``POST /v1/sessions/{sid}/{tag}`` for every\ninput kind (:mod:`app.inputs`), ``GET …/tracks`` and ``GET …/tracks/{tid}``."""

from __future__ import annotations

import functools
from typing import Annotated, Literal

from fastapi import APIRouter, Path, Query
from fastapi.responses import Response

from api_schemas.base import FiniteFloat
from api_schemas.config import SessionConfig
from api_schemas.issues import FieldIssue
from api_schemas.results import FusedPicture, FusedTrackDetail
from app.geo.geojson import GEOJSON_MEDIA_TYPE, GeodeticOutput, with_geodetic
from app.http.deps import CurrentSessionDep, RegistryDep
from app.http.errors import (
    InvalidFields,
    TrackNotFound,
    problem_responses,
)
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse
from app.sessions.translate import picture_geojson, picture_json, session_geodetic, wire_json

router = APIRouter(prefix="/v1/sessions", tags=["fusion"], route_class=WireRoute)

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
        raise InvalidFields(
            [FieldIssue((parameter,), "the session has no origin: geodetic output needs one")],
            prefix="query",
        )
    return geodetic


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
