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

import logging
import uuid
from collections.abc import Iterable, Mapping, Sequence
from http import HTTPStatus
from typing import Any, ClassVar

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException as StarletteHTTPException

from api_schemas.issues import FieldIssue
from api_schemas.problem import FieldError, Problem
from core.errors import InvalidInput

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


class SessionLeased(ServiceError):  # noqa: N818 - HTTP vocabulary
    """Another service instance holds the session's lease (it applies the session's inputs)."""

    status = HTTPStatus.SERVICE_UNAVAILABLE
    slug = "session-leased"
    title = "Session applied by another instance"

    def __init__(self, session_id: str, retry_after_s: int) -> None:
        super().__init__(
            f"session {session_id!r} is applied by another service instance; "
            f"its lease lapses within {retry_after_s} s if that instance is gone",
            session=session_id,
            retry_after=retry_after_s,
        )
        self.retry_after_s = retry_after_s

    def headers(self) -> dict[str, str]:
        return {"Retry-After": str(self.retry_after_s)}


class StoreUnavailable(ServiceError):  # noqa: N818 - HTTP vocabulary
    """The session store cannot be reached (or cannot write): nothing was stored, retry later.

    Raised by the stores for their backend's connection and I/O errors, so an
    outage answers 503 with ``Retry-After`` and is never mistaken for a bug.
    """

    status = HTTPStatus.SERVICE_UNAVAILABLE
    slug = "store-unavailable"
    title = "Session store unavailable"
    retry_after_s: ClassVar[int] = 2

    def __init__(self, store: str, reason: str) -> None:
        super().__init__(
            f"the {store} store is unavailable ({reason}); nothing was stored, retry later",
            store=store,
            retry_after=self.retry_after_s,
        )

    def headers(self) -> dict[str, str]:
        return {"Retry-After": str(self.retry_after_s)}


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
    ) -> None:
        subject = what or limit
        detail = f"{subject}: limit {limit} is {maximum}" + (
            "" if actual is None else f", got {actual}"
        )
        super().__init__(detail, limit=limit, maximum=maximum, actual=actual)
        self._status = int(status) if status is not None else int(type(self).status)

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


