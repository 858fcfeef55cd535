"""The Content-Security-Policy of the service's HTML pages (viewer, ``/docs``, ``/redoc``).

Every page is self-contained or loads its assets from this server; the policy
makes the browser hold to that: a script, style, image, font, fetch or
WebSocket aimed anywhere else is refused before it leaves the machine.
"""

from __future__ import annotations

from fastapi.responses import HTMLResponse

CONTENT_SECURITY_POLICY = (
    "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
    "script-src 'self' 'unsafe-inline'; worker-src 'self' blob:; font-src 'self' data:"
)
"""Only this server ('self' covers its ws:// too); ReDoc's search runs in a blob: worker."""


def local_only(page: HTMLResponse) -> HTMLResponse:
    """``page`` with the policy that keeps the browser on this server."""
    page.headers["Content-Security-Policy"] = CONTENT_SECURITY_POLICY
    return page
