"""JSON answers built from plain data (the engine's results are not re-validated on the way out)."""

from __future__ import annotations

import json
from typing import Any

from fastapi.responses import JSONResponse, Response


def dumps(content: Any) -> str:
    """Compact JSON text; a non-finite number raises instead of producing invalid JSON."""
    return json.dumps(content, allow_nan=False, separators=(",", ":"))


class PlainJSONResponse(JSONResponse):
    """A JSON answer of plain data; the route's ``response_model`` documents its shape."""

    def render(self, content: Any) -> bytes:
        return dumps(content).encode("utf-8")


class JSONTextResponse(Response):
    """A JSON answer whose text is already serialised (a step result, built once per input)."""

    media_type = "application/json"
