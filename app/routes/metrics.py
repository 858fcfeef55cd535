"""Prometheus exposition."""

from __future__ import annotations

from fastapi import APIRouter, Response

from app.http.deps import MetricsDep, StoreDep
from app.http.errors import StoreCorrupt, StoreUnavailable, problem_responses
from app.http.requests import WireRoute

router = APIRouter(tags=["health"], route_class=WireRoute)


@router.get(
    "/metrics",
    response_class=Response,
    responses={
        200: {
            "content": {"text/plain": {"schema": {"type": "string"}}},
            "description": "Prometheus text",
        },
        **problem_responses(),
    },
)
def get_metrics(metrics: MetricsDep, store: StoreDep) -> Response:
    """Prometheus metrics of the service (text exposition format)."""
    try:
        usage = store.usage()
    except (StoreUnavailable, StoreCorrupt):
        pass  # the gauges keep their last values; /readyz says why
    else:
        metrics.store_bytes.set(usage.bytes)
        metrics.store_inputs.set(usage.inputs)
    body, content_type = metrics.exposition()
    return Response(content=body, media_type=content_type)
