"""Stateless association: ``POST /v1/associate``."""

from __future__ import annotations

import functools

import anyio
from fastapi import APIRouter

from api_schemas.associate import AssociateRequest, AssociateResponse
from app.errors import problem_responses
from app.requests import WireRoute
from app.responses import PlainJSONResponse
from app.translate import PlainObject, associate_plain, class_frame, evidence_masses, side_arrays
from core.association import associate

router = APIRouter(tags=["association"], route_class=WireRoute)

TINY_PROBLEM = 256
"""known × incoming pairs up to which the association runs on the event loop."""


def run_association(request: AssociateRequest) -> PlainObject:
    """Associate ``known`` (rows) with ``incoming`` (columns) by the request's method."""
    tracks = request.known or request.incoming
    dim = len(tracks[0].state) if tracks else 1
    frame = class_frame(request.classes)
    carried = any(track.classification is not None for track in (*request.known, *request.incoming))
    known_classes = incoming_classes = None
    if frame is not None and carried:
        known_classes = evidence_masses(request.known, frame)
        incoming_classes = evidence_masses(request.incoming, frame)
    options = request.options.model_dump(exclude_none=True)
    distance = str(options.pop("distance", "sum"))
    result = associate(
        side_arrays(request.known, dim),
        side_arrays(request.incoming, dim),
        request.method,
        options,
        distance,
        known_classes,
        incoming_classes,
    )
    return associate_plain(request, result)


@router.post(
    "/v1/associate", response_model=AssociateResponse, responses=problem_responses(413, 422)
)
async def associate_tracks(request: AssociateRequest) -> PlainJSONResponse:
    """Two track lists and a method → the assignment with its score matrix (no session, no token)."""
    work = functools.partial(run_association, request)
    if len(request.known) * len(request.incoming) <= TINY_PROBLEM:
        return PlainJSONResponse(work())
    return PlainJSONResponse(await anyio.to_thread.run_sync(work))
