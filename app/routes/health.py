"""Liveness."""

from __future__ import annotations

from fastapi import APIRouter

from api_schemas.health import Health
from app.requests import WireRoute
from core import __version__

router = APIRouter(tags=["health"], route_class=WireRoute)


@router.get("/healthz", operation_id="get_health")
def get_health() -> Health:
    """Liveness and version; needs no token."""
    return Health(version=__version__)
