"""Prometheus exposition."""

from __future__ import annotations

from fastapi import APIRouter, Response

from app.deps import MetricsDep
from app.errors import problem_responses
from app.requests import WireRoute

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
def get_metrics(metrics: MetricsDep) -> Response:
    """Prometheus metrics of the service (text exposition format)."""
    body, content_type = metrics.exposition()
    return Response(content=body, media_type=content_type)
