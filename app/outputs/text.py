"""Compact JSON text, written a list item at a time: what every output writer produces.

Big answers (a 2 000-track picture is ~10 MB) never hold the event loop or the
GIL for long in one piece: their text is written one list item at a time
(:func:`itemwise`, in a worker thread); the HTTP edge then sends the body in
slices (:class:`app.http.responses.SlicedResponse`).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from typing import Any


def dumps(content: Any) -> str:
    """Compact JSON text; a non-finite number raises instead of producing invalid JSON."""
    return json.dumps(content, allow_nan=False, separators=(",", ":"))


def itemwise(document: object, write: Callable[[object], str] = dumps) -> str:
    """``write(document)``, byte for byte, for a compact writer (:func:`dumps`, orjson's
    ``wire_json``) of a document with string keys, written one list item at a time: dicts
    are entered, each list's items written whole (a step result's tracks, pairs and matrix
    rows; a logged report's tracks). Each call of the writer stays small, so no single C
    call holds the GIL, stalling the event loop, for the whole of a 10 MB answer.

    An iterator stands for a list whose items are made as they are written (a step's
    tracks built from the engine's views): each is freed once written, so no big
    structure is freed in one piece (a deallocation holds the GIL throughout too)."""
    if isinstance(document, dict):
        members = (f"{write(key)}:{itemwise(value, write)}" for key, value in document.items())
        return "{" + ",".join(members) + "}"
    if isinstance(document, list | Iterator):
        return "[" + ",".join(write(item) for item in document) + "]"
    return write(document)
