"""The Content-Security-Policy of the service's HTML pages (viewer, ``/docs``, ``/redoc``).

Every page is self-contained or loads its assets from this server; the policy
makes the browser hold to that: a script, style, image, font, fetch or
WebSocket aimed anywhere else is refused before it leaves the machine. Inline
scripts run only if they are the page's own (their SHA-256 is in the policy),
and no page can be framed.
"""

from __future__ import annotations

import base64
import functools
import hashlib
import re

from fastapi.responses import HTMLResponse

POLICY = (
    "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
    "script-src 'self'{scripts}; worker-src 'self' blob:; font-src 'self' data:; "
    "object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
)
"""Only this server ('self' covers its ws:// too); ReDoc's search runs in a blob: worker; a
page's own inline scripts by their hashes (no other inline script runs: an injected one
would not match); no page may be framed (clickjacking)."""
INLINE_SCRIPT = re.compile(rb"<script>(.*?)</script>", re.DOTALL)


@functools.lru_cache(maxsize=16)
def policy_of(body: bytes) -> str:
    """The policy of a page: :data:`POLICY` with the hash of each of its inline scripts."""
    hashes = [
        "'sha256-" + base64.b64encode(hashlib.sha256(script).digest()).decode() + "'"
        for script in INLINE_SCRIPT.findall(body)
    ]
    return POLICY.format(scripts="".join(f" {digest}" for digest in hashes))


def local_only(page: HTMLResponse) -> HTMLResponse:
    """``page`` with the policy that keeps the browser on this server."""
    page.headers["Content-Security-Policy"] = policy_of(bytes(page.body))
    page.headers["X-Frame-Options"] = "DENY"
    return page
