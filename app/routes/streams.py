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

Both channels take the query parameters ``format`` and ``frame`` on connect,
as the REST inputs and reads do (:func:`app.outputs.output_for`): every
``result`` sent on that connection is written in that output (``frame=geodetic``
adds ``geodetic: {lat, lon, alt}`` to every fused track, ``format=geojson``
makes each result a FeatureCollection); the session needs an ``origin`` for
either, and an unknown value or a geodetic output without one refuses the
upgrade with the 422 problem naming ``query/frame`` or ``query/format``.
"""

from __future__ import annotations

import functools
import json
import logging
import re
from typing import Any

import anyio
import orjson
from fastapi import APIRouter, WebSocket
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.websockets import WebSocketDisconnect

from api_schemas.issues import FieldIssue
from api_schemas.problem import Problem
from app.http.deps import open_record
from app.http.errors import (
    InvalidFields,
    LimitExceeded,
    ServiceError,
    SessionNotFound,
    StoreUnavailable,
    Unauthorized,
    error_message,
    problem_for,
    problem_response,
)
from app.http.front import FrontDoor, KeyedFirst
from app.http.rate_limit import MessageRate
from app.http.requests import OFFLOAD_BYTES, WireRoute, json_error, parse_json
from app.inputs import DECODED_KINDS, INPUT_KINDS, client_messages, message_input
from app.outputs import JSON, Output
from app.outputs.text import dumps
from app.routes.fusion import output_of
from app.runtime import collection_paused, without_collection
from app.sessions.hub import SESSION_ENDED, STORE_UNAVAILABLE, Ending, Published
from app.sessions.live import LiveSession
from app.sessions.pipeline import result_message
from app.sessions.registry import SessionRegistry
from app.sessions.work import Receipt, receipt

router = APIRouter(prefix="/v1/sessions", route_class=WireRoute)
logger = logging.getLogger("credal_fusion.streams")

OUTBOX_SIZE = 16
"""Answers waiting to be sent on one ``stream`` connection."""
POLICY_VIOLATION = 1008
BEARER_SUBPROTOCOL = "bearer"
"""Browsers offer the token as the subprotocols ``["bearer", token]``; the server accepts ``bearer``."""
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


def _output(websocket: WebSocket, session: LiveSession) -> Output:
    """The output the connection asks for (``?format=…&frame=…``, as the REST routes take)."""
    query = websocket.query_params
    return output_of(session.config, query.get("format", "json"), query.get("frame", "session"))


async def _open(websocket: WebSocket, sid: str) -> tuple[LiveSession, Output] | None:
    """The session (and the output the connection asks for) if the upgrade request may open
    it; otherwise refuse the upgrade."""
    app = websocket.app
    registry: SessionRegistry = app.state.registry
    try:
        token = _bearer(websocket)
        record = open_record(sid, await registry.record(sid), token, app.state.settings)
        session = await registry.current(await registry.get(record.id))
        return session, _output(websocket, session)
    except (ServiceError, RequestValidationError) as error:
        path = websocket.url.path
        if "websocket.http.response" in websocket.scope.get("extensions", {}):
            await websocket.send_denial_response(problem_response(error, path))
        else:
            reason = problem_for(error, path).detail[:120]
            await websocket.close(code=POLICY_VIOLATION, reason=reason)
        return None


async def _in_output(published: Published, output: Output) -> str:
    """A published result's message in a subscriber's output: written beside the step (a
    subscriber of this instance was there before it), else converted here (a result forwarded
    from another instance through Redis): parsing a 10 MB result holds the GIL ~300 ms, a cost
    the text written beside the step avoids."""
    written = published.texts.get(output)
    if written is not None:
        return written
    convert = functools.partial(converted_message, published.text, output)
    if len(published.text) > OFFLOAD_BYTES:
        return await anyio.to_thread.run_sync(without_collection(convert))
    return convert()


def converted_message(message: str, output: Output) -> str:
    """A hub message (the contract's JSON) with its result written as ``output`` (other
    messages as they are), a track at a time."""
    document = orjson.loads(message)
    if document.get("type") != "result":
        return message
    result = output.from_plain(document["result"])
    return f'{{"type":"result","ref":{dumps(document["ref"])},"result":{result}}}'


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


def _ack(session: LiveSession, seq: int | None = None) -> str:
    """The ``ack`` message: ``seq`` the session's latest (by default, as this instance has it)."""
    return dumps({"type": "ack", "ref": None, "seq": session.seq if seq is None else seq})


