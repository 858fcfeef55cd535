"""JSON answers built from plain data (the engine's results are not re-validated on the way out).

Big answers (a 2 000-track picture is ~10 MB) never hold the event loop or the
GIL for long in one piece: their text is written one list item at a time
(:func:`itemwise`, in a worker thread), and the body is sent in slices of
:data:`SLICE_BYTES` (:class:`SlicedResponse`), so the loop serves other
connections between two slices.
"""

from __future__ import annotations

from typing import Any

from fastapi.responses import JSONResponse, Response
from starlette.types import Receive, Scope, Send

from app.outputs.text import dumps, itemwise

__all__ = ["JSONTextResponse", "PlainJSONResponse", "SlicedResponse", "dumps", "itemwise"]

SLICE_BYTES = 256 * 1024
"""A body is handed to the server in pieces of this size."""


class SlicedResponse(Response):
    """An answer whose body goes to the server :data:`SLICE_BYTES` at a time."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        await send(
            {"type": "http.response.start", "status": self.status_code, "headers": self.raw_headers}
        )
        body = self.body
        for start in range(0, max(len(body), 1), SLICE_BYTES):
            end = start + SLICE_BYTES
            await send(
                {
                    "type": "http.response.body",
                    "body": body[start:end],
                    "more_body": end < len(body),
                }
            )
        if self.background is not None:
            await self.background()


class PlainJSONResponse(SlicedResponse, JSONResponse):
    """A JSON answer of plain data; the route's ``response_model`` documents its shape."""

    def render(self, content: Any) -> bytes:
        return dumps(content).encode("utf-8")


class JSONTextResponse(SlicedResponse):
    """A JSON answer whose text is already serialised (a step result, built once per input)."""

    media_type = "application/json"
