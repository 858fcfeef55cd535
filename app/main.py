"""The FastAPI application factory."""

from __future__ import annotations

from fastapi import FastAPI

from app.routes import health
from core import __version__


def create_app() -> FastAPI:
    """Build the service application."""
    app = FastAPI(
        title="credal-fusion",
        version=__version__,
        description="Multi-sensor track fusion with belief-function association and classification.",
    )
    app.include_router(health.router)
    return app
