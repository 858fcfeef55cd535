"""API docs that load offline: ``/docs`` (Swagger UI), ``/redoc`` and ``/favicon.ico``.

FastAPI's own pages fetch Swagger UI and ReDoc from a CDN, so without
internet they stay blank. Here the same pages load their scripts, styles and
icon from the ``fastapi-offline`` package's copy, mounted at
:data:`ASSETS_URL`: no request leaves the machine (``tests/e2e/test_docs_offline.py``
loads ``/docs`` and ``/redoc`` with every other host blocked). Two things in
them would still call out: Swagger UI's validator badge (switched off) and the
Redocly logo in ReDoc's sidebar, an ``<img>`` on Redocly's CDN (the page points
it at the local icon before ReDoc runs). Both pages also carry the
policy of :mod:`app.http.page_policy`, which lets the browser load nothing from elsewhere.
"""

from __future__ import annotations

from functools import cache
from importlib.resources import files
from pathlib import Path

from fastapi import APIRouter, FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse, Response
from fastapi.staticfiles import StaticFiles

from app.http.page_policy import local_only

router = APIRouter(include_in_schema=False)

ASSETS_URL = "/docs-assets"
ASSETS_PACKAGE = "fastapi_offline"
ICON = "favicon.png"
OPENAPI_URL = "/openapi.json"
REDOCLY_CDN = "https://cdn.redoc.ly/"
REDOC_PAGE = f"""<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>credal-fusion · API reference</title>
<link rel="icon" href="/favicon.ico">
<style>body {{ margin: 0; padding: 0; }}</style>
<script>
// ReDoc's sidebar shows Redocly's logo from its CDN: show the local icon instead.
const local = (url) => (String(url).startsWith("{REDOCLY_CDN}") ? "/favicon.ico" : url);
const setAttribute = Element.prototype.setAttribute;
Element.prototype.setAttribute = function (name, value) {{
  return setAttribute.call(this, name, name === "src" ? local(value) : value);
}};
const src = Object.getOwnPropertyDescriptor(HTMLImageElement.prototype, "src");
Object.defineProperty(HTMLImageElement.prototype, "src", {{
  ...src, set(value) {{ src.set.call(this, local(value)); }},
}});
</script>
</head>
<body>
<redoc spec-url="{OPENAPI_URL}"></redoc>
<script src="{ASSETS_URL}/redoc.standalone.js"></script>
</body>
</html>
"""


def assets_directory() -> Path:
    """The installed package's folder of Swagger UI and ReDoc files."""
    return Path(str(files(ASSETS_PACKAGE).joinpath("static")))


def install_docs(app: FastAPI) -> None:
    """Serve the pages and their assets (the app is built with ``docs_url=None, redoc_url=None``)."""
    app.mount(ASSETS_URL, StaticFiles(directory=assets_directory()), name="docs-assets")
    app.include_router(router)


@router.get("/docs")
def get_swagger_ui() -> HTMLResponse:
    """Swagger UI over ``/openapi.json``."""
    page = get_swagger_ui_html(
        openapi_url=OPENAPI_URL,
        title="credal-fusion · API docs",
        swagger_js_url=f"{ASSETS_URL}/swagger-ui-bundle.js",
        swagger_css_url=f"{ASSETS_URL}/swagger-ui.css",
        swagger_favicon_url="/favicon.ico",
        swagger_ui_parameters={"validatorUrl": None},
    )
    return local_only(page)


@router.get("/redoc")
def get_redoc() -> HTMLResponse:
    """ReDoc over ``/openapi.json`` (system fonts: no Google Fonts)."""
    return local_only(HTMLResponse(REDOC_PAGE))


@cache
def icon() -> bytes:
    """The site icon (a PNG: browsers read it whatever the name says)."""
    return (assets_directory() / ICON).read_bytes()


@router.get("/favicon.ico")
def get_favicon() -> Response:
    """The icon browsers ask for on every page."""
    return Response(icon(), media_type="image/png", headers={"Cache-Control": "max-age=86400"})
