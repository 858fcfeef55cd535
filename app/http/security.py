"""Bearer tokens: one per session (returned once at creation) and the admin token.

Tokens are 256-bit ``secrets.token_urlsafe`` strings; only their SHA-256 is
stored (a fast hash is enough for high-entropy secrets: there is no password
to guess). Every comparison is between two hashes with
``hmac.compare_digest``, so it takes the same time wherever they differ.
A session's token opens that session only; the admin token
(``CREDAL_ADMIN_TOKEN``) opens every session and the admin routes.
"""

from __future__ import annotations

import hashlib
import hmac
import secrets
from dataclasses import dataclass

from starlette.datastructures import MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send

TOKEN_BYTES = 32
HASH_PREFIX = "sha256:"


def issue_token() -> str:
    """A new random bearer token; never one that starts with ``-`` (a command line would take
    ``--token -x…`` for two options: one token in 64 did)."""
    while (token := secrets.token_urlsafe(TOKEN_BYTES)).startswith("-"):
        pass
    return token


def hash_token(token: str) -> str:
    """The stored form of a token."""
    return HASH_PREFIX + hashlib.sha256(token.encode("utf-8")).hexdigest()


def token_matches(token: str, stored_hash: str) -> bool:
    """Whether ``token`` hashes to ``stored_hash`` (constant-time comparison)."""
    return hmac.compare_digest(hash_token(token).encode("ascii"), stored_hash.encode("ascii"))


def is_admin_token(token: str, admin_token: str | None) -> bool:
    """Whether ``token`` is the admin token (never true when no admin token is configured)."""
    if not admin_token:
        return False
    return token_matches(token, hash_token(admin_token))


@dataclass(frozen=True)
class Principal:
    """Who a request acts as: the admin, or the holder of one session's token."""

    admin: bool
    session_id: str | None = None


class SecurityHeaders:
    """ASGI middleware: every answer says ``X-Content-Type-Options: nosniff`` (a browser never
    guesses a type), and every API answer (``/v1/…``) ``Cache-Control: no-store``: a session's
    token (in its creation's answer) and its data are never kept by a cache."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        private = str(scope.get("path", "")).startswith("/v1/")

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                headers["X-Content-Type-Options"] = "nosniff"
                if private:
                    headers["Cache-Control"] = "no-store"
            await send(message)

        await self.app(scope, receive, with_headers)
