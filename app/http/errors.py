"""Every error answer of the service, as RFC 9457 ``application/problem+json``: the edge.

The service raises the errors of :mod:`app.errors` (its one tree, free of
HTTP frameworks; re-exported here for the edge's code), or lets request
validation, core ``InvalidInput`` and Starlette HTTP errors happen;
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
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from api_schemas.issues import wire_location
from api_schemas.keys import allowed_keys, body_path
from api_schemas.limits import LIMIT_EXCEEDED
from api_schemas.problem import FieldError, Problem
from app.errors import (
    MAX_LISTED_ERRORS,
    BodyTooLarge,
    BodyTooSlow,
    Conflict,
    Forbidden,
    HeadersTooLarge,
    HeadTooSlow,
    IdempotencyKeyReused,
    InvalidFields,
    LimitExceeded,
    RateLimited,
    RetryLater,
    ServiceError,
    SessionLeased,
    SessionNotFound,
    SessionUnreadable,
    StaleReport,
    StoreCorrupt,
    StoreUnavailable,
    TooManyConnections,
    TrackNotFound,
    Unauthorized,
    UnsupportedEncoding,
    located,
    pointer,
)
from app.http.requests import body_model
from app.http.responses import dumps
from core.errors import InvalidInput

__all__ = [
    "MAX_LISTED_ERRORS",
    "BodyTooLarge",
    "BodyTooSlow",
    "Conflict",
    "Forbidden",
    "HeadTooSlow",
    "HeadersTooLarge",
    "IdempotencyKeyReused",
    "InvalidFields",
    "LimitExceeded",
    "RateLimited",
    "RetryLater",
    "ServiceError",
    "SessionLeased",
    "SessionNotFound",
    "SessionUnreadable",
    "StaleReport",
    "StoreCorrupt",
    "StoreUnavailable",
    "TooManyConnections",
    "TrackNotFound",
    "Unauthorized",
    "UnsupportedEncoding",
    "install_error_handlers",
    "problem_for",
    "problem_response",
    "problem_responses",
]

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
    found = []
    for error in errors:
        loc = list(error.get("loc", ()))
        if root is not None:
            loc = body_path(root, loc)  # where the value is in the body: no union tags
        found.append(
            FieldError(
                loc=loc,
                pointer=pointer(loc, str(error.get("type", ""))),
                detail=_detail(error, root),
                type=str(error.get("type", "value_error")),
            )
        )
    return found


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
    if isinstance(error, RequestValidationError | ValidationError | InvalidFields):
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
            errors=[located(wire_location(error.loc), str(error), "invalid_input")],
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
