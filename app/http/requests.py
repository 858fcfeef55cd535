"""Request bodies as JSON: duplicate keys refused, nesting bounded, one parser for REST and WebSocket.

``json.loads`` keeps the last of two equal keys silently (``{"time": 1,
"time": 2}`` is read as 2); a body that says two things is refused instead
(422 ``json_invalid`` naming the key). A body nested beyond Python's
recursion limit is refused the same way instead of raising ``RecursionError``;
so is a number with more than 4 300 digits (Python's ``int`` limit). Every
route uses :class:`WireRoute`, whose request parses with :func:`parse_json`.
"""

from __future__ import annotations

import functools
import json
import threading
import typing
from collections.abc import Callable, Coroutine
from typing import Any

import anyio
from fastapi import Request, Response
from fastapi._compat import ModelField
from fastapi.exceptions import RequestValidationError
from fastapi.routing import APIRoute, _effective_route_context_var
from pydantic import BaseModel, ValidationError

from app.runtime import collection_paused


class DuplicateKeyError(ValueError):
    """An object of the body names a key twice."""


def _refuse_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    document = dict(pairs)
    if len(document) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise DuplicateKeyError(f"duplicate key {key!r} in an object")
            seen.add(key)
    return document


_DECODERS = threading.local()


def _decoder() -> json.JSONDecoder:
    """This thread's decoder (``json.loads`` builds one, its scanner included, at every call;
    one per thread: a decoder's scanner is not shared between threads)."""
    decoder: json.JSONDecoder | None = getattr(_DECODERS, "decoder", None)
    if decoder is None:
        decoder = _DECODERS.decoder = json.JSONDecoder(object_pairs_hook=_refuse_duplicates)
    return decoder


def parse_json(text: str | bytes) -> Any:
    """The JSON document ``text``; :class:`json.JSONDecodeError` for anything it cannot be."""
    source = text if isinstance(text, str) else text.decode("utf-8", errors="surrogatepass")
    if source.startswith("\ufeff"):  # as json.loads refuses it
        raise json.JSONDecodeError("Unexpected UTF-8 BOM (decode using utf-8-sig)", source, 0)
    try:
        return _decoder().decode(source)
    except json.JSONDecodeError:
        raise
    except DuplicateKeyError as error:
        raise json.JSONDecodeError(str(error), source, 0) from None
    except RecursionError:
        raise json.JSONDecodeError("nesting too deep", source, 0) from None
    except ValueError as error:  # e.g. an integer of more than 4 300 digits
        raise json.JSONDecodeError(str(error), source, 0) from None


class WireRequest(Request):
    """A request whose JSON body is parsed by :func:`parse_json`."""

    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            body = await self.body()
            try:
                self._json = parse_json(body)
            except UnicodeDecodeError as error:
                raise json.JSONDecodeError(
                    f"body is not UTF-8 ({error.reason})", repr(body[:64]), error.start
                ) from None
        return self._json


OFFLOAD_BYTES = 32 * 1024
"""Bodies larger than this are parsed and validated in a worker thread, not on the event loop."""


Precheck = Callable[[Request, Any], None]
"""A route's check of a large body's parsed document before it is validated (it raises to
refuse): a refusal that needs only a count costs the parse, not the validation (the
validation of a 2 000-track list is 20-130 ms of CPU, its parse 10 ms)."""
PRECHECKS: dict[Callable[..., Any], Precheck] = {}
"""Route endpoint → its :data:`Precheck` (:class:`WireRoute` applies it)."""


def _parsed(body: bytes) -> Any:
    """``body`` parsed as JSON; a :class:`RequestValidationError` if it is not JSON."""
    try:
        return parse_json(body.decode("utf-8"))
    except UnicodeDecodeError as error:
        raise json_error(f"body is not UTF-8 ({error.reason})", error.start) from None
    except json.JSONDecodeError as error:
        raise json_error(error.msg, error.pos) from None


