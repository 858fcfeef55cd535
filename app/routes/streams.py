"""WebSocket channels of a session: ``stream`` (inputs in, results out) and ``subscribe``.

The protocol is documented in ``docs/asyncapi.yaml``. Both channels need the
session's token (or the admin token) in the upgrade request's
``Authorization`` header, or — for browsers, which cannot set headers on an
upgrade — offered as the two subprotocols ``bearer`` and the token (the
server then accepts ``bearer``); a refused upgrade gets the problem+json answer the
REST route would give (or close code 1008 where the server cannot send one).
The server pings (uvicorn's ``ws_ping_interval``/``ws_ping_timeout``) and
drops a peer that stops answering.

``stream``: a reader task reads, validates and applies each message in
order and puts its answer (one ``result`` or ``error``, echoing ``ref``) into
a bounded queue; a writer task sends them. When the client does not read, the
queue fills, the reader stops reading and TCP pushes back: nothing grows
without bound. ``subscribe``: the session's hub gives each subscriber a
bounded queue that keeps the latest results (:mod:`app.sessions.hub`); with the
redis store the hub is fed from Redis pub/sub, so results applied on any
instance arrive (:meth:`app.sessions.registry.SessionRegistry.subscribe`). The server
closes a subscription with 1000 "session ended" when the session is deleted
or expires, and with 1013 "store unavailable" when the store (or its
pub/sub connection) fails: subscribe again once ``/readyz`` is ready.

Both channels take the query parameter ``frame`` on connect, as the REST
inputs and reads do: ``geodetic`` adds ``geodetic: {lat, lon, alt}`` to every
fused track of every ``result`` sent on that connection (the session needs an
``origin``; otherwise, or for another value, the upgrade is refused with the
422 problem naming ``query/frame``).
"""

from __future__ import annotations

import functools
import json
import logging
import re

import anyio
import orjson
from fastapi import APIRouter, WebSocket
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.websockets import WebSocketDisconnect

from api_schemas.issues import FieldIssue
from api_schemas.problem import Problem
from api_schemas.ws import DetectionsMessage, TracksMessage, client_message_adapter
from app.geo.geojson import GeodeticOutput, with_geodetic
from app.http.deps import open_record
from app.http.errors import (
    LimitExceeded,
    ServiceError,
    StoreUnavailable,
    Unauthorized,
    error_message,
    problem_for,
    problem_response,
    request_validation_error,
)
from app.http.rate_limit import MessageRate
from app.http.requests import OFFLOAD_BYTES, WireRoute, json_error, parse_json
from app.http.responses import dumps, itemwise
from app.routes.fusion import geodetic_output
from app.runtime import collection_paused, without_collection
from app.sessions.hub import STORE_UNAVAILABLE, Ending, Published
from app.sessions.live import LiveSession
from app.sessions.registry import SessionRegistry, result_message

router = APIRouter(prefix="/v1/sessions", route_class=WireRoute)
logger = logging.getLogger("credal_fusion.streams")

OUTBOX_SIZE = 16
"""Answers waiting to be sent on one ``stream`` connection."""
POLICY_VIOLATION = 1008
BEARER_SUBPROTOCOL = "bearer"
"""Browsers offer the token as the subprotocols ``["bearer", token]``; the server accepts ``bearer``."""
MESSAGE_TAGS = ("tracks", "detections")
DISCONNECTED = (WebSocketDisconnect, OSError, anyio.ClosedResourceError, anyio.BrokenResourceError)
"""What a peer that went away raises on our side (uvicorn's ClientDisconnected is an OSError)."""


