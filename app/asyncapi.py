"""``docs/asyncapi.yaml``: the WebSocket protocol, generated from the message models.

OpenAPI cannot describe WebSockets; this AsyncAPI 3.0 document does, with
the payload schemas taken from :mod:`api_schemas.ws` so that it cannot
disagree with what the service validates. ``make openapi`` rewrites it and a
test fails when the committed file drifts.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, create_model
from pydantic.json_schema import models_json_schema

from api_schemas.base import WireModel
from api_schemas.ws import AckMessage, ErrorMessage, GapMessage, ResultMessage
from app.inputs import DECODED_KINDS, INPUT_KINDS, DecodedKind
from app.outputs import FRAMES, OUTPUT_FORMATS
from core import __version__

DEFAULT_PATH = Path("docs") / "asyncapi.yaml"
SCHEMA_REF = "#/components/schemas/{model}"

Direction = Literal["client", "server"]

MESSAGES: dict[str, tuple[type[BaseModel], Direction, str]] = {
    **{tag: (kind.message_model, "client", kind.summary) for tag, kind in INPUT_KINDS.items()},
    "result": (
        ResultMessage,
        "server",
        "The fused result of one input; `ref` echoes the input's `ref`.",
    ),
    "error": (
        ErrorMessage,
        "server",
        "A rejected message (RFC 9457 problem); the connection stays open.",
    ),
    "ack": (
        AckMessage,
        "server",
        "Sent once when the connection is ready, with the session's latest `seq`.",
    ),
    "gap": (
        GapMessage,
        "server",
        "`subscribe` only: the results after `after` and before `next` were not delivered; "
        "read `GET …/tracks` for the current picture.",
    ),
}
"""Message name (its ``type`` tag) → model, who sends it, what it means; a decoded kind
(:data:`~app.inputs.DECODED_KINDS`) adds its answer here and its binary message below."""


def decoded_answer(kind: DecodedKind[Any]) -> type[BaseModel]:
    """The server's ``<tag>_result`` message answering a decoded kind's binary message."""
    tag = f"{kind.tag}_result"
    name = "".join(part.title() for part in tag.split("_")) + "Message"
    model: type[BaseModel] = create_model(
        name,
        __base__=WireModel,
        __doc__=f"Server → client: the answer to a `{kind.tag}` binary message.",
        type=(Literal[tag], ...),  # type: ignore[arg-type]
        ref=(str | None, ...),
        result=(kind.answer_model, ...),
    )
    return model


for _kind in DECODED_KINDS.values():
    MESSAGES[f"{_kind.tag}_result"] = (
        decoded_answer(_kind),
        "server",
        f"The answer to a `{_kind.tag}` binary message.",
    )


def _binary_message(kind: DecodedKind[Any]) -> dict[str, Any]:
    return {
        "name": kind.tag,
        "title": f"{kind.tag} (binary)",
        "summary": kind.summary,
        "contentType": kind.media_type,
        "payload": {"type": "string", "format": "binary"},
        "x-direction": "client",
        "x-query": kind.parameters.model_json_schema(),
    }


DESCRIPTION = """\
Every message is one JSON object (a text frame) with a required `type` tag, but the
binary messages of the decoded kinds (bytes of a surveillance format, listed below with
their content type; a binary frame whose first byte is not `{` or `[`), each answered by
one `<kind>_result` (or `error`); the connection's query gives that kind's parameters
(its `x-query`; `?decode=` names the kind when several are registered).

`stream`: the client sends `tracks` and `detections` messages (the REST bodies
plus `type` and an optional `ref`); the server answers each with exactly one
`result` or `error`, in the order the inputs were sent. A bad message gets an
`error` that names the problem (field paths in `problem.errors`) and the
client's `ref`; the connection stays open. That holds for every kind of bad
message: not JSON, nested too deep, duplicate keys, invalid UTF-8 in a binary
frame, a message larger than `CREDAL_MAX_BODY_BYTES`, more than
`CREDAL_WS_MESSAGES_PER_SECOND` messages in a second (an `error` with status
429, the message not applied). The one exception: a message beyond 4 times
`CREDAL_MAX_BODY_BYTES` is not parsed; its `error` (422 `limit-exceeded`,
`limit` `max_body_bytes`, `ref` null) is the last message before the server
closes the connection with 1009. The server then half-closes and reads and
discards the rest of the message and the client's close until the client
closes its side (at most 8 MB or 2 s), so that the client receives both
rather than a connection reset.

Backpressure: the server keeps at most 16 answers per `stream` connection;
when the client does not read them, the server stops reading its messages
and TCP pushes back on the client. Nothing grows without bound.

