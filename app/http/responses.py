"""JSON answers built from plain data (the engine's results are not re-validated on the way out)."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from fastapi.responses import JSONResponse, Response


def dumps(content: Any) -> str:
    """Compact JSON text; a non-finite number raises instead of producing invalid JSON."""
    return json.dumps(content, allow_nan=False, separators=(",", ":"))


def itemwise(document: object, write: Callable[[object], str] = dumps) -> str:
    """``write(document)``, byte for byte, for a compact writer (:func:`dumps`, orjson's
    ``wire_json``) of a document with string keys, written one list item at a time: dicts
    are entered, each list's items written whole (a step result's tracks, pairs and matrix
    rows; a logged report's tracks). Each call of the writer stays small, so no single C
    call holds the GIL, stalling the event loop, for the whole of a 10 MB answer."""
    if isinstance(document, dict):
        members = (f"{write(key)}:{itemwise(value, write)}" for key, value in document.items())
        return "{" + ",".join(members) + "}"
    if isinstance(document, list):
        return "[" + ",".join(write(item) for item in document) + "]"
    return write(document)


class PlainJSONResponse(JSONResponse):
    """A JSON answer of plain data; the route's ``response_model`` documents its shape."""

    def render(self, content: Any) -> bytes:
        return dumps(content).encode("utf-8")


class JSONTextResponse(Response):
    """A JSON answer whose text is already serialised (a step result, built once per input)."""

    media_type = "application/json"