def _bearer(websocket: WebSocket) -> str:
    """The upgrade request's token: ``Authorization: Bearer …``, or the subprotocol pair
    ``bearer, <token>`` (what a browser can send: it cannot set headers on an upgrade)."""
    scheme, _, token = websocket.headers.get("authorization", "").partition(" ")
    if scheme.lower() == "bearer" and token.strip():
        return token.strip()
    offered = [
        part.strip() for part in websocket.headers.get("sec-websocket-protocol", "").split(",")
    ]
    if len(offered) == 2 and offered[0] == BEARER_SUBPROTOCOL and offered[1]:
        return offered[1]
    raise Unauthorized(
        "send 'Authorization: Bearer <token>' with the upgrade request "
        f"(or the subprotocols '{BEARER_SUBPROTOCOL}', '<token>')"
    )


def _subprotocol(websocket: WebSocket) -> str | None:
    """The subprotocol to accept: ``bearer`` when the token came that way."""
    offered = websocket.headers.get("sec-websocket-protocol", "")
    return BEARER_SUBPROTOCOL if offered.split(",")[0].strip() == BEARER_SUBPROTOCOL else None


OUTPUT_FRAMES = ("session", "geodetic")


def _output_frame(websocket: WebSocket, session: LiveSession) -> GeodeticOutput | None:
    """The session's geodetic output when the connection asks ``?frame=geodetic``, else None."""
    frame = websocket.query_params.get("frame", "session")
    if frame not in OUTPUT_FRAMES:
        raise request_validation_error(
            [FieldIssue(("frame",), f"frame is one of {list(OUTPUT_FRAMES)}", frame)],
            prefix="query",
        )
    return geodetic_output(session.config, "frame") if frame == "geodetic" else None


async def _open(websocket: WebSocket, sid: str) -> tuple[LiveSession, GeodeticOutput | None] | None:
    """The session (and the output frame the connection asks for) if the upgrade request may
    open it; otherwise refuse the upgrade."""
    app = websocket.app
    registry: SessionRegistry = app.state.registry
    try:
        token = _bearer(websocket)
        record = open_record(sid, await registry.record(sid), token, app.state.settings)
        session = await registry.current(await registry.get(record.id))
        return session, _output_frame(websocket, session)
    except (ServiceError, RequestValidationError) as error:
        path = websocket.url.path
        if "websocket.http.response" in websocket.scope.get("extensions", {}):
            await websocket.send_denial_response(problem_response(error, path))
        else:
            reason = problem_for(error, path).detail[:120]
            await websocket.close(code=POLICY_VIOLATION, reason=reason)
        return None


async def _in_frame(published: Published, geodetic: GeodeticOutput | None) -> str:
    """A published result's message in a subscriber's frame: written beside the step (a
    geodetic subscriber of this instance was there before it), else converted here (a
    result forwarded from another instance through Redis): parsing a 10 MB result holds the
    GIL ~300 ms, a cost the geodetic text written beside the step avoids."""
    if geodetic is None:
        return published.text
    if published.geodetic is not None:
        return published.geodetic
    convert = functools.partial(geodetic_message, published.text, geodetic)
    if len(published.text) > OFFLOAD_BYTES:
        return await anyio.to_thread.run_sync(without_collection(convert))
    return convert()


def geodetic_message(message: str, geodetic: GeodeticOutput) -> str:
    """A hub message with ``geodetic`` added to its result's tracks (other messages as they
    are), written a track at a time."""
    document = orjson.loads(message)
    if document.get("type") != "result":
        return message
    result = document["result"]
    result["tracks"] = with_geodetic(result["tracks"], geodetic)
    return itemwise(document)


def message_bytes(text: str, limit: int) -> int:
    """A text message's size in UTF-8 bytes (what ``max_body_bytes`` counts: a character is 1 to
    4 bytes); past ``limit`` in characters already, that length (a lower bound) is enough."""
    return len(text) if len(text) > limit else len(text.encode("utf-8", "surrogatepass"))


RESULT_SEQ = re.compile(r'"result":\{"seq":(\d+)')
TAKEN_OVER = Ending(1013, "session taken over")
"""A stream's session now applied by another instance (its lease lost): reconnect."""


