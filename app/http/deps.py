"""FastAPI dependencies, as ``Annotated`` aliases used in route signatures."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Path, Request
from fastapi.openapi.models import HTTPBearer as HTTPBearerModel
from fastapi.security.base import SecurityBase
from fastapi.security.utils import get_authorization_scheme_param
from starlette.requests import HTTPConnection

from app.http.errors import Forbidden, SessionNotFound, SessionUnreadable, Unauthorized
from app.http.security import Principal, is_admin_token, token_matches
from app.http.tenants import Tenancy
from app.metrics import ServiceMetrics
from app.sessions.live import LiveSession
from app.sessions.registry import SessionRegistry
from app.settings import Settings
from app.stores import SessionRecord, Store


class BearerTokenScheme(SecurityBase):
    """The ``HTTPBearer`` security scheme as a dependency that gives the token (401 without one).

    It reads the header as FastAPI's ``HTTPBearer`` does and documents the same
    scheme, but it is one dependency where ``HTTPBearer`` and a check of its
    result were two: FastAPI resolves every dependency anew on each request.
    """

    def __init__(self, description: str) -> None:
        self.model = HTTPBearerModel(description=description)
        self.scheme_name = "HTTPBearer"

    async def __call__(self, request: HTTPConnection) -> str:
        scheme, token = get_authorization_scheme_param(request.headers.get("Authorization"))
        if scheme.lower() != "bearer" or not token:
            raise Unauthorized("send 'Authorization: Bearer <token>'")
        return token


bearer_token = BearerTokenScheme(
    "The session's token (returned once by POST /v1/sessions) or the admin token."
)


def _settings_of(request: Request) -> Settings:
    settings: Settings = request.app.state.settings
    return settings


def _registry_of(request: Request) -> SessionRegistry:
    registry: SessionRegistry = request.app.state.registry
    return registry


async def get_app_settings(request: Request) -> Settings:
    """The settings the application was built with."""
    return _settings_of(request)


async def get_store(request: Request) -> Store:
    """The application's store."""
    store: Store = request.app.state.store
    return store


async def get_metrics(request: Request) -> ServiceMetrics:
    """The application's metrics."""
    metrics: ServiceMetrics = request.app.state.metrics
    return metrics


async def get_registry(request: Request) -> SessionRegistry:
    """The application's live sessions."""
    return _registry_of(request)


SettingsDep = Annotated[Settings, Depends(get_app_settings)]
RegistryDep = Annotated[SessionRegistry, Depends(get_registry)]
StoreDep = Annotated[Store, Depends(get_store)]
MetricsDep = Annotated[ServiceMetrics, Depends(get_metrics)]
SessionId = Annotated[str, Path(min_length=1, max_length=64, description="The session id.")]


BearerToken = Annotated[str, Depends(bearer_token)]


def _admin_token(settings: Settings) -> str | None:
    return settings.admin_token.get_secret_value() if settings.admin_token is not None else None


async def require_admin(token: BearerToken, settings: SettingsDep) -> Principal:
    """Admin routes: only the admin token (403 for any other token)."""
    admin_token = _admin_token(settings)
    if admin_token is None:
        raise Forbidden(
            "this route needs the admin token, and this service has none: start it with the "
            "environment variable CREDAL_ADMIN_TOKEN set (at least 32 visible ASCII "
            "characters), then send it as 'Authorization: Bearer <CREDAL_ADMIN_TOKEN>'"
        )
    if not is_admin_token(token, admin_token):
        raise Forbidden(
            "this route needs the admin token: the value of the environment variable "
            "CREDAL_ADMIN_TOKEN the service runs with, as 'Authorization: Bearer "
            "<CREDAL_ADMIN_TOKEN>' (a session's token opens its own session only)"
        )
    return Principal(admin=True)


def open_record(
    sid: str, record: SessionRecord | None, token: str, settings: Settings
) -> SessionRecord:
    """The session ``sid`` if ``token`` opens it: its own token or the admin token.

    404 alike for an unknown session and for a token that does not open it (another
    session's token included): a token cannot tell which sessions exist.
    """
    if record is not None and (
        token_matches(token, record.token_hash) or is_admin_token(token, _admin_token(settings))
    ):
        return record
    raise SessionNotFound(sid)


async def authorize_session(sid: SessionId, token: BearerToken, request: Request) -> SessionRecord:
    """The session ``sid`` if the token opens it (401 without a token; see :func:`open_record`).

    Live sessions are checked in memory; the store is read (off the event loop) only for
    a session the registry does not hold. The settings and the registry are read from
    the application here rather than as sub-dependencies: FastAPI resolves every
    sub-dependency anew on each request, and these two never change.
    """
    record = await _registry_of(request).record(sid)
    return open_record(sid, record, token, _settings_of(request))


async def creator_tenant(request: Request) -> str:
    """The tenant a session-creating request acts for (its API key's; in open mode without a
    key, its address's): 401 without a valid key in ``keys`` mode (:mod:`app.http.tenants`)."""
    tenancy: Tenancy = request.app.state.tenancy
    client = request.client.host if request.client is not None else None
    return tenancy.creator(request.headers.get("authorization"), client)


TenantDep = Annotated[str, Depends(creator_tenant)]


async def deletable_session(sid: SessionId, token: BearerToken, request: Request) -> str:
    """The id of a session the token may delete: :func:`authorize_session`, or a quarantined
    session (unreadable: its token cannot be checked) with the admin token."""
    try:
        return (await authorize_session(sid, token, request)).id
    except SessionUnreadable:
        if is_admin_token(token, _admin_token(_settings_of(request))):
            return sid
        raise


AdminDep = Annotated[Principal, Depends(require_admin)]
AuthorizedSession = Annotated[SessionRecord, Depends(authorize_session)]
DeletableSession = Annotated[str, Depends(deletable_session)]


async def live_session(sid: SessionId, token: BearerToken, request: Request) -> LiveSession:
    """The authorized session with its engine (the checks of :func:`authorize_session`)."""
    record = await authorize_session(sid, token, request)
    return await _registry_of(request).get(record.id)


LiveSessionDep = Annotated[LiveSession, Depends(live_session)]


async def current_session(sid: SessionId, token: BearerToken, request: Request) -> LiveSession:
    """The authorized session at the store's latest state, for reads (no stale ``seq`` when
    several instances share the store: :meth:`~app.sessions.registry.SessionRegistry.current`)."""
    session = await live_session(sid, token, request)
    return await _registry_of(request).current(session)


CurrentSessionDep = Annotated[LiveSession, Depends(current_session)]
