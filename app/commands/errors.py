"""CLI failures as one line each: what failed, and what to do about it.

A command raises :class:`CommandError` for a failure the user can act on (a
refused request, a malformed event file); :func:`one_line` also words the
usual foreign failures (the server does not answer, a file is missing).
``credal-fusion --debug`` shows the traceback instead.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import httpx

MAX_DETAIL_CHARS = 300
"""A server's answer quoted in a message is cut to this length."""

HINTS = {
    401: "pass the session's token with --token (printed when the session was created)",
    403: "check --token: it must be this session's token (or the admin token)",
    404: "check --session, --token and --server: the session may have ended (idle timeout or "
    "DELETE), or the token is not its own (a token that does not open a session gets 404)",
    409: "the session refused this input in its current state (see the detail)",
    413: "the body is over the server's limit (CREDAL_MAX_BODY_BYTES and the other limits)",
    422: "the body was refused: the detail names the field",
    429: "too many requests for this tenant: wait and try again (or raise its limits)",
    503: "the server is not ready (store unavailable or session leased): try again shortly",
}


class CommandError(Exception):
    """A failure the user can act on; its message is the whole line the CLI prints."""


def http_failure(method: str, path: str, status: int, body: Any) -> CommandError:
    """A refused request, from the problem+json answer (or whatever text the server sent)."""
    if isinstance(body, dict):
        detail = str(body.get("detail") or body.get("title") or body)
    else:
        detail = str(body)
    detail = " ".join(detail.split())[:MAX_DETAIL_CHARS]
    hint = HINTS.get(status, "see the server's log" if status >= 500 else "see the detail")
    return CommandError(f"{method} {path} answered {status}: {detail} ({hint})")


def raise_for_problem(answer: httpx.Response) -> None:
    """Raise a one-line :class:`CommandError` if ``answer`` is not a success."""
    if answer.is_success:
        return
    try:
        body = answer.json()
    except ValueError:
        body = answer.text
    raise http_failure(answer.request.method, answer.request.url.path, answer.status_code, body)


def pydantic_line(error: Any) -> str:
    """A pydantic ``ValidationError`` in one line: the first invalid field (and how many more)."""
    errors = error.errors()
    first = errors[0]
    where = ".".join(str(part) for part in first.get("loc", ())) or "the body"
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return f"{where}: {first.get('msg', 'invalid')}{more}"


def one_line(error: BaseException) -> str:
    """What failed and what to do, in one line, for any exception a command lets through."""
    import httpx  # lazily: the CLI's start-up stays light

    if isinstance(error, CommandError):
        return str(error)
    if isinstance(error, httpx.TransportError):
        try:
            url = error.request.url
            server = f"{url.scheme}://{url.netloc.decode()}"
        except RuntimeError:  # no request attached
            server = "the server"
        if isinstance(error, httpx.ConnectError):
            return (
                f"cannot connect to {server} ({error or 'connection refused'}): "
                "is the service running? start it with `credal-fusion serve` "
                "(or `make run`), or fix --server"
            )
        if isinstance(error, httpx.TimeoutException):
            return f"{server} did not answer in time: check that it is the credal-fusion service"
        return f"the connection to {server} failed ({type(error).__name__}: {error})"
    from core.errors import CredalError

    if isinstance(error, CredalError):  # the engine refused an input (as the server would: 4xx)
        return f"the engine refused an input: {error}"
    if isinstance(error, FileNotFoundError):
        return f"no such file: {error.filename} (check the path)"
    if isinstance(error, OSError):
        return f"cannot use {error.filename or 'a file'}: {error.strerror or error}"
    return f"unexpected {type(error).__name__}: {error} (run again with --debug for the traceback)"
