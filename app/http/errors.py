"""Every error answer of the service, as RFC 9457 ``application/problem+json``.

The service raises :class:`ServiceError` subclasses (or lets request
validation, core ``InvalidInput`` and Starlette HTTP errors happen);
:func:`install_error_handlers` maps each to a problem document with a
machine-readable ``type`` (``urn:credal-fusion:problem:<slug>``), a ``title``,
the ``status``, a human ``detail`` and the request path as ``instance``.
Validation problems add ``errors``: every invalid field with its location.
Anything unexpected becomes a 500 whose detail carries only a reference id
that is also logged with the traceback.
"""

from __future__ import annotations

import difflib
import logging
import uuid
from collections.abc import Callable, Iterable, Mapping, Sequence
from http import HTTPStatus
from typing import Any, ClassVar

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from api_schemas.issues import FieldIssue, wire_location
from api_schemas.keys import allowed_keys
from api_schemas.limits import LIMIT_EXCEEDED
from api_schemas.problem import FieldError, Problem
from app.http.requests import body_model
from app.http.responses import dumps
from core.errors import InvalidInput
from core.errors import StaleReport as CoreStaleReport

PROBLEM_MEDIA_TYPE = "application/problem+json"
PROBLEM_TYPE_PREFIX = "urn:credal-fusion:problem:"
MAX_ERRORS_IN_DETAIL = 3

logger = logging.getLogger("credal_fusion.errors")


def problem_type(slug: str) -> str:
    """The ``type`` URI of a problem kind."""
    return PROBLEM_TYPE_PREFIX + slug


class ProblemResponse(JSONResponse):
    """A JSON response with the problem+json media type."""

    media_type = PROBLEM_MEDIA_TYPE


class ServiceError(Exception):
    """Base of the errors the service raises on purpose; each knows its status and slug."""

    status: ClassVar[int] = HTTPStatus.INTERNAL_SERVER_ERROR
    slug: ClassVar[str] = "internal-error"
    title: ClassVar[str] = "Internal server error"

    def __init__(self, detail: str, **extensions: Any) -> None:
        super().__init__(detail)
        self.detail = detail
        self.extensions = extensions

    @property
    def status_code(self) -> int:
        """The HTTP status of this error."""
        return int(self.status)

    def headers(self) -> dict[str, str]:
        """Extra response headers."""
        return {}

    def field_errors(self) -> list[FieldError] | None:
        """The fields at fault (422s list them; other statuses may)."""
        return None


class SessionNotFound(ServiceError):  # noqa: N818 - HTTP vocabulary
    """No live session has this id."""

    status = HTTPStatus.NOT_FOUND
    slug = "session-not-found"
    title = "Session not found"

    def __init__(self, session_id: str) -> None:
        super().__init__(f"no session {session_id!r}", session=session_id)


class Unauthorized(ServiceError):  # noqa: N818 - HTTP vocabulary
    """No usable bearer token was given."""

    status = HTTPStatus.UNAUTHORIZED
    slug = "unauthorized"
    title = "Missing or malformed bearer token"

    def headers(self) -> dict[str, str]:
        return {"WWW-Authenticate": 'Bearer realm="credal-fusion"'}


class Forbidden(ServiceError):  # noqa: N818 - HTTP vocabulary
    """The bearer token does not open this resource."""

    status = HTTPStatus.FORBIDDEN
    slug = "forbidden"
    title = "Token does not grant access"


class Conflict(ServiceError):  # noqa: N818 - HTTP vocabulary
    """The request conflicts with the session's state (for instance a duplicate sequence number)."""

    status = HTTPStatus.CONFLICT
    slug = "conflict"
    title = "Conflict with the session state"


class StaleReport(Conflict):
    """A report older than the session accepts for its sensor; says both times."""

    slug = "stale-report"
    title = "Stale report"

    def __init__(self, sensor: str, time: float, last_time: float) -> None:
        super().__init__(
            f"report of sensor {sensor!r} at time {time!r} is not newer than its last accepted report at time {last_time!r}",
            sensor=sensor,
            time=time,
            last_time=last_time,
        )

    def field_errors(self) -> list[FieldError] | None:
        return [_located(CoreStaleReport.loc, self.detail, "stale_report")]


