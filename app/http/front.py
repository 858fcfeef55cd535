"""The front door: what is decided from a request's head alone, before any other layer.

:class:`FrontDoor` is the outermost ASGI layer (:func:`app.main.create_app` puts it around the
whole middleware stack, Starlette's own error middleware included): it sees every HTTP request
and WebSocket upgrade once its head is read (the transport limits of
:mod:`app.http.transport` came before it) and, in this order:

1. answers ``GET /healthz`` itself, from bytes written once: a liveness probe costs no
   routing, no middleware and no rate limit (and is never refused);
2. decides whom the request counts against (:func:`~app.http.rate_limit.client_key`: the
   tenant of its verified token, else its client address's);
3. the rate limit (``CREDAL_RATE_LIMIT``) per tenant;
4. **keyed tenants first**: while a tenant with an API key is being served —
   a request of its *work* (an input, ``POST`` under a session's path, or an association,
   ``POST /v1/associate``: :func:`is_work`) in flight here, or answered less than
   :data:`KEYED_GRACE_S` ago, or an input of it in flight in the pipeline (REST or
   WebSocket), or a ``stream`` message of it answered less than :data:`KEYED_GRACE_S` ago
   (:meth:`FrontDoor.worked`) — a client *without* a key
   (an address tenant of ``CREDAL_ACCESS=open``; the admin is neither; without open access a
   request without a valid token is the application's to refuse) sending a body larger than
   :data:`~app.http.requests.OFFLOAD_BYTES` (a body whose parsing and validation cost
   milliseconds of CPU: 10-15 ms for a 2 000-track list) is refused ``503 overloaded``
   (``limit: "keyed_tenants_first"``, ``Retry-After: 1``) before its body is read. Small
   requests (session creation, reads, small inputs) of every tenant go on as before. A
   client that sends its next large body before the ``Retry-After`` it was given has passed
   waits it out: that refusal is answered when the time is up (``credal_requests_held_at_door``
   counts them), so one address's refusals come at most one per second per connection
   (``max_connections_per_client`` of them), whatever it sends. A keyed tenant's reads
   (a dashboard polling its tracks, its sessions) and its session creations and deletions
   are no work here: they hold no anonymous input back. A WebSocket ``stream``
   message of such a client over that size is answered the same refusal (an ``error``
   message, the connection kept) before it is parsed (:func:`app.routes.streams.stream_session`
   asks :meth:`FrontDoor.waits`): the stream is no way around the door. The refusal tells a
   client without a key that a keyed tenant sent work in the last second; it is not disguised
   as the pipeline's load shedding (``overload_delay_ms``, ``max_queue_ms``): those refuse
   inputs of every size after their parsing, this one only large bodies, unread, so a client
   sending one large and one small input tells them apart whatever the answer says, and
   ``/metrics``, open to every client, counts every input (``credal_inputs_total``) anyway;
5. the tenant's request-body bytes (``tenant_body_bytes_per_second``, on ``Content-Length``).

Every refusal here is a problem+json answer written once per server and kept (an
:func:`functools.lru_cache` of its bytes): a refusal renders nothing, validates nothing and
runs no other layer, so a crowd's refused requests cost the server the reading of their
heads. (A refused body is not read by the application; the HTTP protocol discards its bytes
as they arrive, so the connection stays usable for the answer.) ``/metrics`` counts the
refusals in ``credal_requests_refused_at_door{limit}``.

Measured in ``bench/soak.py --crowd``: an anonymous attacker's 276 KB inputs cost the server
~8 ms of CPU each refused after parsing (``max_input_work``) and 60-90 ms each accepted (the
2 000-track first input of each new session): beside the honest load the server spent
+4.1 to +4.6 ms of CPU per honest input (+53 to +64 %); refused at the door, each costs
0.25 ms (its body discarded unparsed) and the server +0.4 to +0.6 ms per honest input.
"""

from __future__ import annotations

import asyncio
import functools
import math
import re
import time
from collections import OrderedDict
from collections.abc import Callable
from http import HTTPStatus

from limits import RateLimitItem, RateLimitItemPerSecond
from limits.aio.storage import MemoryStorage
from limits.aio.strategies import SlidingWindowCounterRateLimiter
from prometheus_client import Counter
from starlette.types import ASGIApp, Receive, Scope, Send

