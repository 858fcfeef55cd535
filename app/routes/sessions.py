"""Session lifecycle, summary and the event log (``/v1/sessions``)."""

from __future__ import annotations

import uuid
from datetime import UTC, datetime
from http import HTTPStatus
from typing import Annotated

from fastapi import APIRouter, Query, Response

from api_schemas.config import SessionConfig
from api_schemas.events import EventLog, SnapshotEvent
from api_schemas.examples import SESSION_EXAMPLES, json_body_examples
from api_schemas.sessions import (
    DetectionTally,
    SensorActivity,
    SessionCreated,
    SessionList,
    SessionListItem,
    SessionSummary,
    TrackCounts,
)
from app.http.deps import (
    AdminDep,
    AuthorizedSession,
    CurrentSessionDep,
    DeletableSession,
    MetricsDep,
    RegistryDep,
    SettingsDep,
    StoreDep,
    TenantDep,
)
from app.http.errors import problem_responses
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse, dumps, itemwise
from app.http.security import hash_token, issue_token
from app.plausibility import config_warnings, site_placements
from app.runtime import collection_paused
from app.sessions.live import LiveSession, new_session
from app.sessions.log import event_json
from app.stores import SessionRecord, Store
from app.stores.base import history

router = APIRouter(prefix="/v1/sessions", tags=["sessions"], route_class=WireRoute)

MAX_EVENTS_PAGE = 10_000
MAX_SEQ = 2**53
"""Sequence numbers stay below 2⁵³ (exact in every JSON reader; SQLite's INTEGER holds them)."""


@router.post(
    "",
    status_code=HTTPStatus.CREATED,
    response_model=SessionCreated,
    responses=problem_responses(400, 401, 408, 413, 422, 429, 503),
    openapi_extra=json_body_examples(SESSION_EXAMPLES),
)
def create_session(
    config: SessionConfig,
    tenant: TenantDep,
    settings: SettingsDep,
    store: StoreDep,
    registry: RegistryDep,
    metrics: MetricsDep,
) -> JSONTextResponse:
    """Create a session from a config; returns its id, its token (shown only here) and the resolved config.

    The session belongs to the tenant of the request (its API key's; in open mode
    without a key, its client address's): 401 without a valid key in ``keys`` mode,
    429 with ``Retry-After`` beyond ``tenant_max_sessions`` or ``max_sessions``.
    """
    token = issue_token()
    record = SessionRecord(
        id=uuid.uuid4().hex,
        config=config.model_dump(mode="json"),
        token_hash=hash_token(token),
        created_at=datetime.now(UTC),
        tenant=tenant,
    )
    session = new_session(record, config)  # converted once; a config the engine refuses: 422
    # counted and created in one step of the store: instances sharing it keep the limits
    store.create_session(
        record,
        max_sessions=settings.max_sessions,
        max_tenant_sessions=settings.tenant_max_sessions,
    )
    registry.add(session)
    metrics.sessions.set(store.count_sessions())
    # the validated config as it is (constructing the answer would validate it once more)
    created = SessionCreated.model_construct(
        id=record.id,
        token=token,
        config=config,
        created_at=record.created_at,
        sites=site_placements(config),
        warnings=config_warnings(config),
    )
    # written here, in the worker thread: the resolved config of 64 fields of view is ~1 MB
    return JSONTextResponse(created.model_dump_json(), status_code=HTTPStatus.CREATED)


@router.get("", responses=problem_responses(401, 403, 503))
def list_sessions(_admin: AdminDep, store: StoreDep) -> SessionList:
    """Every live session (admin token only)."""
    items = [
        SessionListItem(
            id=record.id,
            name=record.config.get("name"),
            created_at=record.created_at,
            seq=store.last_seq(record.id),
        )
        for record in store.list_sessions()
    ]
    return SessionList(sessions=items)


@router.delete(
    "/{sid}",
    status_code=HTTPStatus.NO_CONTENT,
    response_class=Response,
    responses=problem_responses(401, 403, 404, 503),
)
async def delete_session(session: DeletableSession, registry: RegistryDep) -> Response:
    """End a session: it no longer accepts inputs nor answers (its token stops working).

    A quarantined session (``GET /readyz`` lists them: the store cannot read it)
    is deleted with the admin token."""
    await registry.delete(session)
    return Response(status_code=HTTPStatus.NO_CONTENT)