class IdempotencyKeyReused(Conflict):
    """An ``Idempotency-Key`` sent again with another input than the first."""

    slug = "idempotency-key-reused"
    title = "Idempotency key reused"

    def __init__(self, session_id: str, key: str) -> None:
        super().__init__(
            f"session {session_id!r}: Idempotency-Key {key!r} came with another input; "
            "a key names one input (a retry sends the same input again)",
            session=session_id,
        )


class RetryLater(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A refusal that says when to try again: ``Retry-After`` and ``retry_after`` (seconds)."""

    retry_after_s: int

    def __init__(self, detail: str, retry_after_s: int, **extensions: Any) -> None:
        super().__init__(detail, **extensions, retry_after=retry_after_s)
        self.retry_after_s = retry_after_s

    def headers(self) -> dict[str, str]:
        return {"Retry-After": str(self.retry_after_s)}


class SessionLeased(RetryLater):
    """Another service instance holds the session's lease (it applies the session's inputs)."""

    status = HTTPStatus.SERVICE_UNAVAILABLE
    slug = "session-leased"
    title = "Session applied by another instance"

    def __init__(self, session_id: str, retry_after_ms: int) -> None:
        retry_after_s = max(1, -(-retry_after_ms // 1000))
        super().__init__(
            f"session {session_id!r} is applied by another service instance; "
            f"its lease lapses within {retry_after_ms} ms if that instance is gone",
            retry_after_s,
            session=session_id,
            retry_after_ms=retry_after_ms,
        )


class StoreUnavailable(RetryLater):
    """The session store cannot be reached (or cannot write): nothing was stored, retry later.

    Raised by the stores for their backend's connection and I/O errors, so an
    outage answers 503 with ``Retry-After`` and is never mistaken for a bug.
    """

    status = HTTPStatus.SERVICE_UNAVAILABLE
    slug = "store-unavailable"
    title = "Session store unavailable"
    retry_after_s = 2

    def __init__(self, store: str, reason: str) -> None:
        super().__init__(
            f"the {store} store is unavailable ({reason}); nothing was stored, retry later",
            type(self).retry_after_s,
            store=store,
        )


class SessionUnreadable(ServiceError):  # noqa: N818 - HTTP vocabulary
    """The store holds a session it cannot read (corrupt data): the session is quarantined.

    A permanent fault, so no ``Retry-After``: the operator repairs or deletes the
    session (``DELETE`` with the admin token). The answer names the session and
    what of it could not be read, never the stored text.
    """

    status = HTTPStatus.INTERNAL_SERVER_ERROR
    slug = "session-unreadable"
    title = "Session unreadable"

    def __init__(self, session_id: str, what: str) -> None:
        super().__init__(
            f"session {session_id!r} is quarantined: its stored {what} cannot be read (corrupt "
            "data, a permanent fault: retrying will not help; the operator repairs or deletes "
            "it). Other sessions are served.",
            session=session_id,
            unreadable=what,
        )
        self.session_id = session_id
        self.what = what


class StoreCorrupt(ServiceError):  # noqa: N818 - HTTP vocabulary
    """The store's own structure is damaged (e.g. a malformed sqlite file): a permanent fault."""

    status = HTTPStatus.INTERNAL_SERVER_ERROR
    slug = "store-corrupt"
    title = "Session store corrupt"

    def __init__(self, store: str, reason: str) -> None:
        super().__init__(
            f"the {store} store is damaged ({reason}): a permanent fault, retrying will not "
            "help; the operator restores it from a backup",
            store=store,
        )


class RateLimited(RetryLater):
    """More requests than ``limit`` allows ``who`` (:mod:`app.http.rate_limit`)."""

    status = HTTPStatus.TOO_MANY_REQUESTS
    slug = "rate-limited"
    title = "Too many requests"

    def __init__(self, limit: str, rate: str, who: str, retry_after_s: int) -> None:
        super().__init__(
            f"rate limit {limit} = {rate} exceeded for {who}; retry after {retry_after_s} s",
            retry_after_s,
            limit=limit,
            rate=rate,
        )