def _validated(model: type[BaseModel], body: bytes | Any, parsed: bool = False) -> BaseModel:
    """``body`` parsed (unless ``parsed``: then it is the document) and validated as ``model``;
    a :class:`RequestValidationError` if it is not."""
    document = body if parsed else _parsed(body)
    try:
        return model.model_validate(document)
    except ValidationError as error:
        raise RequestValidationError(
            [{**entry, "loc": ("body", *entry["loc"])} for entry in error.errors()]
        ) from None


def json_error(
    reason: str, position: int, within: tuple[str, ...] = ("body",)
) -> RequestValidationError:
    """The validation error of a document that is not JSON (a request body, or a WebSocket
    message: ``within=()``), at character ``position``."""
    return RequestValidationError(
        [
            {
                "type": "json_invalid",
                "loc": (*within, position),
                "msg": "JSON decode error",
                "input": {},
                "ctx": {"error": reason},
            }
        ]
    )


class WireRoute(APIRoute):
    """The route class of every router: its requests are :class:`WireRequest`.

    A JSON body larger than :data:`OFFLOAD_BYTES` is parsed and validated as the
    route's body model in a worker thread (the configured limits apply there
    too); FastAPI then receives the validated model, which it passes through
    without validating it again. Smaller bodies cost less than the thread hop.
    Garbage collection stays paused (:func:`app.runtime.collection_paused`) until
    such a request is answered: resumed between its worker-thread jobs, a
    collection walked the validated model and the step's objects (177 000
    containers of a 2 000-track list: 65 ms holding the GIL) while they were
    still alive, though reference counting frees them once the request ends.
    """

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()
        model = body_model(self.endpoint)
        precheck = PRECHECKS.get(self.endpoint)
        if model is not None:
            # an included route runs with its own dependant (fastapi 0.165, pinned)
            included = _effective_route_context_var.get()
            owner = included if included is not None and included.original_route is self else self
            for field in owner.dependant.body_params:
                _accept_validated(field, model)

        async def handle(request: Request) -> Response:
            wire = WireRequest(request.scope, request.receive)
            if model is not None and _is_json(wire):
                body = await wire.body()
                if len(body) > OFFLOAD_BYTES:
                    with collection_paused():
                        if precheck is None:
                            validate = functools.partial(_validated, model, body)
                        else:
                            document = await anyio.to_thread.run_sync(_parsed, body)
                            precheck(wire, document)
                            validate = functools.partial(_validated, model, document, True)
                            del document
                        wire._json = await anyio.to_thread.run_sync(validate)
                        del body, validate
                        response = await handler(wire)
                        del wire  # the validated model, freed before collection resumes
                    return response
            return await handler(wire)

        return handle


def _accept_validated(field: ModelField, model: type[BaseModel]) -> None:
    """Let ``field`` take a ``model`` validated in the worker thread as it is.

    pydantic runs a model's ``after`` validators again on an instance of the
    model (the covariance batch of a track list, the geometry of a session
    config), which would put that work back on the event loop.
    """
    validate = field.validate

    def validate_once(
        value: Any, values: dict[str, Any] | None = None, *, loc: tuple[int | str, ...] = ()
    ) -> tuple[Any, list[dict[str, Any]]]:
        if type(value) is model:
            return value, []
        return validate(value, values or {}, loc=loc)

    field.validate = validate_once  # type: ignore[method-assign]


def _is_json(request: Request) -> bool:
    content_type = request.headers.get("content-type", "")
    media = content_type.split(";")[0].strip().lower()
    return media == "application/json" or media.endswith("+json")


@functools.cache
def body_model(endpoint: Callable[..., Any]) -> type[BaseModel] | None:
    """The model a route's body is validated as (its one pydantic-model parameter that is not
    a dependency: ``SettingsDep`` is a model too, but ``Annotated`` with ``Depends``), if any."""
    try:
        hints = typing.get_type_hints(endpoint, include_extras=True)
    except (NameError, TypeError):
        return None
    hints.pop("return", None)
    models = [
        hint
        for hint in hints.values()
        if isinstance(hint, type) and issubclass(hint, BaseModel)  # plain: not Annotated
    ]
    return models[0] if len(models) == 1 else None
