"""Session lifecycle and the event log (the engine-independent part of ``/v1/sessions``)."""

from __future__ import annotations

import uuid
from datetime import UTC, datetime
from http import HTTPStatus
from typing import Annotated

from fastapi import APIRouter, Query, Response

from api_schemas.config import SessionConfig
from api_schemas.events import EventLog
from api_schemas.sessions import SessionCreated, SessionList, SessionListItem
from app.deps import AdminDep, AuthorizedSession, MetricsDep, SettingsDep, StoreDep
from app.errors import LimitExceeded, problem_responses
from app.limits import check_config_limits
from app.security import hash_token, issue_token
from app.session_log import event_from_entry
from app.stores import SessionRecord

router = APIRouter(prefix="/v1/sessions", tags=["sessions"])

MAX_EVENTS_PAGE = 10_000


@router.post(
    "",
    status_code=HTTPStatus.CREATED,
    responses=problem_responses(400, 413, 422, 429),
)
def create_session(
    config: SessionConfig, settings: SettingsDep, store: StoreDep, metrics: MetricsDep
) -> SessionCreated:
    """Create a session from a config; returns its id, its token (shown only here) and the resolved config."""
    check_config_limits(config, settings)
    live = store.count_sessions()
    if live >= settings.max_sessions:
        raise LimitExceeded(
            "max_sessions",
            settings.max_sessions,
            live,
            what="sessions",
            status=HTTPStatus.TOO_MANY_REQUESTS,
        )
    token = issue_token()
    record = SessionRecord(
        id=uuid.uuid4().hex,
        config=config.model_dump(mode="json"),
        token_hash=hash_token(token),
        created_at=datetime.now(UTC),
    )
    store.create_session(record)
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
def delete_session(session: AuthorizedSession, store: StoreDep, metrics: MetricsDep) -> Response:
    """End a session: it no longer accepts inputs nor answers (its token stops working)."""
    store.delete_session(session.id)
    metrics.sessions.set(store.count_sessions())
    return Response(status_code=HTTPStatus.NO_CONTENT)


@router.get("/{sid}/events", responses=problem_responses(401, 403, 404, 422))
def list_session_events(
    session: AuthorizedSession,
    store: StoreDep,
    after: Annotated[int, Query(ge=0, description="only events with seq > after")] = 0,
    limit: Annotated[int, Query(ge=1, le=MAX_EVENTS_PAGE, description="page size")] = 1000,
) -> EventLog:
    """The accepted inputs in order (export and replay); page with ``after``."""
    entries = store.entries(session.id, after=after, limit=limit)
    return EventLog(
        session=session.id,
        events=[event_from_entry(entry) for entry in entries],
        last_seq=store.last_seq(session.id),
    )
