"""The FastAPI application factory."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import sys
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI, Request, Response
from fastapi.middleware.cors import CORSMiddleware
from fastapi.routing import APIRoute
from starlette.types import ASGIApp

from app.cluster.peers import WorkerGroup
from app.http.body_limits import BodyLimits
from app.http.errors import (
    SessionUnreadable,
    StoreCorrupt,
    StoreUnavailable,
    install_error_handlers,
    problem_answer,
)
from app.http.front import FrontDoor
from app.http.security import SecurityHeaders
from app.http.tenants import tenancy_of
from app.metrics import HttpMetrics, ServiceMetrics
from app.openapi import install_openapi
from app.routes import (
    associate,
    docs,
    fusion,
    health,
    inputs,
    metrics,
    sessions,
    streams,
    viewer,
)
from app.runtime import CollectionTimes, LoopLag
from app.sessions.registry import SessionRegistry
from app.settings import Settings, get_settings, parse_rates
from app.stores import open_store
from core import __version__

GIL_SWITCH_INTERVAL_S = 0.0005
"""How long a worker thread (a fusion step) may hold the GIL before the event loop gets it.

Python's default is 5 ms; the event loop needs the GIL at every await of an
answer, so a step in a worker thread delayed ``/healthz`` by hundreds of ms.
"""


logger = logging.getLogger("credal_fusion.main")


def operation_id(route: APIRoute) -> str:
    """Operation ids are the route functions' names (they become SDK method names)."""
    return route.name


def create_app(settings: Settings | None = None, workers: WorkerGroup | None = None) -> FastAPI:
    """Build the service application (the store opens in the lifespan, not here); ``workers``:
    the group of worker processes this one belongs to (``serve --workers``), sharing the store."""
    settings = settings or get_settings()
    service_metrics = ServiceMetrics.create()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        sys.setswitchinterval(GIL_SWITCH_INTERVAL_S)
        app.openapi()  # built before serving: the first GET /openapi.json held the loop 250 ms
        store = open_store(
            settings.store,
            redis_prefix=settings.redis_prefix,
            sqlite_synchronous=settings.sqlite_synchronous,
        )
        app.state.store = store
        loop_lag = LoopLag(service_metrics.loop_lag, ceiling=2e-3 * settings.overload_delay_ms)
        shared = {} if workers is None else await workers.join(store, settings)
        registry = SessionRegistry(store, settings, service_metrics, loop_lag=loop_lag, **shared)
        app.state.registry = registry
        collections = CollectionTimes(service_metrics.collections)
        collections.install()
        tasks = [
            asyncio.create_task(registry.run_expiry(), name="session-expiry"),
            asyncio.create_task(loop_lag.run(), name="loop-lag"),
        ]
        # a store that answers is restored before the first request; one that is down is
        # retried in the background (the process starts and answers /healthz meanwhile)
        try:
            await registry.restore_all()
            service_metrics.sessions.set(store.count_sessions())
        except StoreUnavailable as error:
            logger.warning("serving without the store for now: %s", error.detail)
            tasks.append(asyncio.create_task(registry.restore_when_available(), name="restore"))
        except StoreCorrupt as error:  # permanent: serve, say so (/readyz), never retry
            registry.store_corrupt = error.detail
            logger.error("serving with a damaged store: %s", error.detail)
        try:
            yield
        finally:
            for task in tasks:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            await registry.aclose()
            store.close()
            collections.remove()

    app = FastAPI(
        title="credal-fusion",
        version=__version__,
        description="Multi-sensor track fusion with belief-function association and classification.",
        lifespan=lifespan,
        generate_unique_id_function=operation_id,
        docs_url=None,  # app.routes.docs serves /docs and /redoc with local assets
        redoc_url=None,
    )
    app.state.settings = settings
    app.state.tenancy = tenancy_of(settings)
    app.state.metrics = service_metrics
    install_error_handlers(app, service_metrics.internal_errors.inc)

    async def unreadable(request: Request, error: Exception) -> Response:
        """A session found unreadable (wherever it was read) is quarantined, then answered."""
        registry: SessionRegistry = request.app.state.registry
        if isinstance(error, SessionUnreadable):
            registry.quarantine(error)
        elif isinstance(error, StoreCorrupt):
            registry.store_corrupt = error.detail
        return problem_answer(request, error)

    app.add_exception_handler(SessionUnreadable, unreadable)
    app.add_exception_handler(StoreCorrupt, unreadable)
    app.include_router(health.router)
    app.include_router(metrics.router)
    app.include_router(sessions.router)
    app.include_router(inputs.input_routes())
    app.include_router(fusion.router)
    app.include_router(associate.router)
    app.include_router(streams.router)
    app.include_router(viewer.router)
    docs.install_docs(app)
    # the last added runs first: metrics, CORS, body limits (then internal errors); the front
    # door (rate limits, keyed tenants first, /healthz) runs before all of them
    app.add_middleware(
        BodyLimits,
        max_bytes=settings.max_body_bytes,
        read_timeout=settings.body_read_timeout,
        limits=settings.wire_limits(),
    )
    origins = settings.cors_origin_list()
    if origins:
        app.add_middleware(
            CORSMiddleware,
            allow_origins=origins,
            allow_methods=["GET", "POST", "DELETE"],
            allow_headers=["Authorization", "Content-Type"],
        )
    app.add_middleware(SecurityHeaders)
    app.add_middleware(HttpMetrics, metrics=service_metrics)
    install_openapi(app)
    build_stack = app.build_middleware_stack

    def behind_the_front_door() -> ASGIApp:
        door = FrontDoor(
            build_stack(),
            rates=parse_rates(settings.rate_limit),
            body_bytes_per_second=settings.tenant_body_bytes_per_second,
            max_body=settings.max_body_bytes,
            refused=service_metrics.refused_at_door,
            held=service_metrics.held_at_door,
            cors_origins=settings.cors_origin_list(),
            anonymous_served=settings.open_access(),
        )
        app.state.front_door = door  # the streams ask it about a message (keyed tenants first)
        return door

    app.build_middleware_stack = behind_the_front_door  # type: ignore[method-assign]
    return app