from app.errors import Overload, RateLimited, ServiceError
from app.http.errors import problem_for, problem_response
from app.http.rate_limit import (
    BODY_RATE,
    RATE_LIMIT,
    bearer_token,
    body_size,
    client_key,
    deny_websocket,
    rate_text,
    tenant_finder,
)
from app.http.requests import OFFLOAD_BYTES
from app.http.responses import dumps
from app.http.security import token_matches
from app.tenants import is_anonymous, is_keyed

HEALTH_PATH = "/healthz"
SESSION_PATH = re.compile(r"^/v1/sessions/([^/]+)/")
"""A path under a session's (its id the group)."""
ASSOCIATE_PATH = "/v1/associate"
KEYED_FIRST = "keyed_tenants_first"
MAX_WAITING_ADDRESSES = 4096
"""Addresses whose keyed-first ``Retry-After`` is remembered, at most (the oldest forgotten)."""
KEYED_GRACE_S = 1.0
"""A keyed tenant answered less than this long ago is still being served (its next request,
a sensor's next scan, is on its way)."""


def is_work(method: str | None, path: str) -> bool:
    """Whether an HTTP request is work a keyed tenant is served (module docstring, 4): an input
    (``POST /v1/sessions/{sid}/{kind}``) or an association (``POST /v1/associate``); not a
    read, a session's creation or deletion."""
    return method == "POST" and (SESSION_PATH.match(path) is not None or path == ASSOCIATE_PATH)


class KeyedFirst(Overload):
    """A large body of a tenant without a key while keyed tenants are served (module docstring)."""

    def __init__(self) -> None:
        super().__init__(
            "tenants with an API key are being served: a request body over "
            f"{OFFLOAD_BYTES} bytes from a client without a key waits for a quiet moment "
            f"(limit {KEYED_FIRST}); nothing was read or applied, send it again after "
            "Retry-After, or with an API key",
            type(self).retry_after_s,
            limit=KEYED_FIRST,
        )


Answer = tuple[int, list[tuple[bytes, bytes]], bytes]
"""An answer written once: its status, raw headers and body."""


def answer_of(refusal: ServiceError, private: bool) -> Answer:
    """The answer of ``refusal`` (problem+json, no ``instance``: it is the same for every
    path); ``private``: an API path (``Cache-Control: no-store``, as
    :class:`~app.http.security.SecurityHeaders` says)."""
    problem = problem_for(refusal)
    body = dumps(problem.model_dump(mode="json", exclude_none=True)).encode()
    headers = [
        (b"content-type", b"application/problem+json"),
        (b"content-length", str(len(body)).encode()),
        (b"x-content-type-options", b"nosniff"),
        *(
            (name.lower().encode("latin-1"), value.encode("latin-1"))
            for name, value in refusal.headers().items()
        ),
    ]
    if private:
        headers.append((b"cache-control", b"no-store"))
    return int(refusal.status_code), headers, body


@functools.lru_cache(maxsize=256)
def _rate_answer(limit: str, rate: str, who: str, retry_after: int, private: bool) -> Answer:
    return answer_of(RateLimited(limit, rate, who, retry_after), private)


@functools.lru_cache(maxsize=2)
def _keyed_first_answer(private: bool) -> Answer:
    return answer_of(KeyedFirst(), private)


@functools.lru_cache(maxsize=1)
def _health_answer() -> Answer:
    from app.routes.health import HEALTH  # the route's own text (it documents the schema)

    headers = [
        (b"content-type", b"application/json"),
        (b"content-length", str(len(HEALTH)).encode()),
        (b"x-content-type-options", b"nosniff"),
    ]
    return HTTPStatus.OK.value, headers, HEALTH


async def send_answer(send: Send, answer: Answer, extra: list[tuple[bytes, bytes]]) -> None:
    """Send ``answer`` with the ``extra`` headers (a browser's CORS headers) after its own."""
    status, headers, body = answer
    if extra:
        headers = headers + extra
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


def _is_preflight(scope: Scope) -> bool:
    """A browser's CORS preflight: ``OPTIONS`` with ``Origin`` and
    ``Access-Control-Request-Method`` (what :class:`~starlette.middleware.cors.CORSMiddleware`
    answers itself); any other ``OPTIONS`` request goes through the door as every request."""
    names = {name for name, _ in scope.get("headers", ())}
    return b"origin" in names and b"access-control-request-method" in names


