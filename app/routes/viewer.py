"""The live viewer at ``/``: one static page (HTML + JS, no build step, nothing fetched from outside).

It asks for a session id and token, reads the session's config (sensors'
fields of view) and current picture over REST, then draws every result of
the ``subscribe`` WebSocket: fused tracks, their 2-σ position ellipses and
each track's class BetP.
"""

from __future__ import annotations

from functools import cache
from importlib.resources import files

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from app.requests import WireRoute

router = APIRouter(include_in_schema=False, route_class=WireRoute)

VIEWER_PAGE = "viewer.html"


@cache
def viewer_page() -> str:
    """The page's text (read once from the package)."""
    return files("app").joinpath("static", VIEWER_PAGE).read_text(encoding="utf-8")


@router.get("/", response_class=HTMLResponse)
def get_viewer() -> HTMLResponse:
    """The live viewer page."""
    return HTMLResponse(viewer_page())