def result_seq(message: str) -> int | None:
    """The ``seq`` of a ``result`` message (written by ``result_message``: ``seq`` first)."""
    found = RESULT_SEQ.search(message, 0, 200)
    return None if found is None else int(found.group(1))


def gap_message(after: int, next_seq: int) -> str:
    """The ``gap`` message: results after ``after`` and before ``next_seq`` were not sent."""
    return dumps({"type": "gap", "ref": None, "after": after, "next": next_seq})


def _ack(session: LiveSession) -> str:
    return dumps({"type": "ack", "ref": None, "seq": session.seq})


def _ref_of(document: object) -> str | None:
    """The ``ref`` of a message that failed validation, if it has a usable one."""
    ref = document.get("ref") if isinstance(document, dict) else None
    return ref if isinstance(ref, str) and 0 < len(ref) <= 128 else None


MESSAGE_TYPES = {"tracks": TracksMessage, "detections": DetectionsMessage}


def _message_problem(error: ValidationError, path: str, document: object, listed: int) -> Problem:
    """A validation problem located in the message (the union's tag is left out of the path)."""
    errors = []
    allowed = " or ".join(repr(tag) for tag in MESSAGE_TAGS)
    for entry in error.errors():
        loc = list(entry.get("loc", ()))
        message = entry.get("msg", "")
        if loc and loc[0] in MESSAGE_TAGS:
            loc = loc[1:]
        elif entry.get("type") == "union_tag_not_found":  # pydantic: "Unable to extract tag …"
            loc, message = ["type"], f"Field required: every message has a 'type', {allowed}"
        elif entry.get("type") == "union_tag_invalid":
            tag = entry.get("ctx", {}).get("tag")
            loc, message = ["type"], f"{tag!r} is not a message type: 'type' is {allowed}"
        errors.append({**entry, "loc": tuple(loc), "msg": message})
    kind = document.get("type") if isinstance(document, dict) else None
    root = MESSAGE_TYPES.get(kind) if isinstance(kind, str) else None
    return problem_for(RequestValidationError(errors), path, listed=listed, root=root)


def _refusal(error: ServiceError, path: str) -> str:
    return error_message(problem_for(error, path), None)


def _client_message(text: str, path: str, listed: int) -> TracksMessage | DetectionsMessage | str:
    """``text`` parsed and validated as a client message, or the ``error`` message answering it."""
    try:
        document = parse_json(text)
    except json.JSONDecodeError as error:
        return error_message(problem_for(json_error(error.msg, error.pos, ()), path), None)
    try:
        return client_message_adapter.validate_python(document)
    except ValidationError as error:
        problem = _message_problem(error, path, document, listed)
        return error_message(problem, _ref_of(document))


async def _answer(
    session: LiveSession,
    registry: SessionRegistry,
    text: str,
    path: str,
    geodetic: GeodeticOutput | None = None,
) -> str:
    """The one answer (``result`` or ``error``) to one client message (``geodetic``: with the
    tracks' geodetic positions). A message larger than ``OFFLOAD_BYTES`` is parsed and
    validated in a worker thread, as a REST body is."""
    read = functools.partial(_client_message, text, path, registry.settings.max_listed_errors)
    if len(text) > OFFLOAD_BYTES:
        with collection_paused():
            message = await anyio.to_thread.run_sync(read)
    else:
        message = read()
    if isinstance(message, str):
        return message
    try:
        if session.closed:  # evicted (store down, or a failed step): the registry reloads it
            session = await registry.get(session.id)
        result = await registry.submit(session, message.report(), geodetic=geodetic)
    except Exception as error:  # every failure is answered; the connection stays open
        return error_message(problem_for(error, path), message.ref)
    return result_message(result, message.ref)


