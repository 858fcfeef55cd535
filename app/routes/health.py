"""Liveness (``/healthz``) and readiness (``/readyz``).

``/healthz`` says the process is up (a restart would not help while the
store is down, so it stays 200); ``/readyz`` says whether the service can
take inputs now: the store answers a ping (and, with the redis store, the
pub/sub connection too). Not ready is 503 with ``Retry-After``; it turns
ready again by itself once the store is back.
"""

from __future__ import annotations

from collections.abc import Awaitable
from http import HTTPStatus
from typing import Literal

import anyio
from fastapi import APIRouter, Request

from api_schemas.health import ComponentState, Health, Readiness
from app.http.errors import StoreUnavailable
from app.http.requests import WireRoute
from app.http.responses import JSONTextResponse, PlainJSONResponse
from app.sessions.registry import SessionRegistry
from core import __version__

router = APIRouter(tags=["health"], route_class=WireRoute)

Component = Literal["store", "fanout"]
PING_TIMEOUT_S = 2.0
"""A store that has not answered a ping by then is not ready (the Redis store's command
timeout: a frozen Redis is told within it)."""


HEALTH = Health(version=__version__).model_dump_json().encode()
"""The answer of ``/healthz``, serialised once: a probe polled every few ms costs routing only."""


@router.get("/healthz", operation_id="get_health", response_model=Health)
async def get_health() -> JSONTextResponse:
    """Liveness and version; needs no token. Answered on the event loop itself (no thread
    hop, nothing awaited, its text written once): it answers as fast as the loop is free
    (``credal_event_loop_lag_seconds``)."""
    return JSONTextResponse(HEALTH)


async def _state(name: Component, ping: Awaitable[None]) -> ComponentState:
    """Whether ``ping`` answers within :data:`PING_TIMEOUT_S`."""
    try:
        with anyio.fail_after(PING_TIMEOUT_S):
            await ping
    except StoreUnavailable as error:
        return ComponentState(name=name, ready=False, detail=error.detail)
    except TimeoutError:
        return ComponentState(name=name, ready=False, detail=f"no answer in {PING_TIMEOUT_S} s")
    return ComponentState(name=name, ready=True)


@router.get(
    "/readyz",
    operation_id="get_readiness",
    response_model=Readiness,
    responses={503: {"model": Readiness, "description": "Not ready (``Retry-After``)"}},
)
async def get_readiness(request: Request) -> PlainJSONResponse:
    """Whether the service can take inputs now: the store (and its pub/sub) answers; no token."""
    registry: SessionRegistry = request.app.state.registry
    store = registry.store
    pings: list[tuple[Component, Awaitable[None]]] = []
    if registry.store_corrupt is None:  # else permanent: no ping will mend it
        # abandoned at the timeout: a frozen store's ping answers nothing until it thaws
        pings.append(("store", anyio.to_thread.run_sync(store.ping, abandon_on_cancel=True)))
    if registry.shared:
        pings.append(("fanout", registry.fanout.ping()))
    states: dict[str, ComponentState] = {}

    async def check(name: Component, ping: Awaitable[None]) -> None:
        states[name] = await _state(name, ping)

    async with anyio.create_task_group() as tasks:  # at the same time: one timeout in all
        for name, ping in pings:
            tasks.start_soon(check, name, ping)
    components = [states[name] for name, _ in pings]
    if registry.store_corrupt is not None:
        components.insert(
            0, ComponentState(name="store", ready=False, detail=registry.store_corrupt)
        )
    readiness = Readiness(
        ready=all(component.ready for component in components),
        store=store.kind,
        components=components,
        leases_held=registry.leases_held(),
        quarantined=sorted(registry.quarantined),
    )
    return PlainJSONResponse(
        readiness.model_dump(mode="json"),
        status_code=HTTPStatus.OK if readiness.ready else HTTPStatus.SERVICE_UNAVAILABLE,
        headers={}
        if readiness.ready or registry.store_corrupt is not None  # permanent: no retry time
        else {"Retry-After": str(StoreUnavailable.retry_after_s)},
    )
