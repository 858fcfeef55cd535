"""The service's errors: one tree, free of HTTP frameworks.

Every error the service raises on purpose is a :class:`ServiceError` that
knows its status, its problem ``slug`` and title, and the fields at fault.
Stores, translation, the input kinds and the registry raise them;
:mod:`app.http.errors` maps each to an RFC 9457 problem at the edge (HTTP
answers and WebSocket ``error`` messages alike). :class:`InvalidFields` is
the domain's validation error: the fields of an input or a config that its
session refuses, located as pydantic locates a body's.
"""

from __future__ import annotations

from collections.abc import Sequence
from http import HTTPStatus
from typing import Any, ClassVar

from api_schemas.issues import FieldIssue
from api_schemas.limits import LIMIT_EXCEEDED
from api_schemas.problem import FieldError
from core.errors import StaleReport as CoreStaleReport
from core.errors import stale_message

MAX_LISTED_ERRORS = 50
"""Default of ``max_listed_errors``: a 422 lists at most this many errors (``error_count`` has all)."""


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

    def __init__(
        self, sensor: str, time: float, last_time: float, window: float | None = None
    ) -> None:
        super().__init__(
            f"report of sensor {sensor!r} at time {time!r} is not newer than its last accepted report at time {last_time!r}"
            if window is None
            else stale_message(sensor, time, last_time, window),
            sensor=sensor,
            time=time,
            last_time=last_time,
        )

    def field_errors(self) -> list[FieldError] | None:
        return [located(CoreStaleReport.loc, self.detail, "stale_report")]


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


class Overload(RetryLater):
    """An input refused because the instance could not answer it in time (503 ``overloaded``,
    ``Retry-After``), before it was applied: ``limit`` names the measure that refused it."""

    status = HTTPStatus.SERVICE_UNAVAILABLE
    slug = "overloaded"
    title = "Service overloaded"
    retry_after_s = 1
    AFTER = "the input was not applied, send it again after Retry-After (to any instance)"


class Overloaded(Overload):
    """The instance runs behind (its event loop late by more than ``overload_delay_ms``): a new
    input is refused before any work, so the inputs it accepts are answered in time."""

    def __init__(self, delay_ms: float, limit_ms: float) -> None:
        super().__init__(
            f"this instance runs {delay_ms:.0f} ms behind (limit overload_delay_ms = "
            f"{limit_ms:g}): {self.AFTER}",
            type(self).retry_after_s,
            limit="overload_delay_ms",
            delay_ms=round(delay_ms),
        )


class TooLate(Overload):
    """An input that waited longer than ``max_queue_ms`` for its step (for the event loop, its
    session's lock, its tenant's turn): refused before it is applied rather than answered late."""

    def __init__(self, queued_ms: float, limit_ms: float) -> None:
        super().__init__(
            f"this input waited {queued_ms:.0f} ms for its turn (limit max_queue_ms = "
            f"{limit_ms:g}): {self.AFTER}",
            type(self).retry_after_s,
            limit="max_queue_ms",
            queued_ms=round(queued_ms),
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
        return [located(self.loc, self.detail, LIMIT_EXCEEDED)]

    @property
    def status_code(self) -> int:
        return self._status


class InvalidFields(ServiceError):  # noqa: N818 - HTTP vocabulary
    """Fields that the session refuses, found after parsing (a 422 listing every one).

    ``prefix`` is where the locations start (``body``, ``query``); :meth:`errors`
    gives them in pydantic's form, so the edge answers them as it answers a body
    that failed validation.
    """

    status = HTTPStatus.UNPROCESSABLE_ENTITY
    slug = "validation-error"
    title = "Invalid request"

    def __init__(self, issues: Sequence[FieldIssue], *, prefix: str = "body") -> None:
        super().__init__("; ".join(issue.message for issue in issues))
        self.issues = tuple(issues)
        self.prefix = prefix

    def errors(self) -> list[dict[str, Any]]:
        """The issues as pydantic error dicts (``loc`` under :attr:`prefix`)."""
        return [
            {"loc": (self.prefix, *issue.loc), "msg": issue.message, "type": issue.kind}
            for issue in self.issues
        ]


def pointer(loc: Sequence[str | int], error_type: str) -> str:
    """A JSON pointer (as a URI fragment) into the body; ``#`` for the whole body."""
    if error_type == "json_invalid":
        return "#"
    parts = list(loc[1:]) if loc and loc[0] == "body" else list(loc)
    escaped = [str(part).replace("~", "~0").replace("/", "~1") for part in parts]
    return "#/" + "/".join(escaped) if escaped else "#"


def located(loc: Sequence[str | int], detail: str, kind: str) -> FieldError:
    full = ["body", *loc] if loc else []
    return FieldError(loc=full, pointer=pointer(full, kind), detail=detail, type=kind)