class FrontDoor:
    """ASGI layer: the checks of the module docstring, before every other layer."""

    def __init__(
        self,
        app: ASGIApp,
        rates: list[RateLimitItem],
        body_bytes_per_second: int,
        max_body: int,
        refused: Counter | None = None,
        held: Counter | None = None,
        cors_origins: list[str] | None = None,
        anonymous_served: bool = True,
    ) -> None:
        self.app = app
        self.anonymous_served = anonymous_served
        """Whether a client without a key is one the service serves (``CREDAL_ACCESS=open``):
        only then does its large body wait for the keyed tenants. Without open access an
        address tenant is a request without a valid token (none, a typo, an ended session's):
        the application answers it (401, 404) as before; a 503 "send it again after
        Retry-After" would have it retry for ever, and tell it keyed tenants are active."""
        self.held = held
        self.cors_origins = frozenset(cors_origins or ())
        """The browser origins allowed (``CREDAL_CORS_ORIGINS``): the door's answers to them
        carry the headers :class:`~starlette.middleware.cors.CORSMiddleware` would add, and
        their preflight requests (``OPTIONS`` with ``Origin`` and
        ``Access-Control-Request-Method``) are that middleware's alone."""
        self.rates = rates
        self.body_rate = RateLimitItemPerSecond(body_bytes_per_second)
        self.max_body = max_body
        self.limiter = SlidingWindowCounterRateLimiter(MemoryStorage())
        self.refused = refused
        self._tenant_of: Callable[[str], str | None] | None = None
        self.keyed_in_flight = 0
        """Requests of keyed tenants' work (:func:`is_work`) being answered here."""
        self.keyed_answered = -math.inf
        """When (``time.monotonic()``) a keyed tenant's work was last answered here."""
        self.waiting_until: OrderedDict[str, float] = OrderedDict()
        """Address tenant → when (``time.monotonic()``) the ``Retry-After`` of its latest
        keyed-first refusal ends, the earliest end first; at most
        :data:`MAX_WAITING_ADDRESSES`."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        path = scope.get("path", "")
        method = scope.get("method")
        if self.cors_origins and method == "OPTIONS" and _is_preflight(scope):
            await self.app(scope, receive, send)
            return
        extra = self._cors_headers(scope)
        if path == HEALTH_PATH and method == "GET":
            await send_answer(send, _health_answer(), extra)
            return
        if self._tenant_of is None:  # the application's registry and tenants, once
            self._tenant_of = tenant_finder(scope)
        key = client_key(scope, self._tenant_of)
        private = path.startswith("/v1/")
        for item in self.rates:
            if not await self.limiter.hit(item, key):
                reset = (await self.limiter.get_window_stats(item, key)).reset_time
                answer = (RATE_LIMIT, item, key, reset, private)
                await self._refuse(scope, receive, send, extra, *answer)
                return
        tenant = key.removeprefix("tenant:")
        size = body_size(scope, self.max_body)
        if self.waits(tenant, size, scope) and await self._stored_waits(scope, size):
            await self._wait_your_turn(tenant)
            await send_answer(send, _keyed_first_answer(private), extra)
            return
        if size and not await self.limiter.hit(self.body_rate, "bytes", key, cost=size):
            reset = (await self.limiter.get_window_stats(self.body_rate, "bytes", key)).reset_time
            answer = (BODY_RATE, self.body_rate, key, reset, private)
            await self._refuse(scope, receive, send, extra, *answer)
            return
        if kind != "http" or not is_keyed(tenant) or not is_work(method, path):
            await self.app(scope, receive, send)  # a keyed stream is served by its inputs
            return
        self.keyed_in_flight += 1
        try:
            await self.app(scope, receive, send)
        finally:
            self.keyed_in_flight -= 1
            self.keyed_answered = time.monotonic()

    def worked(self, tenant: str) -> None:
        """A message of ``tenant``'s ``stream`` WebSocket was answered: an input, work as a
        ``POST`` of it is (:func:`is_work`), so a keyed tenant's is served as long after it
        (:data:`KEYED_GRACE_S`: its sensor's next scan is on its way)."""
        if is_keyed(tenant):
            self.keyed_answered = time.monotonic()

    def waits(self, tenant: str, size: int, scope: Scope) -> bool:
        """Whether a body (or a WebSocket message) of ``size`` bytes of ``tenant`` waits for
        the keyed tenants (module docstring, 4)."""
        return (
            size > OFFLOAD_BYTES
            and self.anonymous_served
            and is_anonymous(tenant)
            and self.keyed_served(scope)
        )

    async def _stored_waits(self, scope: Scope, size: int) -> bool:
        """Whether a request the door took for an address tenant's still waits once its
        session's stored record is read: the token of a session not held in memory (evicted
        after a failed write, held by another instance, not yet restored) is unknown to
        :func:`~app.http.rate_limit.client_key`, and a keyed tenant's sensor posting to it
        would be refused for ever while other keyed tenants are served. Only a large body of a
        bearer token on a session's path reaches this (one record read, as the route's own)."""
        found = SESSION_PATH.match(scope.get("path", ""))
        token = bearer_token(scope)
        registry = getattr(getattr(scope.get("app"), "state", None), "registry", None)
        if found is None or token is None or registry is None:
            return True
        try:
            record = await registry.record(found.group(1))
        except ServiceError:  # unavailable, unreadable: the address's, as the door took it
            return True
        if record is None or not token_matches(token, record.token_hash):
            return True
        return self.waits(record.tenant, size, scope)

    def keyed_served(self, scope: Scope) -> bool:
        """Whether a keyed tenant is being served (module docstring, 4)."""
        if self.keyed_in_flight or time.monotonic() - self.keyed_answered < KEYED_GRACE_S:
            return True
        registry = getattr(getattr(scope.get("app"), "state", None), "registry", None)
        in_flight: dict[str, int] = {} if registry is None else registry.pipeline.tenant_in_flight
        return any(is_keyed(tenant) for tenant in in_flight)

    async def _wait_your_turn(self, tenant: str) -> None:
        """Count a keyed-first refusal of ``tenant``; hold it until the ``Retry-After`` of the
        previous one has passed if that has not (module docstring, 4)."""
        self._count(KEYED_FIRST)
        now = time.monotonic()
        until = self.waiting_until.get(tenant, -math.inf)
        if until > now:
            if self.held is not None:
                self.held.inc()
            await asyncio.sleep(until - now)
            now = time.monotonic()
        # in the order of their ends (each is now + Retry-After, written at its time): the
        # ones past their time are the first; at the bound the oldest live one is forgotten too
        # (its next refusal is answered at once), never a walk of them all
        waiting = self.waiting_until
        waiting.pop(tenant, None)
        while waiting and (
            len(waiting) >= MAX_WAITING_ADDRESSES or next(iter(waiting.values())) <= now
        ):
            waiting.popitem(last=False)
        waiting[tenant] = now + KeyedFirst.retry_after_s

    def _count(self, limit: str) -> None:
        if self.refused is not None:
            self.refused.labels(limit).inc()

    def _cors_headers(self, scope: Scope) -> list[tuple[bytes, bytes]]:
        """The CORS headers of an answer to an allowed browser origin (none to any other)."""
        if not self.cors_origins:
            return []
        for name, value in scope.get("headers", ()):
            if name == b"origin":
                if value.decode("latin-1") in self.cors_origins:
                    return [(b"access-control-allow-origin", value), (b"vary", b"Origin")]
                break
        return []

    async def _refuse(
        self,
        scope: Scope,
        receive: Receive,
        send: Send,
        extra: list[tuple[bytes, bytes]],
        limit: str,
        item: RateLimitItem,
        key: str,
        reset: float,
        private: bool,
    ) -> None:
        self._count(limit)
        retry_after = max(1, math.ceil(reset - time.time()))
        rate = rate_text(item) + (" bytes" if limit == BODY_RATE else "")
        who = key.removeprefix("tenant:")
        who = "this client address" if who.startswith("address:") else f"tenant {who!r}"
        if scope["type"] == "websocket":
            response = problem_response(
                RateLimited(limit, rate, who, retry_after), scope.get("path")
            )
            await deny_websocket(scope, receive, send, response)
            return
        await send_answer(send, _rate_answer(limit, rate, who, retry_after, private), extra)
