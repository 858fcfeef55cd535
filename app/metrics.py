"""Prometheus metrics: one registry per application, an ASGI middleware for HTTP.

``requests`` and ``latency`` are labelled by the route *template*
(``/v1/sessions/{sid}``), never by the raw path, so cardinality stays bounded.
``sessions``, ``inputs``, ``fusion_step`` and ``engine_cpu`` are fed by the session code.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from prometheus_client import (
    CONTENT_TYPE_LATEST,
    CollectorRegistry,
    Counter,
    Gauge,
    Histogram,
    generate_latest,
)
from starlette.types import ASGIApp, Message, Receive, Scope, Send

UNMATCHED_ROUTE = "unmatched"
LATENCY_BUCKETS = (
    0.0005,
    0.001,
    0.0025,
    0.005,
    0.01,
    0.025,
    0.05,
    0.1,
    0.25,
    0.5,
    1.0,
    2.5,
    5.0,
    10.0,
)

LOOP_LAG_BUCKETS = (
    0.001,
    0.0025,
    0.005,
    0.01,
    0.02,
    0.03,
    0.04,
    0.05,
    0.075,
    0.1,
    0.25,
    1.0,
    5.0,
)
"""Event-loop lag: 0.05 s is the limit of docs/design.md ("Bounded work")."""


@dataclass(frozen=True)
class ServiceMetrics:
    """The service's metrics, registered in their own registry."""

    registry: CollectorRegistry
    requests: Counter
    latency: Histogram
    sessions: Gauge
    inputs: Counter
    fusion_step: Histogram
    engine_cpu: Histogram
    store_bytes: Gauge
    store_inputs: Gauge
    quarantined: Gauge
    rebuilds: Counter
    internal_errors: Counter
    overloaded: Counter
    refused_waiting: Counter
    refused_at_door: Counter
    held_at_door: Counter
    loop_lag: Histogram
    collections: Histogram
    detections: Counter
    local_tracks: Counter

    @classmethod
    def create(cls) -> ServiceMetrics:
        """A fresh registry with every metric of the service."""
        registry = CollectorRegistry(auto_describe=True)
        return cls(
            registry=registry,
            requests=Counter(
                "credal_http_requests",
                "HTTP requests by method, route template and status.",
                ("method", "route", "status"),
                registry=registry,
            ),
            latency=Histogram(
                "credal_http_request_duration_seconds",
                "HTTP request latency by method and route template.",
                ("method", "route"),
                buckets=LATENCY_BUCKETS,
                registry=registry,
            ),
            sessions=Gauge("credal_sessions", "Live sessions.", registry=registry),
            inputs=Counter(
                "credal_inputs",
                "Accepted inputs by kind (tracks, detections).",
                ("kind",),
                registry=registry,
            ),
            quarantined=Gauge(
                "credal_sessions_quarantined",
                "Sessions the store holds but cannot read (set aside; GET /readyz lists them).",
                registry=registry,
            ),
            store_bytes=Gauge(
                "credal_store_bytes",
                "What the session store holds, in its own measure (read at each scrape).",
                registry=registry,
            ),
            store_inputs=Gauge(
                "credal_store_inputs",
                "Inputs held in the store's logs (compacted behind snapshots).",
                registry=registry,
            ),
            fusion_step=Histogram(
                "credal_fusion_step_seconds",
                "Time to apply one input to a session engine.",
                ("kind",),
                buckets=LATENCY_BUCKETS,
                registry=registry,
            ),
            engine_cpu=Histogram(
                "credal_fusion_engine_cpu_seconds",
                "CPU time of the engine step alone (its thread's), a part of the apply step "
                "timed by credal_fusion_step_seconds: the rest of that is translating, "
                "serialising the result and waiting for a CPU.",
                ("kind",),
                buckets=LATENCY_BUCKETS,
                registry=registry,
            ),
            rebuilds=Counter(
                "credal_session_rebuilds",
                "Sessions dropped to be rebuilt from their log, the last defence: an engine "
                "changed by a refused input (a bug: steps are transactions), or a step that "
                "could not be logged.",
                ("reason",),
                registry=registry,
            ),
            internal_errors=Counter(
                "credal_internal_errors",
                "Requests answered 500 internal-error (a bug; the log has each reference).",
                registry=registry,
            ),
            overloaded=Counter(
                "credal_inputs_refused_overloaded",
                "Inputs refused (503 overloaded) because the event loop ran later than "
                "overload_delay_ms (app.sessions.pipeline.InputPipeline.admit).",
                registry=registry,
            ),
            refused_waiting=Counter(
                "credal_inputs_refused_waiting",
                "Inputs refused before their step by the limit on waiting inputs it names: "
                "max_queue_ms (503 overloaded: it waited too long to be answered in time) or "
                "tenant_max_in_flight (429: its tenant had that many waiting or applied).",
                ("limit",),
                registry=registry,
            ),
            refused_at_door=Counter(
                "credal_requests_refused_at_door",
                "Requests refused from their head alone, before any other layer, by the limit "
                "named: rate_limit, tenant_body_bytes_per_second (429) or keyed_tenants_first "
                "(503: a large body without an API key while keyed tenants are served; "
                "app.http.front).",
                ("limit",),
                registry=registry,
            ),
            held_at_door=Counter(
                "credal_requests_held_at_door",
                "keyed_tenants_first refusals answered only when the Retry-After of the "
                "client's previous one had passed (it sent again too soon; app.http.front).",
                registry=registry,
            ),
            loop_lag=Histogram(
                "credal_event_loop_lag_seconds",
                "How late the event loop woke a timer: how long it was busy (or waited for "
                "the GIL) with every request on hold. Sampled every 5 ms (app.runtime.LoopLag); "
                "a stall of S seconds reads between S - 0.005 and S.",
                buckets=LOOP_LAG_BUCKETS,
                registry=registry,
            ),
            detections=Counter(
                "credal_detections",
                "Detections by what they did in their sensor's local tracker, over every "
                "session (docs/algorithms.md §8.8; per session and sensor: GET "
                "/v1/sessions/{sid}): joined_established, joined_tentative, started, unused.",
                ("outcome",),
                registry=registry,
            ),
            local_tracks=Counter(
                "credal_local_tracks",
                "Local tracks by event, over every session: confirmed, refuted (tentative "
                "ended unconfirmed), ended (confirmed, then ended).",
                ("event",),
                registry=registry,
            ),
            collections=Histogram(
                "credal_gc_pause_seconds",
                "Garbage collections by generation and how long each held the GIL (every "
                "thread, the event loop's included, waits meanwhile; app.runtime.CollectionTimes).",
                ("generation",),
                buckets=LOOP_LAG_BUCKETS,
                registry=registry,
            ),
        )

    def exposition(self) -> tuple[bytes, str]:
        """The text exposition of every metric and its content type."""
        return generate_latest(self.registry), CONTENT_TYPE_LATEST


def _route_template(scope: Scope) -> str:
    route = scope.get("route")
    path = getattr(route, "path", None)
    return path if isinstance(path, str) else UNMATCHED_ROUTE


class HttpMetrics:
    """ASGI middleware counting requests and timing them by route template."""

    def __init__(self, app: ASGIApp, metrics: ServiceMetrics) -> None:
        self.app = app
        self.metrics = metrics
        self._series: dict[tuple[str, str, str], tuple[Counter, Histogram]] = {}
        """(method, route, status) → its counter and latency histogram (``labels()`` once each)."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = time.perf_counter()
        status = 500

        async def send_with_status(message: Message) -> None:
            nonlocal status
            if message["type"] == "http.response.start":
                status = int(message["status"])
            await send(message)

        try:
            await self.app(scope, receive, send_with_status)
        finally:
            key = (str(scope.get("method", "")), _route_template(scope), str(status))
            series = self._series.get(key)
            if series is None:
                method, route, status_text = key
                series = self._series[key] = (
                    self.metrics.requests.labels(method, route, status_text),
                    self.metrics.latency.labels(method, route),
                )
            series[0].inc()
            series[1].observe(time.perf_counter() - started)
