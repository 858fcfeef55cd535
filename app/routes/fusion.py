"""The fused picture of a session: ``GET /v1/sessions/{sid}/tracks`` and ``…/tracks/{tid}``
(its inputs: :mod:`app.routes.inputs`), and the output parameters every answer of fused tracks
takes: ``format`` (a registered output format, :mod:`app.outputs`) and ``frame``."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Path, Query

from api_schemas.config import SessionConfig
from api_schemas.issues import FieldIssue
from api_schemas.results import FusedTrackDetail
from api_schemas.timing import QueryTime, seconds
from app.errors import InvalidFields, TrackNotFound
from app.geo.geojson import with_geodetic
from app.http.deps import CurrentSessionDep, RegistryDep
from app.http.errors import problem_responses
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse
from app.outputs import FRAMES, OUTPUT_FORMATS, Output, output_for
from app.outputs.json_results import wire_json
from app.sessions.translate import session_geodetic

router = APIRouter(prefix="/v1/sessions", tags=["fusion"], route_class=WireRoute)

SCHEMA_REF = "#/components/schemas/{model}"
TrackId = Annotated[str, Path(min_length=1, max_length=64, description="A fused track id.")]
OutputFrame = Annotated[
    str,
    Query(
        description="geodetic: add geodetic {lat, lon, alt} to each fused track (needs origin)",
        json_schema_extra={"enum": list(FRAMES)},
    ),
]
OutputFormat = Annotated[
    str,
    Query(
        description="; ".join(f"{name}: {f.description}" for name, f in OUTPUT_FORMATS.items()),
        json_schema_extra={"enum": list(OUTPUT_FORMATS)},
    ),
]


def output_of(config: SessionConfig, format: str = "json", frame: str = "session") -> Output:
    """The output asked (``format``, ``frame``) of a session with ``config`` (422 at the query
    parameter it cannot have: :func:`app.outputs.output_for`)."""
    return output_for(session_geodetic(config), format, frame)


def output_responses(
    answer: Literal["step", "picture"], *statuses: int
) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses``: the problems, and the 200 answer under every registered format's
    media type. The answer's shape depends on ``format`` (a query parameter, which OpenAPI
    cannot tie a schema to), so each media type lists the formats' models as ``oneOf``, the
    route's ``response_model`` first: a generated client reads every format."""
    models = [
        output.step_model if answer == "step" else output.picture_model
        for output in OUTPUT_FORMATS.values()
    ]
    schema = {"oneOf": [{"$ref": SCHEMA_REF.format(model=model.__name__)} for model in models]}
    content = {output.media_type: {"schema": schema} for output in OUTPUT_FORMATS.values()}
    described = ", ".join(
        f"{name}: {model.__name__} ({output.media_type})"
        for (name, output), model in zip(OUTPUT_FORMATS.items(), models, strict=True)
    )
    return {
        **problem_responses(*statuses),
        200: {"description": f"The answer in the format asked ({described})", "content": content},
    }


@router.get(
    "/{sid}/tracks",
    response_model=None,  # the formats' models: output_responses
    responses=output_responses("picture", 401, 403, 404, 422, 503),
)
async def list_fused_tracks(
    session: CurrentSessionDep,
    registry: RegistryDep,
    time: Annotated[
        QueryTime | None,
        Query(
            description="predict the tracks to this time (default: the fusion time): seconds "
            "(at most 1e12 in magnitude, as the inputs' times) or, in a session whose inputs "
            "gave RFC 3339 timestamps (time_epoch unix), a timestamp too",
        ),
    ] = None,
    frame: OutputFrame = "session",
    format: OutputFormat = "json",
) -> JSONTextResponse:
    """The live fused tracks (not terminated), optionally predicted to ``time``.

    ``frame=geodetic`` adds ``geodetic: {lat, lon, alt}`` to each track;
    ``format=geojson`` answers a GeoJSON FeatureCollection of Point features
    (``[lon, lat, alt]``; id, status, decision, BetP and ENU velocity as
    properties). Both need the session's ``origin`` (else 422).
    """
    output = output_of(session.config, format, frame)
    if isinstance(time, str) and session.time_epoch == "arbitrary":
        raise InvalidFields(
            [
                FieldIssue(
                    ("time",),
                    "this session's times are seconds of its own epoch (its inputs gave "
                    f"numbers): ask for a time in seconds, not the timestamp {time!r}",
                    time,
                )
            ],
            prefix="query",
        )
    at = None if time is None else seconds(time)
    text = await registry.picture(session, at, output)
    return JSONTextResponse(text, media_type=output.media_type)


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
    geodetic = output_of(session.config, "json", frame).geodetic
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