@router.websocket("/{sid}/stream")
async def stream_session(websocket: WebSocket, sid: str) -> None:
    """Send inputs, receive one answer per input, in order."""
    opened = await _open(websocket, sid)
    if opened is None:
        return
    session, geodetic = opened
    registry: SessionRegistry = websocket.app.state.registry
    path = websocket.url.path
    await websocket.accept(subprotocol=_subprotocol(websocket))
    await websocket.send_text(_ack(session))
    send, receive = anyio.create_memory_object_stream[str](OUTBOX_SIZE)

    settings = registry.settings
    rate = MessageRate(settings.ws_messages_per_second)

    async def reader() -> None:
        async with send:
            while True:
                incoming = await websocket.receive()
                if incoming["type"] == "websocket.disconnect":
                    return
                text = incoming.get("text")
                if text is None:
                    text = bytes(incoming.get("bytes") or b"").decode("utf-8", errors="replace")
                size = message_bytes(text, settings.max_body_bytes)
                if size > settings.max_body_bytes:
                    answer = _refusal(
                        LimitExceeded(
                            "max_body_bytes", settings.max_body_bytes, size, what="message (bytes)"
                        ),
                        path,
                    )
                elif not rate.admit():
                    answer = _refusal(
                        LimitExceeded(
                            "ws_messages_per_second",
                            settings.ws_messages_per_second,
                            what="messages per second on this connection",
                            status=429,
                        ),
                        path,
                    )
                else:
                    answer = await _answer(session, registry, text, path, geodetic)
                await send.send(answer)

    async def writer() -> None:
        async with receive:
            async for answer in receive:
                await websocket.send_text(answer)

    async def lease_keeper() -> None:
        """Renew the session's lease every third of its TTL while the stream is open; close
        with 1013 when another instance took the session over (the client reconnects)."""
        period = settings.lease_ttl_ms / 3000
        while True:
            await anyio.sleep(period)
            try:
                kept = await registry.keep_lease(session)
            except StoreUnavailable:
                continue  # the inputs say it too; the lease lapses or is kept
            if not kept:
                await websocket.close(code=TAKEN_OVER.code, reason=TAKEN_OVER.reason)
                return

    try:
        async with anyio.create_task_group() as tasks:
            tasks.start_soon(writer)
            if registry.shared:
                tasks.start_soon(lease_keeper)
            await reader()
            tasks.cancel_scope.cancel()
    except* DISCONNECTED:
        pass


@router.websocket("/{sid}/subscribe")
async def subscribe_session(websocket: WebSocket, sid: str) -> None:
    """Receive every result of the session, in order; a slow reader skips to the latest."""
    opened = await _open(websocket, sid)
    if opened is None:
        return
    session, geodetic = opened
    registry: SessionRegistry = websocket.app.state.registry
    await websocket.accept(subprotocol=_subprotocol(websocket))
    try:
        # in place before the ack: nothing missed
        subscriber = await registry.subscribe(session, geodetic=geodetic is not None)
    except StoreUnavailable:
        await websocket.close(code=STORE_UNAVAILABLE.code, reason=STORE_UNAVAILABLE.reason)
        return
    last = session.seq
    await websocket.send_text(_ack(session))

    async def pump() -> None:
        """Every result, in order; a ``gap`` message before one that does not follow."""
        nonlocal last
        while not isinstance(published := await subscriber.next(), Ending):
            seq = result_seq(published.text)
            if seq is not None:
                if seq > last + 1:
                    await websocket.send_text(gap_message(last, seq))
                last = max(last, seq)
            await websocket.send_text(await _in_frame(published, geodetic))
        await websocket.close(code=published.code, reason=published.reason)

    try:
        async with anyio.create_task_group() as tasks:
            tasks.start_soon(pump)
            while (await websocket.receive())["type"] != "websocket.disconnect":
                pass  # the channel is receive-only: client messages are ignored
            tasks.cancel_scope.cancel()
    except* (*DISCONNECTED, RuntimeError):
        pass
    finally:
        registry.unsubscribe(session, subscriber)
