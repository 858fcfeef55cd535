"""The input kinds of a session, in one registry (:class:`~app.inputs.base.InputKind`).

``POST /v1/sessions/{sid}/{tag}``, the WebSocket ``stream`` message types, the
log's ``type``, ``GET …/events``, replay (local and remote), the CLI and
``docs/asyncapi.yaml`` all iterate :data:`INPUT_KINDS`. Adding a kind is one
module and one :func:`register_input_kind` call below.
"""

from __future__ import annotations

import functools
from typing import Annotated, Any, Union

from pydantic import Field, TypeAdapter

from api_schemas.base import WireModel

# ASTERIX from app.inputs.asterix import Asterix
from app.inputs.asterix import Asterix
from app.inputs.base import Applied, Decoded, DecodedKind, Input, InputKind, SessionView
from app.inputs.detections import Detections
from app.inputs.tracks import Tracks

INPUT_KINDS: dict[str, InputKind[Any]] = {}
"""Tag → input kind whose body is a JSON report, in registration order."""
DECODED_KINDS: dict[str, DecodedKind[Any]] = {}
"""Tag → input kind whose body is bytes decoded into JSON kinds' inputs (ASTERIX)."""


def register_input_kind(kind: InputKind[Any] | DecodedKind[Any]) -> None:
    """Add ``kind`` to the registry (its tag must be new)."""
    if kind.tag in INPUT_KINDS or kind.tag in DECODED_KINDS:
        raise ValueError(f"input kind {kind.tag!r} is registered already")
    if isinstance(kind, DecodedKind):
        DECODED_KINDS[kind.tag] = kind
    else:
        INPUT_KINDS[kind.tag] = kind


def input_kind(tag: str) -> InputKind[Any]:
    """The kind registered under ``tag`` (``KeyError`` naming the known ones)."""
    kind = INPUT_KINDS.get(tag)
    if kind is None:
        raise KeyError(f"unknown input type {tag!r} (known: {', '.join(INPUT_KINDS)})")
    return kind


def parse_input(tag: str, body: dict[str, Any]) -> Input:
    """A plain body of kind ``tag`` validated as its report."""
    kind = input_kind(tag)
    return Input(kind, kind.parse(body))


def client_messages() -> TypeAdapter[Any]:
    """The WebSocket ``stream`` client messages: every kind's message, tagged by ``type``."""
    return _client_messages(tuple(kind.message_model for kind in INPUT_KINDS.values()))


@functools.cache
def _client_messages(models: tuple[type[WireModel], ...]) -> TypeAdapter[Any]:
    union = Union[models] if len(models) > 1 else models[0]  # noqa: UP007 - built at run time
    return TypeAdapter(Annotated[union, Field(discriminator="type")])  # type: ignore[arg-type]


def message_input(message: Any) -> Input:
    """The input a validated client message carries."""
    kind = INPUT_KINDS[message.type]
    return Input(kind, kind.of_message(message))


register_input_kind(Tracks())
register_input_kind(Detections())
register_input_kind(Asterix())
# ASTERIX register_input_kind(Asterix())

__all__ = [
    "DECODED_KINDS",
    "INPUT_KINDS",
    "Applied",
    "Decoded",
    "DecodedKind",
    "Input",
    "InputKind",
    "SessionView",
    "client_messages",
    "input_kind",
    "message_input",
    "parse_input",
    "register_input_kind",
]
