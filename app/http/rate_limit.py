"""Rate limits: per tenant (:mod:`app.http.tenants`), decided from the request's token.

Whom a request counts against is decided before its body is read: the
tenant of the token the service *verified* — the token of a live session
held by this instance (its session's tenant: every token of a tenant shares
one budget, so minting sessions never multiplies it), an API key or the admin
token. A request with no token, an unknown or forged token (``Bearer
fake<i>``), or to an unauthenticated route counts against its client
address's tenant.

``CREDAL_RATE_LIMIT`` takes the ``limits`` library's notation: one or more
rates separated by ``;`` (``"200/second"``, ``"50/second;2000/minute"``);
``"none"`` turns the limit off. Every HTTP request and every WebSocket
upgrade counts once against its key (messages on an open WebSocket do not:
the connection's bounded queues and TCP already pace them). The bytes of
request bodies count too, per tenant (``tenant_body_bytes_per_second``,
2 MiB/s: parsing a 1 MiB body costs ~50 ms of CPU, so a tenant can spend about
a tenth of a core on parsing): a body counts its declared ``Content-Length``
(a chunked one, ``max_body_bytes``). A request over either limit gets ``429``
problem+json naming the limit (``limit: "rate_limit"`` or
``"tenant_body_bytes_per_second"``, ``rate``) with a ``Retry-After`` header,
before its body is read, by the front door (:mod:`app.http.front`: the outermost layer, with
an answer written once per server). ``/healthz`` is never limited: a liveness probe must not
be refused.

The counters are the library's sliding-window counters in this process's
memory, its asyncio flavour (the threaded one starts a timer thread every
10 ms under load, which took the GIL from the event loop: +2 ms of REST
p50 in ``bench/service.py``): with several instances behind a load balancer each instance counts
its own share (session affinity sends a session's token to one instance).
Tokens are keyed by a hash, never kept in clear.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

from limits import RateLimitItem
from starlette.responses import Response
from starlette.types import Receive, Scope, Send
from starlette.websockets import WebSocket

from app.http.security import hash_token
from app.tenants import address_tenant

RATE_LIMIT = "rate_limit"
BODY_RATE = "tenant_body_bytes_per_second"


def rate_text(item: RateLimitItem) -> str:
    return f"{item.amount} per {item.multiples} {item.GRANULARITY.name}"


def bearer_token(scope: Scope) -> str | None:
    """The bearer token of a request's first ``Authorization`` header, if it has one."""
    for name, value in scope.get("headers", ()):
        if name == b"authorization":
            scheme, _, token = value.partition(b" ")
            token = token.strip()
            return token.decode("latin-1") if scheme.lower() == b"bearer" and token else None
    return None


def client_key(scope: Scope, tenant_of: Callable[[str], str | None]) -> str:
    """Whom a request counts against: the tenant of its token (a live session's, an API key,
    the admin token) if ``tenant_of`` knows it, else its client address's tenant."""
    token = bearer_token(scope)
    tenant = None if token is None else tenant_of(token)
    if tenant is not None:
        return "tenant:" + tenant
    client = scope.get("client")
    return "tenant:" + address_tenant(client[0] if client else None)


def tenant_finder(scope: Scope) -> Callable[[str], str | None]:
    """The tenant of a token: a live session's (held here), an API key's, the admin's."""
    state = getattr(scope.get("app"), "state", None)
    tenancy = getattr(state, "tenancy", None)

    def tenant_of(token: str) -> str | None:
        hashed = hash_token(token)
        if tenancy is not None and (tenant := tenancy.of_hash(hashed)) is not None:
            return str(tenant)
        registry = getattr(state, "registry", None)  # set by the lifespan
        found = None if registry is None else registry.tenant_of_token(hashed)
        return None if found is None else str(found)

    return tenant_of


def body_size(scope: Scope, max_body: int) -> int:
    """What a request's body counts against the tenant's bytes: its ``Content-Length`` (at most
    ``max_body``: more is refused unread anyway), ``max_body`` for a body of unknown length
    (chunked), 0 without a body."""
    if scope["type"] != "http":
        return 0
    chunked = False
    for name, value in scope.get("headers", ()):
        if name == b"content-length":
            return min(int(value), max_body) if value.isdigit() else 0
        if name == b"transfer-encoding":
            chunked = True
    return max_body if chunked else 0


async def deny_websocket(scope: Scope, receive: Receive, send: Send, response: Response) -> None:
    """Refuse an upgrade: the 429 answer if the server can send one, else close code 1008."""
    websocket = WebSocket(scope, receive, send)
    if "websocket.http.response" in scope.get("extensions", {}):
        await websocket.send_denial_response(response)
    else:
        await websocket.close(code=1008, reason="rate limit exceeded")


class MessageRate:
    """At most ``per_second`` messages in any one-second window of one WebSocket connection
    (``ws_messages_per_second``): a moving window, as the ``limits`` library's for HTTP, kept
    by the connection itself: the times of its latest ``per_second`` messages admitted. (The
    library's threaded memory storage started a timer thread every 10 ms under load, about
    one per scan, each taking the GIL from the event loop.)"""

    def __init__(self, per_second: int) -> None:
        self.per_second = per_second
        self._admitted: deque[float] = deque(maxlen=per_second)

    def admit(self) -> bool:
        """Count one message; ``False`` if it is beyond the rate (it is then not counted):
        when the ``per_second``-th latest message admitted is less than a second old."""
        now = time.monotonic()
        if len(self._admitted) == self.per_second and self._admitted[0] >= now - 1.0:
            return False
        self._admitted.append(now)
        return True
