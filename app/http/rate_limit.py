"""Rate limits: per verified session token, or per client address for every other request.

Whom a request counts against is decided before its body is read, and only a
token the service *verified* earns its own budget: the token of a live
session held by this instance (the registry keeps their hashes) or the admin
token. A request with no token, an unknown or forged token (``Bearer
fake<i>``), or to an unauthenticated route (``POST /v1/sessions``, ``POST
/v1/associate``) counts against its client address, so inventing tokens
never buys more requests.

``CREDAL_RATE_LIMIT`` takes the ``limits`` library's notation: one or more
rates separated by ``;`` (``"200/second"``, ``"50/second;2000/minute"``);
``"none"`` turns the limit off. Every HTTP request and every WebSocket
upgrade counts once against its key (messages on an open WebSocket do not:
the connection's bounded queues and TCP already pace them). A request over
the limit gets ``429`` problem+json naming the limit (``limit:
"rate_limit"``, ``rate``) with a ``Retry-After`` header, before its body is
read. ``/healthz`` is never limited: a liveness probe must not be refused.

The counters are the library's sliding-window counters in this process's
memory, its asyncio flavour (the threaded one starts a timer thread every
10 ms under load, which took the GIL from the event loop: +2 ms of REST
p50 in ``bench/service.py``): with several instances behind a load balancer each instance counts
its own share (session affinity sends a session's token to one instance).
Tokens are keyed by a hash, never kept in clear.
"""

from __future__ import annotations

import hmac
import math
import time
import uuid
from collections.abc import Callable

from limits import RateLimitItem, RateLimitItemPerSecond
from limits.aio.storage import MemoryStorage
from limits.aio.strategies import SlidingWindowCounterRateLimiter
from limits.storage import MemoryStorage as ThreadSafeMemoryStorage
from limits.strategies import MovingWindowRateLimiter
from starlette.responses import Response
from starlette.types import ASGIApp, Receive, Scope, Send
from starlette.websockets import WebSocket

from app.http.errors import RateLimited, problem_response
from app.http.security import hash_token

RATE_LIMIT = "rate_limit"
EXEMPT_PATHS = frozenset({"/healthz"})


def _rate_text(item: RateLimitItem) -> str:
    return f"{item.amount} per {item.multiples} {item.GRANULARITY.name}"


def client_key(scope: Scope, verified: Callable[[str], bool]) -> str:
    """Whom a request counts against: its token's hash if ``verified`` knows it, else its address."""
    for name, value in scope.get("headers", ()):
        if name == b"authorization":
            scheme, _, token = value.partition(b" ")
            token = token.strip()
            if scheme.lower() == b"bearer" and token:
                token_hash = hash_token(token.decode("latin-1"))
                if verified(token_hash):
                    return "token:" + token_hash
            break
    client = scope.get("client")
    return f"address:{client[0] if client else 'unknown'}"


def verifier(scope: Scope) -> Callable[[str], bool]:
    """Whether a token hash is a live session's (held here) or the admin token's."""
    state = getattr(scope.get("app"), "state", None)
    settings = getattr(state, "settings", None)
    admin = getattr(settings, "admin_token", None)
    admin_hash = hash_token(admin.get_secret_value()) if admin is not None else None

    def verified(token_hash: str) -> bool:
        if admin_hash is not None and hmac.compare_digest(token_hash, admin_hash):
            return True
        registry = getattr(state, "registry", None)  # set by the lifespan
        return registry is not None and bool(registry.knows_token(token_hash))

    return verified


class RateLimit:
    """ASGI middleware: refuse requests beyond ``rates`` per key with 429 and ``Retry-After``."""

    def __init__(self, app: ASGIApp, rates: list[RateLimitItem]) -> None:
        self.app = app
        self.rates = rates
        self.limiter = SlidingWindowCounterRateLimiter(MemoryStorage())
        self._verified: Callable[[str], bool] | None = None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if (
            not self.rates
            or scope["type"] not in ("http", "websocket")
            or scope.get("path") in EXEMPT_PATHS
        ):
            await self.app(scope, receive, send)
            return
        if self._verified is None:  # the application's registry and settings, once
            self._verified = verifier(scope)
        key = client_key(scope, self._verified)
        for item in self.rates:
            if not await self.limiter.hit(item, key):
                await self._refuse(scope, receive, send, item, key)
                return
        await self.app(scope, receive, send)

    async def _refuse(
        self, scope: Scope, receive: Receive, send: Send, item: RateLimitItem, key: str
    ) -> None:
        reset = (await self.limiter.get_window_stats(item, key)).reset_time
        retry_after = max(1, math.ceil(reset - time.time()))
        rate = _rate_text(item)
        who = "this token" if key.startswith("token:") else "this client address"
        response = problem_response(
            RateLimited(RATE_LIMIT, rate, who, retry_after), scope.get("path")
        )
        if scope["type"] == "websocket":
            await _deny_websocket(scope, receive, send, response)
            return
        await response(scope, receive, send)


async def _deny_websocket(scope: Scope, receive: Receive, send: Send, response: Response) -> None:
    """Refuse an upgrade: the 429 answer if the server can send one, else close code 1008."""
    websocket = WebSocket(scope, receive, send)
    if "websocket.http.response" in scope.get("extensions", {}):
        await websocket.send_denial_response(response)
    else:
        await websocket.close(code=1008, reason="rate limit exceeded")


MESSAGES = MovingWindowRateLimiter(ThreadSafeMemoryStorage())
"""The message counts of every WebSocket connection of the process (one key each)."""


class MessageRate:
    """At most ``per_second`` messages in any one-second window of one WebSocket connection
    (``ws_messages_per_second``): the ``limits`` library's moving window, as for HTTP."""

    def __init__(self, per_second: int) -> None:
        self.item = RateLimitItemPerSecond(per_second)
        self.key = f"ws-connection:{uuid.uuid4().hex}"

    def admit(self) -> bool:
        """Count one message; ``False`` if it is beyond the rate (it is then not counted)."""
        return MESSAGES.hit(self.item, self.key)
