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
undecided. The view follows the tracks until the user pans or zooms (key F
follows again); labels are placed where they collide with nothing, else
hidden. A session with an ``origin`` is drawn on a map: Natural Earth's land
and borders (``/map/countries-50m.json``, vendored from the ``world-atlas``
package with its licence in ``app/static/map/``). ``window.__viewer.state()``
is what tests read of it.
"""

from __future__ import annotations

from functools import cache
from importlib.resources import files

from fastapi import APIRouter
from fastapi.responses import HTMLResponse, Response

from app.http.page_policy import local_only
from app.http.requests import WireRoute

router = APIRouter(include_in_schema=False, route_class=WireRoute)

VIEWER_PAGE = "viewer.html"
MAP_DATA = "countries-50m.json"
"""Natural Earth 1:50m land and countries as TopoJSON (``app/static/map/README.md``)."""


@cache
def viewer_page() -> str:
    """The page's text (read once from the package)."""
    return files("app").joinpath("static", VIEWER_PAGE).read_text(encoding="utf-8")


@router.get("/", response_class=HTMLResponse)
def get_viewer() -> HTMLResponse:
    """The live viewer page."""
    return local_only(HTMLResponse(viewer_page()))


@cache
def map_data() -> bytes:
    """The map's TopoJSON bytes (read once from the package)."""
    return files("app").joinpath("static", "map", MAP_DATA).read_bytes()


@router.get(f"/map/{MAP_DATA}")
def get_map() -> Response:
    """The viewer's offline map background (Natural Earth via world-atlas; public domain / ISC)."""
    return Response(
        map_data(), media_type="application/json", headers={"Cache-Control": "max-age=86400"}
    )
