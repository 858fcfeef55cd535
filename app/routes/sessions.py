"""Session lifecycle, summary and the event log (``/v1/sessions``)."""

from __future__ import annotations

import uuid
from datetime import UTC, datetime
from http import HTTPStatus
from typing import Annotated

from fastapi import APIRouter, Query, Response

from api_schemas.config import SessionConfig
from api_schemas.events import EventLog
from api_schemas.sessions import (
    SensorActivity,
    SessionCreated,
    SessionList,
    SessionListItem,
    SessionSummary,
    TrackCounts,
)
from app.deps import (
    AdminDep,
    AuthorizedSession,
    LiveSessionDep,
    MetricsDep,
    RegistryDep,
    SettingsDep,
    StoreDep,
)
from app.errors import LimitExceeded, problem_responses
from app.live_session import LiveSession
from app.requests import WireRoute
from app.security import hash_token, issue_token
from app.session_log import event_from_entry
from app.stores import SessionRecord

router = APIRouter(prefix="/v1/sessions", tags=["sessions"], route_class=WireRoute)

MAX_EVENTS_PAGE = 10_000
MAX_SEQ = 2**53
"""Sequence numbers stay below 2⁵³ (exact in every JSON reader; SQLite's INTEGER holds them)."""


@router.post(
    "",
    status_code=HTTPStatus.CREATED,
    responses=problem_responses(400, 413, 422, 429),
)
def create_session(
    config: SessionConfig,
    settings: SettingsDep,
    store: StoreDep,
    registry: RegistryDep,
    metrics: MetricsDep,
) -> SessionCreated:
    """Create a session from a config; returns its id, its token (shown only here) and the resolved config."""
    registry.check_config(config)
    token = issue_token()
    record = SessionRecord(
        id=uuid.uuid4().hex,
        config=config.model_dump(mode="json"),
        token_hash=hash_token(token),
        created_at=datetime.now(UTC),
    )
    with registry.creating:  # count and create as one step (this instance's requests)
        live = store.count_sessions()
        if live >= settings.max_sessions:
            raise LimitExceeded(
                "max_sessions",
                settings.max_sessions,
                live,
                what="sessions",
                status=HTTPStatus.TOO_MANY_REQUESTS,
            )
        store.create_session(record)
        registry.add(record)
    metrics.sessions.set(store.count_sessions())
    return SessionCreated(id=record.id, token=token, config=config, created_at=record.created_at)


@router.get("", responses=problem_responses(401, 403))
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
    responses=problem_responses(401, 403, 404),
)
async def delete_session(session: AuthorizedSession, registry: RegistryDep) -> Response:
    """End a session: it no longer accepts inputs nor answers (its token stops working)."""
    await registry.delete(session.id)
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
        sensors=[
            SensorActivity(
                id=sensor,
                inputs=session.sensor_inputs.get(sensor, 0),
                last_time=session.last_time(sensor),
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
    )


@router.get("/{sid}", responses=problem_responses(401, 403, 404))
async def get_session(session: LiveSessionDep) -> SessionSummary:
    """The session's summary: config, sensors with their activity, track counts, time and seq."""
    async with session.lock:
        return summary(session)


@router.get("/{sid}/events", responses=problem_responses(401, 403, 404, 422))
def list_session_events(
    session: AuthorizedSession,
    store: StoreDep,
    after: Annotated[int, Query(ge=0, le=MAX_SEQ, description="only events with seq > after")] = 0,
    limit: Annotated[int, Query(ge=1, le=MAX_EVENTS_PAGE, description="page size")] = 1000,
) -> EventLog:
    """The accepted inputs in order (export and replay); page with ``after``."""
    entries = store.entries(session.id, after=after, limit=limit)
    return EventLog(
        session=session.id,
        events=[event_from_entry(entry) for entry in entries],
        last_seq=store.last_seq(session.id),
    )