def _ref_of(document: object) -> str | None:
    """The ``ref`` of a message that failed validation, if it has a usable one."""
    ref = document.get("ref") if isinstance(document, dict) else None
    return ref if isinstance(ref, str) and 0 < len(ref) <= 128 else None


def _message_problem(error: ValidationError, path: str, document: object, listed: int) -> Problem:
    """A validation problem located in the message (the union's tag is left out of the path)."""
    errors = []
    allowed = " or ".join(repr(tag) for tag in INPUT_KINDS)
    for entry in error.errors():
        loc = list(entry.get("loc", ()))
        message = entry.get("msg", "")
        if loc and loc[0] in INPUT_KINDS:
            loc = loc[1:]
        elif entry.get("type") == "union_tag_not_found":  # pydantic: "Unable to extract tag …"
            loc, message = ["type"], f"Field required: every message has a 'type', {allowed}"
        elif entry.get("type") == "union_tag_invalid":
            tag = entry.get("ctx", {}).get("tag")
            loc, message = ["type"], f"{tag!r} is not a message type: 'type' is {allowed}"
        errors.append({**entry, "loc": tuple(loc), "msg": message})
    kind = document.get("type") if isinstance(document, dict) else None
    found = INPUT_KINDS.get(kind) if isinstance(kind, str) else None
    root = None if found is None else found.message_model
    return problem_for(RequestValidationError(errors), path, listed=listed, root=root)


def _refusal(error: ServiceError, path: str) -> str:
    return error_message(problem_for(error, path), None)


def _client_message(text: str, path: str, listed: int) -> Any:
    """``text`` parsed and validated as a client message, or the ``error`` message answering it."""
    try:
        document = parse_json(text)
    except json.JSONDecodeError as error:
        return error_message(problem_for(json_error(error.msg, error.pos, ()), path), None)
    try:
        return client_messages().validate_python(document)
    except ValidationError as error:
        problem = _message_problem(error, path, document, listed)
        return error_message(problem, _ref_of(document))


async def _answer(
    session: LiveSession,
    registry: SessionRegistry,
    text: str,
    path: str,
    output: Output = JSON,
    received_at: Receipt | None = None,
) -> str:
    """The one answer (``result`` or ``error``) to one client message (its result written as
    ``output``; ``received_at``: when the reader took it). A message
    larger than ``OFFLOAD_BYTES`` is parsed and validated in a worker thread, as a REST body is."""
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
        result = await registry.submit(
            session,
            message_input(message),
            output=output,
            idempotency_key=message.idempotency_key,
            received_at=received_at,
        )
    except Exception as error:  # every failure is answered; the connection stays open
        return error_message(problem_for(error, path), message.ref)
    return result_message(result, message.ref)


def _looks_like_json(data: bytes) -> bool:
    """Whether a binary message is JSON text (as a text message is read) rather than the bytes
    of a decoded kind (ASTERIX: its first byte is a category, never ``{`` or ``[`` here)."""
    start = data.lstrip()[:1]
    return not DECODED_KINDS or start in (b"{", b"[") or not data


