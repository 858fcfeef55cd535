"""Request bodies as JSON: duplicate keys refused, nesting bounded, one parser for REST and WebSocket.

``json.loads`` keeps the last of two equal keys silently (``{"time": 1,
"time": 2}`` is read as 2); a body that says two things is refused instead
(422 ``json_invalid`` naming the key). A body nested beyond Python's
recursion limit is refused the same way instead of raising ``RecursionError``;
so is a number with more than 4 300 digits (Python's ``int`` limit). Every
route uses :class:`WireRoute`, whose request parses with :func:`parse_json`.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Coroutine
from typing import Any

from fastapi import Request, Response
from fastapi.routing import APIRoute


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


def parse_json(text: str | bytes) -> Any:
    """The JSON document ``text``; :class:`json.JSONDecodeError` for anything it cannot be."""
    source = text if isinstance(text, str) else text.decode("utf-8", errors="surrogatepass")
    try:
        return json.loads(source, object_pairs_hook=_refuse_duplicates)
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


class WireRoute(APIRoute):
    """The route class of every router: its requests are :class:`WireRequest`."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def handle(request: Request) -> Response:
            return await handler(WireRequest(request.scope, request.receive))

        return handle