def field_errors(errors: Iterable[Mapping[str, Any]]) -> list[FieldError]:
    """Pydantic/FastAPI error dicts as :class:`FieldError` entries (the input value is never echoed)."""
    return [
        FieldError(
            loc=list(error.get("loc", ())),
            pointer=_pointer(list(error.get("loc", ())), str(error.get("type", ""))),
            detail=str(error.get("msg", "invalid")),
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


def problem_response(
    request: Request | None,
    *,
    status: int,
    slug: str,
    title: str,
    detail: str,
    errors: list[FieldError] | None = None,
    headers: Mapping[str, str] | None = None,
    instance: str | None = None,
    **extensions: Any,
) -> ProblemResponse:
    """Build a problem+json response (``instance`` defaults to the request path)."""
    problem = Problem(
        type=problem_type(slug),
        title=title,
        status=status,
        detail=detail,
        instance=instance if instance is not None or request is None else request.url.path,
        errors=errors,
        **extensions,
    )
    return ProblemResponse(
        problem.model_dump(mode="json", exclude_none=True),
        status_code=status,
        headers=dict(headers or {}),
    )


def _validation_detail(errors: list[FieldError]) -> str:
    shown = "; ".join(
        f"{error.pointer if error.pointer != '#' else 'body'}: {error.detail}"
        for error in errors[:MAX_ERRORS_IN_DETAIL]
    )
    more = len(errors) - MAX_ERRORS_IN_DETAIL
    suffix = f"; and {more} more" if more > 0 else ""
    noun = "field" if len(errors) == 1 else "fields"
    return f"{len(errors)} invalid {noun}: {shown}{suffix}"


async def _on_validation_error(request: Request, error: Exception) -> ProblemResponse:
    assert isinstance(error, RequestValidationError)
    errors = field_errors(error.errors())
    return problem_response(
        request,
        status=HTTPStatus.UNPROCESSABLE_ENTITY,
        slug="validation-error",
        title="Invalid request",
        detail=_validation_detail(errors),
        errors=errors,
    )


async def _on_service_error(request: Request, error: Exception) -> ProblemResponse:
    assert isinstance(error, ServiceError)
    return problem_response(
        request,
        status=error.status_code,
        slug=error.slug,
        title=error.title,
        detail=error.detail,
        headers=error.headers(),
        **error.extensions,
    )


async def _on_invalid_input(request: Request, error: Exception) -> ProblemResponse:
    return problem_response(
        request,
        status=HTTPStatus.UNPROCESSABLE_ENTITY,
        slug="invalid-input",
        title="Invalid input",
        detail=str(error),
    )


async def _on_http_error(request: Request, error: Exception) -> ProblemResponse:
    assert isinstance(error, StarletteHTTPException)
    status = HTTPStatus(error.status_code)
    return problem_response(
        request,
        status=error.status_code,
        slug=status.phrase.lower().replace(" ", "-"),
        title=status.phrase,
        detail=str(error.detail),
        headers=error.headers,
    )


async def _on_unexpected_error(request: Request, error: Exception) -> ProblemResponse:
    reference = uuid.uuid4().hex
    logger.error(
        "unexpected error (reference %s) on %s", reference, request.url.path, exc_info=error
    )
    return problem_response(
        request,
        status=HTTPStatus.INTERNAL_SERVER_ERROR,
        slug="internal-error",
        title="Internal server error",
        detail=f"unexpected error; the server log has the details under reference {reference}",
        reference=reference,
    )


def problem_for(error: Exception, instance: str | None = None) -> Problem:
    """The problem document of any error (the WebSocket channel's ``error`` messages use it)."""
    if isinstance(error, RequestValidationError):
        errors = field_errors(error.errors())
        return Problem(
            type=problem_type("validation-error"),
            title="Invalid request",
            status=HTTPStatus.UNPROCESSABLE_ENTITY,
            detail=_validation_detail(errors),
            instance=instance,
            errors=errors,
        )
    if isinstance(error, ServiceError):
        return Problem(
            type=problem_type(error.slug),
            title=error.title,
            status=error.status_code,
            detail=error.detail,
            instance=instance,
            **error.extensions,
        )
    if isinstance(error, InvalidInput):
        return Problem(
            type=problem_type("invalid-input"),
            title="Invalid input",
            status=HTTPStatus.UNPROCESSABLE_ENTITY,
            detail=str(error),
            instance=instance,
        )
    reference = uuid.uuid4().hex
    logger.error("unexpected error (reference %s) on %s", reference, instance, exc_info=error)
    return Problem(
        type=problem_type("internal-error"),
        title="Internal server error",
        status=HTTPStatus.INTERNAL_SERVER_ERROR,
        detail=f"unexpected error; the server log has the details under reference {reference}",
        instance=instance,
        reference=reference,
    )


def install_error_handlers(app: FastAPI) -> None:
    """Register every problem+json handler on ``app``."""
    app.add_exception_handler(RequestValidationError, _on_validation_error)
    app.add_exception_handler(ServiceError, _on_service_error)
    app.add_exception_handler(InvalidInput, _on_invalid_input)
    app.add_exception_handler(StarletteHTTPException, _on_http_error)
    app.add_exception_handler(Exception, _on_unexpected_error)


PROBLEM_STATUSES: dict[int, str] = {
    400: "Malformed request",
    401: "Missing or malformed bearer token",
    403: "The token does not grant access",
    404: "Not found",
    409: "Conflict with the session state",
    413: "Body too large",
    422: "Invalid request (every invalid field is listed in `errors`) or a limit exceeded",
    429: "Too many requests (``rate_limit``, with ``Retry-After``) or too many sessions",
    503: "The session store is unavailable, or another service instance applies this "
    "session's inputs (both with ``Retry-After``)",
}


def problem_responses(*statuses: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries documenting problem+json answers for ``statuses``.

    Every route may answer 429 (the rate limit, :mod:`app.rate_limit`), so it is always listed.
    """
    return {
        status: {"model": Problem, "description": PROBLEM_STATUSES[status]}
        for status in sorted({*statuses, int(HTTPStatus.TOO_MANY_REQUESTS)})
    }