async def _decoded_answer(
    websocket: WebSocket,
    session: LiveSession,
    data: bytes,
    path: str,
    output: Output,
    received_at: Receipt | None = None,
) -> str:
    """The answer to a binary message: bytes of a decoded kind (``?decode=TAG``, default the
    first registered), with that kind's parameters in the connection's query."""
    registry: SessionRegistry = websocket.app.state.registry
    query = websocket.query_params
    tag = query.get("decode", next(iter(DECODED_KINDS)))
    try:
        kind = DECODED_KINDS.get(tag)
        if kind is None:
            raise InvalidFields(
                [FieldIssue(("decode",), f"decode is one of {list(DECODED_KINDS)}", tag)],
                prefix="query",
            )
        fields = {name: query[name] for name in kind.parameters.model_fields if name in query}
        try:
            parameters = kind.parameters.model_validate(fields)
        except ValidationError as error:
            raise InvalidFields(
                [
                    FieldIssue(tuple(entry["loc"]), entry["msg"], None, entry["type"])
                    for entry in error.errors()
                ],
                prefix="query",
            ) from None
        if session.closed:
            session = await registry.get(session.id)
        answer = await registry.submit_decoded(
            session, kind, data, parameters, output=output, received_at=received_at
        )
    except Exception as error:  # every failure is answered; the connection stays open
        return error_message(problem_for(error, path), None)
    return f'{{"type":"{kind.tag}_result","ref":null,"result":{answer}}}'


@router.websocket("/{sid}/stream")
async def stream_session(websocket: WebSocket, sid: str) -> None:
    """Send inputs, receive one answer per input, in order."""
    opened = await _open(websocket, sid)
    if opened is None:
        return
    session, output = opened
    registry: SessionRegistry = websocket.app.state.registry
    path = websocket.url.path
    await websocket.accept(subprotocol=_subprotocol(websocket))
    await websocket.send_text(_ack(session))
    send, receive = anyio.create_memory_object_stream[str](OUTBOX_SIZE)

    settings = registry.settings
    rate = MessageRate(settings.ws_messages_per_second)
    door: FrontDoor | None = getattr(websocket.app.state, "front_door", None)
    tenant = session.record.tenant

    async def reader() -> None:
        async with send:
            while True:
                incoming = await websocket.receive()
                # the protocol reads no further message until this one is taken: the wait
                # counted against max_queue_ms starts here (a backlog stays in TCP's buffers)
                received = receipt()
                if incoming["type"] == "websocket.disconnect":
                    return
                text = incoming.get("text")
                data = b""
                if text is None:
                    data = bytes(incoming.get("bytes") or b"")
                    if _looks_like_json(data):
                        text, data = data.decode("utf-8", errors="replace"), b""
                size = len(data) if text is None else message_bytes(text, settings.max_body_bytes)
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
                elif door is not None and door.waits(tenant, size, websocket.scope):
                    answer = _refusal(KeyedFirst(), path)  # as the door answers a large body
                else:
                    if text is None:
                        answer = await _decoded_answer(
                            websocket, session, data, path, output, received
                        )
                    else:
                        answer = await _answer(session, registry, text, path, output, received)
                    if door is not None:  # an input, a keyed tenant's work as its POST is
                        door.worked(tenant)
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
    session, output = opened
    registry: SessionRegistry = websocket.app.state.registry
    await websocket.accept(subprotocol=_subprotocol(websocket))
    try:
        # in place before the ack: nothing missed
        subscriber = await registry.subscribe(session, output)
    except StoreUnavailable:
        await websocket.close(code=STORE_UNAVAILABLE.code, reason=STORE_UNAVAILABLE.reason)
        return
    last = session.seq
    if registry.shared:  # an input logged before the subscription may not have been
        # published (Store.append: only where someone listens): ack the store's seq, read after
        try:
            last = max(last, await registry.io(registry.store.last_seq, session.id))
        except (StoreUnavailable, SessionNotFound) as error:
            registry.unsubscribe(session, subscriber)
            ending = STORE_UNAVAILABLE if isinstance(error, StoreUnavailable) else SESSION_ENDED
            await websocket.close(code=ending.code, reason=ending.reason)
            return
    await websocket.send_text(_ack(session, last))

    async def pump() -> None:
        """Every result, in order; a ``gap`` message before one that does not follow."""
        nonlocal last
        while not isinstance(published := await subscriber.next(), Ending):
            seq = result_seq(published.text)
            if seq is not None:
                if seq > last + 1:
                    await websocket.send_text(gap_message(last, seq))
                last = max(last, seq)
            await websocket.send_text(await _in_output(published, output))
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
