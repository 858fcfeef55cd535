"""RFC 9457 problem details (``application/problem+json``)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class FieldError(BaseModel):
    """One validation error: where (``loc`` and a JSON pointer into the body) and what."""

    model_config = ConfigDict(extra="forbid")

    loc: list[str | int]
    pointer: str
    detail: str
    type: str


class Problem(BaseModel):
    """An error answer. ``type`` is machine-readable; ``errors`` lists every invalid field.

    Extension members (such as ``limit`` and ``maximum`` for a limit breach)
    may be added; clients ignore members they do not know.
    """

    model_config = ConfigDict(extra="allow")

    type: str
    title: str
    status: int
    detail: str
    instance: str | None = None
    errors: list[FieldError] | None = None
    error_count: int | None = None
    """How many errors there were when ``errors`` lists only the first ones (``max_listed_errors``)."""
