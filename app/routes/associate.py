"""Stateless association: ``POST /v1/associate``."""

from __future__ import annotations

import functools

import anyio
from fastapi import APIRouter

from api_schemas.associate import AssociateRequest, AssociateResponse
from api_schemas.examples import ASSOCIATE_EXAMPLES, json_body_examples
from app.http.deps import RegistryDep, SettingsDep, TenantDep
from app.http.errors import LimitExceeded, problem_responses
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse, dumps
from app.runtime import without_collection
from app.sessions.translate import (
    PlainObject,
    associate_plain,
    class_frame,
    evidence_masses,
    side_arrays,
)
from app.settings import Settings
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
    "/v1/associate",
    response_model=AssociateResponse,
    responses=problem_responses(401, 408, 413, 422, 503),
    openapi_extra=json_body_examples(ASSOCIATE_EXAMPLES),
)
async def associate_tracks(
    request: AssociateRequest, tenant: TenantDep, settings: SettingsDep, registry: RegistryDep
) -> JSONTextResponse:
    """Two track lists and a method → the assignment with its score matrix (no session).

    Needs an API key in ``keys`` mode (as creating a session does); its known ×
    incoming pairs count against the tenant's ``tenant_work_per_minute``.
    422 ``limit-exceeded`` when known × incoming exceeds ``max_associate_pairs``
    (``max_associate_class_pairs`` when the tracks carry class evidence).
    """
    check_pairs(request, settings)
    await registry.quotas.charge(tenant, len(request.known) * len(request.incoming))
    work = functools.partial(run_association, request)
    if len(request.known) * len(request.incoming) <= TINY_PROBLEM:
        return JSONTextResponse(dumps(work()))
    return JSONTextResponse(
        await anyio.to_thread.run_sync(without_collection(lambda: dumps(work())))
    )


def check_pairs(request: AssociateRequest, settings: Settings) -> None:
    """known × incoming within the pair limits, checked before any work."""
    pairs = len(request.known) * len(request.incoming)
    carried = bool(request.classes) and any(
        track.classification is not None for track in (*request.known, *request.incoming)
    )
    limit = "max_associate_class_pairs" if carried else "max_associate_pairs"
    maximum = settings.max_associate_class_pairs if carried else settings.max_associate_pairs
    if pairs > maximum:
        raise LimitExceeded(limit, maximum, pairs, what="known × incoming pairs", loc=("incoming",))
