"""The live viewer at ``/``: one static page (HTML + JS + canvas, no build step, nothing fetched from outside).

It opens the session named in its URL fragment (``/#session=ID&token=TOKEN``:
a fragment never reaches the server; the token is then kept in the tab's
sessionStorage and dropped from the address bar) or typed in its form. It
reads the session's config (sensors' fields of view) over REST, subscribes
to its results (WebSocket ``subscribe``, reconnecting with backoff), reads
the current picture and each track's history, and draws the fused tracks
with trails, 2-σ position ellipses to scale (never under 4 px), axes, a
scale bar and a legend; a click shows a track's sources, state, covariance,
masses, BetP and conflict. A track whose top BetP values tie is drawn
undecided. ``window.__viewer.state()`` is what tests read of it.
"""

from __future__ import annotations

from functools import cache
from importlib.resources import files

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from app.http.page_policy import local_only
from app.http.requests import WireRoute

router = APIRouter(include_in_schema=False, route_class=WireRoute)

VIEWER_PAGE = "viewer.html"


@cache
def viewer_page() -> str:
    """The page's text (read once from the package)."""
    return files("app").joinpath("static", VIEWER_PAGE).read_text(encoding="utf-8")


@router.get("/", response_class=HTMLResponse)
def get_viewer() -> HTMLResponse:
    """The live viewer page."""
    return local_only(HTMLResponse(viewer_page()))