Messages are not compressed: the server declines `permessage-deflate`
(compressing a 10 MB result would hold its event loop ~200 ms).

A `detections` message runs the sensor's local tracker (the sensor needs a
`measurement` model in the session config) and then the fusion step, like
`POST …/detections`.

`subscribe`: after the `ack` (its `seq` is the session's latest input), the
server sends every later `result` of the session, in order, with `ref` null:
every `seq`, or an explicit `gap` message (`after`, `next`) just before a
result that does not follow the last one sent. A gap comes from a subscriber
that cannot keep up (it keeps the latest 64 results and skips older ones: it
is never queued without bound) or from an instance that died between logging
an input and publishing its result; on a `gap`, read `GET …/tracks` for the
current picture. Messages sent by the client on this channel are ignored. When the session ends (deleted or
expired) the server closes the connection with code 1000, reason `session
ended`; when the session store (or, with Redis, its pub/sub connection) fails
it closes with code 1013, reason `store unavailable`: subscribe again once
`GET /readyz` answers 200. An input sent on `stream` while the store is down
gets an `error` with the 503 `store-unavailable` problem and is not applied.
An input sent to an instance that runs behind (its event loop later than
`CREDAL_OVERLOAD_DELAY_MS` on average, 200 ms by default, while its tenant
holds at least its share of the inputs in flight), or one that waited longer
than `CREDAL_MAX_QUEUE_MS` (500 ms by default) for its step while other
inputs' steps ran, gets an `error` with the 503 `overloaded` problem (its
`limit` names which), refused before its step: it was not applied, and the
connection stays open; send it again after the problem's `retry_after`
seconds (on this connection, or to another instance). A tenant with
`CREDAL_TENANT_MAX_IN_FLIGHT` inputs in flight on the instance gets an `error`
with a 429 `limit-exceeded` problem naming `tenant_max_in_flight` for the
next, also unapplied.

Clients and failures (the reference client is `app/commands/resilient.py`):

- `seq` numbers the session's applied inputs, one by one; the `ack` of a
  connection carries the session's latest. An input is applied once its
  `result` arrives, and only then.