def summary(session: LiveSession) -> SessionSummary:
    """What ``GET /v1/sessions/{sid}`` says about a live session."""
    statuses = [track.status.value for track in session.tracks]
    return SessionSummary(
        id=session.id,
        name=session.config.name,
        created_at=session.record.created_at,
        last_input_at=session.last_input_at,
        config=session.config,
        seq=session.seq,
        time=session.time,
        time_epoch=session.time_epoch,
        sensors=[
            SensorActivity(
                id=sensor,
                inputs=session.sensor_inputs.get(sensor, 0),
                last_time=session.last_time(sensor),
                detections=detection_tally(session, sensor),
            )
            for sensor in session.sensor_ids()
        ],
        counts=TrackCounts(
            tentative=statuses.count("tentative"),
            confirmed=statuses.count("confirmed"),
            coasting=statuses.count("coasting"),
            phantom=statuses.count("phantom"),
            terminated=session.created_tracks - len(statuses),
        ),
        sites=site_placements(session.config),
        warnings=config_warnings(session.config),
    )


def detection_tally(session: LiveSession, sensor: str) -> DetectionTally | None:
    """A detecting sensor's tally and clutter density (docs/algorithms.md §8.8)."""
    tracker = None if session.engine is None else session.engine.tracker_of(sensor)
    if tracker is None:
        return None
    tally = tracker.tallies[sensor].to_plain()
    return DetectionTally(**tally, clutter_density=tracker.clutter_density(sensor))


@router.get("/{sid}", responses=problem_responses(401, 403, 404, 503))
async def get_session(session: CurrentSessionDep) -> SessionSummary:
    """The session's summary: config, sensors with their activity, track counts, time and seq."""
    async with session.lock:
        return summary(session)


MAX_EVENTS_PAGE_BYTES = 4 * 1024 * 1024
"""A page of events stops once its events reach this size (at least one event is given)."""


@router.get(
    "/{sid}/events",
    response_model=EventLog,
    responses=problem_responses(401, 403, 404, 422, 503),
)
def list_session_events(
    session: AuthorizedSession,
    store: StoreDep,
    after: Annotated[int, Query(ge=0, le=MAX_SEQ, description="only events with seq > after")] = 0,
    limit: Annotated[int, Query(ge=1, le=MAX_EVENTS_PAGE, description="page size")] = 1000,
) -> JSONTextResponse:
    """The accepted inputs in order (export and replay); page with ``after``.

    The log keeps ``log_retention`` inputs behind the latest snapshot; a page
    whose ``after`` is older starts with that ``snapshot``, then the inputs
    after it, so every page sequence from ``after=0`` replays the session.
    A page holds at most ``limit`` events and stops after 4 MiB of events (at
    least one is always given): continue with ``after`` = the last event's
    ``seq`` until it reaches ``last_seq``. Built in a worker thread, as JSON text.
    """
    with collection_paused():  # a page's parsed inputs: hundreds of thousands of containers
        return JSONTextResponse(events_page(store, session.id, after, limit))


def events_page(store: Store, session_id: str, after: int, limit: int) -> str:
    """The JSON text of an ``EventLog`` page (see :func:`list_session_events`)."""
    page = history(store, session_id, after, limit)
    events: list[str] = []
    size = 0
    for entry in page.entries:
        text = event_json(entry)
        if events and size + len(text) > MAX_EVENTS_PAGE_BYTES:
            break
        events.append(text)
        size += len(text) + 1
    parts = [
        f'"session":{dumps(session_id)}',
        f'"events":[{",".join(events)}]',
        f'"last_seq":{page.last_seq}',
    ]
    snapshot = page.snapshot
    if snapshot is not None:  # the state as stored, not validated again
        shown = SnapshotEvent.model_construct(
            type="snapshot", seq=snapshot.seq, taken_at=snapshot.taken_at, state=snapshot.state
        ).model_dump(mode="json")
        parts.append(f'"snapshot":{itemwise(shown)}')
    return "{" + ",".join(parts) + "}"