class BodyTooLarge(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A request body beyond ``limit`` bytes (:mod:`app.http.body_limits`), refused unparsed."""

    status = HTTPStatus.REQUEST_ENTITY_TOO_LARGE
    slug = "body-too-large"
    title = "Body too large"

    def __init__(self, limit: str, maximum: int, declared: int | None) -> None:
        got = "" if declared is None else f" (Content-Length {declared})"
        super().__init__(
            f"request body exceeds limit {limit} = {maximum} bytes{got}",
            limit=limit,
            maximum=maximum,
        )


class BodyTooSlow(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A request body not received within ``limit`` seconds (:mod:`app.http.body_limits`)."""

    status = HTTPStatus.REQUEST_TIMEOUT
    slug = "body-too-slow"
    title = "Request body too slow"

    def __init__(self, limit: str, maximum: float, received: int) -> None:
        super().__init__(
            f"the request body was not received within limit {limit} = "
            f"{maximum} s ({received} bytes received)",
            limit=limit,
            maximum=maximum,
        )


class UnsupportedEncoding(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A body sent with a ``Content-Encoding`` (gzip, …): bodies are read as sent, never inflated
    (a small compressed body can inflate past every size limit)."""

    status = HTTPStatus.UNSUPPORTED_MEDIA_TYPE
    slug = "unsupported-encoding"
    title = "Content-Encoding not supported"

    def __init__(self, encoding: str) -> None:
        super().__init__(
            f"Content-Encoding {encoding[:40]!r} is not supported: send the body as it is "
            "(identity)",
            encoding=encoding[:40],
        )


class HeadersTooLarge(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A request head beyond ``limit`` (:mod:`app.http.transport`), refused unparsed."""

    status = HTTPStatus.REQUEST_HEADER_FIELDS_TOO_LARGE
    slug = "headers-too-large"
    title = "Request headers too large"

    def __init__(self, what: str, limit: str, maximum: int) -> None:
        super().__init__(
            f"request {what} exceed limit {limit} = {maximum}", limit=limit, maximum=maximum
        )


class HeadTooSlow(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A request head not received within ``request_head_timeout`` (:mod:`app.http.transport`)."""

    status = HTTPStatus.REQUEST_TIMEOUT
    slug = "head-too-slow"
    title = "Request head too slow"

    def __init__(self, limit: str, maximum: float) -> None:
        super().__init__(
            f"the request head was not received within limit {limit} = {maximum} s",
            limit=limit,
            maximum=maximum,
        )


class TooManyConnections(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A connection beyond ``max_connections_per_client`` (429) or ``max_connections`` (503)."""

    status = HTTPStatus.SERVICE_UNAVAILABLE
    slug = "too-many-connections"
    title = "Too many connections"

    def __init__(self, limit: str, maximum: int, who: str, status: int) -> None:
        super().__init__(
            f"{who} has {maximum} open connections: limit {limit} = {maximum}; "
            "close one, or reuse one (keep-alive)",
            limit=limit,
            maximum=maximum,
        )
        self._status = status

    @property
    def status_code(self) -> int:
        return self._status


class TrackNotFound(ServiceError):  # noqa: N818 - HTTP vocabulary
    """The session has no live fused track with this id."""

    status = HTTPStatus.NOT_FOUND
    slug = "track-not-found"
    title = "Track not found"

    def __init__(self, session_id: str, track_id: str) -> None:
        super().__init__(
            f"session {session_id!r} has no live fused track {track_id!r}",
            session=session_id,
            track=track_id,
        )


class LimitExceeded(ServiceError):  # noqa: N818 - HTTP vocabulary
    """A configured limit was exceeded; ``limit`` names the setting (``CREDAL_<LIMIT>``)."""

    status = HTTPStatus.UNPROCESSABLE_ENTITY
    slug = "limit-exceeded"
    title = "Limit exceeded"

    def __init__(
        self,
        limit: str,
        maximum: float,
        actual: float | None = None,
        *,
        what: str | None = None,
        status: int | None = None,
        loc: Sequence[str | int] = (),
        retry_after_s: int | None = None,
    ) -> None:
        subject = what or limit
        detail = f"{subject}: limit {limit} is {maximum}" + (
            "" if actual is None else f", got {actual}"
        )
        extensions: dict[str, Any] = {"limit": limit, "maximum": maximum, "actual": actual}
        if retry_after_s is not None:
            extensions["retry_after"] = retry_after_s
        super().__init__(detail, **extensions)
        self._status = int(status) if status is not None else int(type(self).status)
        self.loc = tuple(loc)
        self.retry_after_s = retry_after_s

    def headers(self) -> dict[str, str]:
        return {} if self.retry_after_s is None else {"Retry-After": str(self.retry_after_s)}

    def field_errors(self) -> list[FieldError] | None:
        return [_located(self.loc, self.detail, LIMIT_EXCEEDED)]

    @property
    def status_code(self) -> int:
        return self._status


def _pointer(loc: Sequence[str | int], error_type: str) -> str:
    """A JSON pointer (as a URI fragment) into the body; ``#`` for the whole body."""
    if error_type == "json_invalid":
        return "#"
    parts = list(loc[1:]) if loc and loc[0] == "body" else list(loc)
    escaped = [str(part).replace("~", "~0").replace("/", "~1") for part in parts]
    return "#/" + "/".join(escaped) if escaped else "#"


LIBRARY_PREFIXES = ("Value error, ", "Assertion failed, ")
"""What pydantic puts before a validator's own message; never shown to clients."""


def unknown_key_detail(root: object, loc: Sequence[str | int]) -> str:
    """``unknown key 'x'`` with the keys its object allows and the closest one."""
    path = list(loc[1:]) if loc and loc[0] == "body" else list(loc)
    key = str(path[-1])
    allowed = allowed_keys(root, path[:-1]) if root is not None else None
    if not allowed:
        return f"unknown key {key!r}"
    close = difflib.get_close_matches(key, allowed, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return f"unknown key {key!r} (allowed: {', '.join(allowed)}){hint}"


def _detail(error: Mapping[str, Any], root: object) -> str:
    """The message of one error, without library prefixes; unknown keys list the allowed ones."""
    kind = str(error.get("type", ""))
    message = str(error.get("msg", "invalid"))
    for prefix in LIBRARY_PREFIXES:
        message = message.removeprefix(prefix)
    loc = list(error.get("loc", ()))
    if kind == "json_invalid":
        reason = (error.get("ctx") or {}).get("error")
        at = f" at character {loc[-1]}" if loc and isinstance(loc[-1], int) else ""
        return f"invalid JSON{at}: {reason}" if reason else f"invalid JSON{at}"
    if kind == "extra_forbidden" and loc:
        return unknown_key_detail(root, loc)
    # a tuple once validated (a polygon's vertices) is an array on the wire
    if kind == "tuple_type":
        return "Input should be a valid array"
    return "Array" + message.removeprefix("Tuple") if message.startswith("Tuple ") else message


def field_errors(errors: Iterable[Mapping[str, Any]], root: object = None) -> list[FieldError]:
    """Pydantic/FastAPI error dicts as :class:`FieldError` entries (the input value is never echoed).

    ``root`` is the type the body was validated as (it names the keys an object allows).
    """
    return [
        FieldError(
            loc=list(error.get("loc", ())),
            pointer=_pointer(list(error.get("loc", ())), str(error.get("type", ""))),
            detail=_detail(error, root),
            type=str(error.get("type", "value_error")),
        )
        for error in errors
    ]


def request_validation_error(
    issues: Sequence[FieldIssue], *, prefix: str = "body"
) -> RequestValidationError:
    """A request validation error for ``issues`` found after parsing (locations under ``prefix``)."""
    return RequestValidationError(
        [
            {"loc": (prefix, *issue.loc), "msg": issue.message, "type": issue.kind}
            for issue in issues
        ]
    )


MAX_LISTED_ERRORS = 50
"""Default of ``max_listed_errors``: a 422 lists at most this many errors (``error_count`` has all)."""


def _validation_detail(errors: list[FieldError], total: int) -> str:
    shown = "; ".join(
        f"{error.pointer if error.pointer != '#' else 'body'}: {error.detail}"
        for error in errors[:MAX_ERRORS_IN_DETAIL]
    )
    more = total - min(len(errors), MAX_ERRORS_IN_DETAIL)
    suffix = f"; and {more} more" if more > 0 else ""
    noun = "field" if total == 1 else "fields"
    return f"{total} invalid {noun}: {shown}{suffix}"


def _validation_problem(
    raw: Sequence[Mapping[str, Any]], instance: str | None, listed: int, root: object
) -> Problem:
    """One 422 for every validation error: the first ``listed`` of them and their count.

    A breached configurable limit (an error of type ``limit_exceeded``) makes it a
    ``limit-exceeded`` problem naming the limit, its maximum and the actual size.
    """
    errors = field_errors(raw[:listed], root)
    breach = next((error for error in raw if error.get("type") == LIMIT_EXCEEDED), None)
    slug, title = "validation-error", "Invalid request"
    extensions: dict[str, Any] = {}
    if breach is not None:
        context = breach.get("ctx") or {}
        slug, title = LimitExceeded.slug, LimitExceeded.title
        extensions = {key: context.get(key) for key in ("limit", "maximum", "actual")}
    if len(raw) > len(errors):
        extensions["error_count"] = len(raw)
    return Problem(
        type=problem_type(slug),
        title=title,
        status=HTTPStatus.UNPROCESSABLE_ENTITY,
        detail=_validation_detail(errors, len(raw)),
        instance=instance,
        errors=errors,
        **extensions,
    )


def _located(loc: Sequence[str | int], detail: str, kind: str) -> FieldError:
    full = ["body", *loc] if loc else []
    return FieldError(loc=full, pointer=_pointer(full, kind), detail=detail, type=kind)


def problem_for(
    error: Exception,
    instance: str | None = None,
    *,
    listed: int = MAX_LISTED_ERRORS,
    root: object = None,
) -> Problem:
    """The problem document of any error: the one mapping used by HTTP and WebSocket answers.

    ``listed`` caps the listed validation errors; ``root`` is the type the body was
    validated as (it names the keys an object allows).
    """
    if isinstance(error, RequestValidationError | ValidationError):
        return _validation_problem(list(error.errors()), instance, listed, root)
    if isinstance(error, ServiceError):
        return Problem(
            type=problem_type(error.slug),
            title=error.title,
            status=error.status_code,
            detail=error.detail,
            instance=instance,
            errors=error.field_errors(),
            **error.extensions,
        )
    if isinstance(error, InvalidInput):
        # the core's refusal, located where the core knows the field (``error.loc``)
        return Problem(
            type=problem_type("invalid-input"),
            title="Invalid input",
            status=HTTPStatus.UNPROCESSABLE_ENTITY,
            detail=str(error),
            instance=instance,
            errors=[_located(wire_location(error.loc), str(error), "invalid_input")],
        )
    if isinstance(error, StarletteHTTPException):
        status = HTTPStatus(error.status_code)
        return Problem(
            type=problem_type(status.phrase.lower().replace(" ", "-")),
            title=status.phrase,
            status=error.status_code,
            detail=str(error.detail),
            instance=instance,
        )
    reference = uuid.uuid4().hex
    logger.error("unexpected error (reference %s) on %s", reference, instance, exc_info=error)
    return Problem(
        type=problem_type(ServiceError.slug),
        title=ServiceError.title,
        status=ServiceError.status,
        detail=f"unexpected error; the server log has the details under reference {reference}",
        instance=instance,
        reference=reference,
    )


def error_message(problem: Problem, ref: str | None) -> str:
    """The WebSocket ``error`` message of ``problem`` (``api_schemas.ws.ErrorMessage``), as text."""
    return dumps(
        {"type": "error", "ref": ref, "problem": problem.model_dump(mode="json", exclude_none=True)}
    )


def _headers_of(error: Exception) -> dict[str, str]:
    if isinstance(error, ServiceError):
        return error.headers()
    if isinstance(error, StarletteHTTPException):
        return dict(error.headers or {})
    return {}


def problem_response(
    error: Exception,
    instance: str | None,
    *,
    listed: int = MAX_LISTED_ERRORS,
    root: object = None,
) -> ProblemResponse:
    """The problem+json answer of ``error`` (:func:`problem_for`, with the error's headers).

    What HTTP handlers, middleware and WebSocket upgrade denials send.
    """
    problem = problem_for(error, instance, listed=listed, root=root)
    return ProblemResponse(
        problem.model_dump(mode="json", exclude_none=True),
        status_code=problem.status,
        headers=_headers_of(error),
    )


def problem_answer(request: Request, error: Exception) -> ProblemResponse:
    """The problem+json answer of ``error`` to ``request``."""
    settings = getattr(request.app.state, "settings", None)
    listed = getattr(settings, "max_listed_errors", MAX_LISTED_ERRORS)
    endpoint = request.scope.get("endpoint")
    root = body_model(endpoint) if callable(endpoint) else None
    return problem_response(error, request.url.path, listed=listed, root=root)


async def _on_error(request: Request, error: Exception) -> ProblemResponse:
    return problem_answer(request, error)


def install_error_handlers(
    app: FastAPI, on_internal_error: Callable[[], None] | None = None
) -> None:
    """Register the problem+json handler of every error kind on ``app``.

    Unexpected errors are answered by :class:`InternalErrors` (a middleware, added
    here: call this before adding other middleware so that it runs innermost), not
    by a handler of ``Exception``: Starlette re-raises after such a handler
    answered, and the server then drops the keep-alive connection.
    ``on_internal_error`` is called once per internal error.
    """
    for kind in (RequestValidationError, ServiceError, InvalidInput, StarletteHTTPException):
        app.add_exception_handler(kind, _on_error)
    app.add_middleware(InternalErrors, on_error=on_internal_error or _ignore)


def _ignore() -> None:
    return None


class InternalErrors:
    """ASGI middleware: an unexpected error becomes a 500 problem, counted; the connection stays.

    ``on_error`` is called once per internal error (the metrics count them).
    """

    def __init__(self, app: ASGIApp, on_error: Callable[[], None]) -> None:
        self.app = app
        self.on_error = on_error

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def tracking_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, receive, tracking_send)
        except Exception as error:
            self.on_error()
            if started:
                raise  # half an answer is out: only closing the connection can say so
            await problem_response(error, scope.get("path"))(scope, receive, send)


PROBLEM_STATUSES: dict[int, str] = {
    400: "Malformed request",
    401: "Missing or malformed bearer token",
    403: "The token does not grant access",
    404: "Not found",
    408: "The body did not arrive within ``body_read_timeout`` (the connection is closed)",
    409: "Conflict with the session state",
    413: "Body too large",
    415: "A ``Content-Encoding`` other than identity (bodies are never inflated)",
    422: "Invalid request (every invalid field is listed in `errors`) or a limit exceeded",
    429: "Too many requests (``rate_limit``, with ``Retry-After``) or too many sessions",
    500: "An unexpected error (a ``reference`` to the server log), a quarantined session "
    "(``session-unreadable``: its stored data cannot be read) or a damaged store "
    "(``store-corrupt``): permanent, no ``Retry-After``",
    503: "The session store is unavailable, or another service instance applies this "
    "session's inputs (both with ``Retry-After``)",
}


def problem_responses(*statuses: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries documenting problem+json answers for ``statuses``.

    Every route may answer 429 (the rate limit, :mod:`app.http.rate_limit`) and 500, so they
    are always listed.
    """
    always = {int(HTTPStatus.TOO_MANY_REQUESTS), int(HTTPStatus.INTERNAL_SERVER_ERROR)}
    return {
        status: {"model": Problem, "description": PROBLEM_STATUSES[status]}
        for status in sorted({*statuses, *always})
    }