- A 503 (`store-unavailable` or `session-leased`), an `error` carrying one, or
  a connection that closed (1013 `store unavailable`, `session taken over`, a
  dead instance) means: the inputs not yet answered may or may not have been
  applied. Wait `Retry-After` seconds (a leased session: the lease's time left,
  at most `CREDAL_LEASE_TTL_MS`, 3 s by default; another instance takes a dead
  instance's sessions over within it), reconnect (any instance), and read the
  new `ack.seq`. A sender that keeps one input in flight at a time knows: if
  `ack.seq` is its last answered `seq` + 1, its pending input was applied
  (do not resend it); if it equals its last answered `seq`, it was lost: send
  it again. A message with an `idempotency_key` (the REST `Idempotency-Key`
  header) can always be resent: it is logged with its input in the same store
  write, so any instance, after a restart or a takeover, sends its first
  `result` again instead of applying it twice (a session keeps its latest 256
  keys).
- While a `stream` is open, its instance renews the session's lease every
  third of the TTL; if another instance took the session over meanwhile, the
  stream closes with 1013 `session taken over`: reconnect.

Both channels take the query parameters `format` and `frame` on connect
(`…/stream?frame=geodetic`, `…/subscribe?format=geojson`), as the REST inputs
and reads do: with `frame=geodetic`, every fused track of every `result` sent on
the connection carries `geodetic: {lat, lon, alt}` (WGS84) beside its
session-frame `state`; with `format=geojson` every `result` is a GeoJSON
FeatureCollection (with `seq`, `time`, `sensor`). Both need the session's
`origin`; without one, or for an unknown value, the upgrade is refused with the
422 problem naming `query/frame` or `query/format`.

Both channels need the session's bearer token (or the admin token) in the
`Authorization` header of the upgrade request, or, from a browser (which
cannot set headers on an upgrade), offered as the two subprotocols `bearer`
and the token (the server accepts `bearer`); a refused upgrade gets the
REST route's problem+json answer (401, 404 or 429). With the redis
store, `subscribe` on any instance receives the results applied on any
other. The server sends
WebSocket pings every `CREDAL_WS_PING_INTERVAL` seconds; a peer that does not
answer within `CREDAL_WS_PING_TIMEOUT` is disconnected (1011) unless it is
visibly alive or behind: it sent data since the ping, or answers to it are
still queued (its pong waits behind them). A client whose results are queued
is never cut by the keepalive.
"""


def _message(name: str) -> dict[str, Any]:
    model, direction, summary = MESSAGES[name]
    return {
        "name": name,
        "title": model.__name__,
        "summary": summary,
        "contentType": "application/json",
        "payload": {"$ref": SCHEMA_REF.format(model=model.__name__)},
        "x-direction": direction,
    }


def _refs(names: Sequence[str], prefix: str) -> list[dict[str, str]]:
    return [{"$ref": f"{prefix}/{name}"} for name in names]


FRAME_QUERY: dict[str, Any] = {
    "type": "object",
    "properties": {
        "frame": {
            "type": "string",
            "enum": list(FRAMES),
            "default": "session",
            "description": (
                "geodetic: every fused track of every `result` on this connection carries "
                "`geodetic: {lat, lon, alt}` (WGS84; the session needs an `origin`, else the "
                "upgrade is refused with 422 at `query/frame`)"
            ),
        },
        "format": {
            "type": "string",
            "enum": list(OUTPUT_FORMATS),
            "default": "json",
            "description": "every `result` on this connection in this output format: "
            + "; ".join(f"{name}: {f.description}" for name, f in OUTPUT_FORMATS.items()),
        },
    },
}
"""The query parameters of both channels' upgrade request (the REST routes' ``format`` and
``frame``)."""


def _channel(address: str, description: str, names: Sequence[str]) -> dict[str, Any]:
    return {
        "address": address,
        "description": description,
        "parameters": {"sid": {"description": "The session id."}},
        "messages": {name: {"$ref": f"#/components/messages/{name}"} for name in names},
        "bindings": {"ws": {"query": FRAME_QUERY, "bindingVersion": "0.1.0"}},
    }


def payload_schemas() -> dict[str, Any]:
    """JSON schemas of every message model (client ones as validated, server ones as serialised)."""
    models = [
        (model, "validation" if direction == "client" else "serialization")
        for model, direction, _ in MESSAGES.values()
    ]
    _, top = models_json_schema(models, ref_template=SCHEMA_REF)  # type: ignore[arg-type]
    schemas: dict[str, Any] = top.get("$defs", {})
    return schemas


def build_asyncapi() -> dict[str, Any]:
    """The AsyncAPI 3.0 document as plain data."""
    inputs = [*INPUT_KINDS, *DECODED_KINDS]
    answers = [f"{tag}_result" for tag in DECODED_KINDS]
    stream_messages = [*inputs, "result", *answers, "error", "ack"]
    subscribe_messages = ["result", "error", "ack", "gap"]
    return {
        "asyncapi": "3.0.0",
        "info": {
            "title": "credal-fusion WebSocket protocol",
            "version": __version__,
            "description": DESCRIPTION,
        },
        "defaultContentType": "application/json",
        "servers": {
            "local": {
                "host": "127.0.0.1:8000",
                "protocol": "ws",
                "description": "`make run`",
                "security": [{"$ref": "#/components/securitySchemes/bearer"}],
            }
        },
        "channels": {
            "stream": _channel(
                "/v1/sessions/{sid}/stream",
                "Send inputs, receive one result per input.",
                stream_messages,
            ),
            "subscribe": _channel(
                "/v1/sessions/{sid}/subscribe", "Receive every fused result.", subscribe_messages
            ),
        },
        "operations": {
            "send_inputs": {
                "action": "send",
                "channel": {"$ref": "#/channels/stream"},
                "messages": _refs(inputs, "#/channels/stream/messages"),
            },
            "receive_step_results": {
                "action": "receive",
                "channel": {"$ref": "#/channels/stream"},
                "messages": _refs(
                    ["result", *answers, "error", "ack"], "#/channels/stream/messages"
                ),
            },
            "receive_subscription": {
                "action": "receive",
                "channel": {"$ref": "#/channels/subscribe"},
                "messages": _refs(subscribe_messages, "#/channels/subscribe/messages"),
            },
        },
        "components": {
            "messages": {
                **{name: _message(name) for name in MESSAGES},
                **{tag: _binary_message(kind) for tag, kind in DECODED_KINDS.items()},
            },
            "schemas": payload_schemas(),
            "securitySchemes": {"bearer": {"type": "http", "scheme": "bearer"}},
        },
    }


def render_asyncapi() -> str:
    """The document as deterministic YAML text."""
    text: str = yaml.safe_dump(build_asyncapi(), sort_keys=True, allow_unicode=True, width=100)
    return text


def main(argv: Sequence[str] | None = None) -> int:
    """Write the document: ``python -m app.asyncapi [PATH]`` (default ``docs/asyncapi.yaml``)."""
    args = list(sys.argv[1:] if argv is None else argv)
    target = Path(args[0]) if args else DEFAULT_PATH
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(render_asyncapi(), encoding="utf-8")
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
