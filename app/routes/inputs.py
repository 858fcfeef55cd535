"""The inputs of a session: ``POST /v1/sessions/{sid}/{tag}`` for every input kind registered
in :mod:`app.inputs` (a JSON report as the body, or the bytes of a decoded kind), built with
the application: the routes iterate the registry, as the WebSocket, the log and replay do."""

from __future__ import annotations

import functools
from typing import Annotated, Any

from fastapi import APIRouter, Header, Query, Request

from api_schemas.base import WireModel
from api_schemas.examples import json_body_examples
from api_schemas.ws import IDEMPOTENCY_KEY_MAX, IDEMPOTENCY_KEY_PATTERN
from app.http.deps import LiveSessionDep, RegistryDep
from app.http.errors import problem_responses
from app.http.requests import PRECHECKS, WireRoute
from app.http.responses import JSONTextResponse
from app.http.security import hash_token
from app.http.transport import received_at
from app.inputs import DECODED_KINDS, INPUT_KINDS, DecodedKind, Input, InputKind
from app.routes.fusion import OutputFormat, OutputFrame, output_of, output_responses
from app.sessions.live import IDEMPOTENCY_KEYS

Explain = Annotated[
    bool,
    Query(
        description="add the association's score matrix: (known + reported) × reported cells, "
        "at most max_explain_cells (422 before the work beyond)"
    ),
]
IdempotencyKey = Annotated[
    str | None,
    Header(
        alias="Idempotency-Key",
        min_length=1,
        max_length=IDEMPOTENCY_KEY_MAX,
        pattern=IDEMPOTENCY_KEY_PATTERN,
        description="names this input: sent again with the same key (a retry after a lost "
        "answer, to this instance or another, before or after a restart), the same input is "
        "not applied twice, its first answer is given again (409 if the key came with another "
        f"input); the key is logged with the input, the session remembers its latest "
        f"{IDEMPOTENCY_KEYS}",
    ),
]


TRUE_WORDS = frozenset({"1", "true", "yes", "on"})
"""What FastAPI reads as a true boolean query parameter (case aside)."""


def _work_precheck(tag: str, request: Request, document: Any) -> None:
    """A large body's work checked on its parsed document, before it is validated: its items
    counted against ``max_input_work`` (and ``max_explain_cells``) as the pipeline will
    (:meth:`~app.sessions.pipeline.InputPipeline.check_work`, the same refusal). Only for the
    session that the request's own token opens, held in memory; anything else is left to the
    route (its authentication, its validation)."""
    registry = request.app.state.registry
    scheme, _, token = request.headers.get("authorization", "").partition(" ")
    if scheme.lower() != "bearer" or not token.strip():
        return
    session = registry.session_of_token(hash_token(token.strip()))
    if session is None or session.id != request.path_params.get("sid") or session.closed:
        return
    items = document.get(tag) if isinstance(document, dict) else None
    sensor = document.get("sensor") if isinstance(document, dict) else None
    if isinstance(items, list) and isinstance(sensor, str):
        explain = request.query_params.get("explain", "").lower() in TRUE_WORDS
        registry.pipeline.check_work(session, sensor, len(items), tag, explain=explain)


def _submit_route(router: APIRouter, kind: InputKind[Any]) -> None:
    """``POST /v1/sessions/{sid}/{tag}`` for the input kind ``kind`` (its report as the body)."""

    async def submit(
        request: Request,
        report: WireModel,
        session: LiveSessionDep,
        registry: RegistryDep,
        explain: Explain = False,
        frame: OutputFrame = "session",
        format: OutputFormat = "json",
        idempotency_key: IdempotencyKey = None,
    ) -> JSONTextResponse:
        output = output_of(session.config, format, frame)  # refused before anything is applied
        submitted = Input(kind, report)
        answer = await registry.submit(
            session,
            submitted,
            explain=explain,
            output=output,
            idempotency_key=idempotency_key,
            received_at=received_at(request.scope),
        )
        return JSONTextResponse(answer, media_type=output.media_type)

    submit.__annotations__["report"] = kind.report_model
    submit.__name__ = submit.__qualname__ = f"submit_{kind.tag}"
    submit.__doc__ = kind.description
    PRECHECKS[submit] = functools.partial(_work_precheck, kind.tag)
    router.add_api_route(
        f"/{{sid}}/{kind.tag}",
        submit,
        methods=["POST"],
        response_model=None,  # the formats' models: output_responses
        responses=output_responses("step", 401, 403, 404, 409, 408, 413, 422, 503),
        name=submit.__name__,
        openapi_extra=json_body_examples(kind.examples),
    )


def _decoded_route(router: APIRouter, kind: DecodedKind[Any]) -> None:
    """``POST /v1/sessions/{sid}/{tag}`` for a kind whose body is bytes (``kind.media_type``)
    with its query ``parameters``; the answer is ``kind.answer_model``."""

    async def submit(
        request: Request,
        parameters: WireModel,
        session: LiveSessionDep,
        registry: RegistryDep,
        explain: Explain = False,
        frame: OutputFrame = "session",
        format: OutputFormat = "json",
    ) -> JSONTextResponse:
        output = output_of(session.config, format, frame)
        data = await request.body()
        return JSONTextResponse(
            await registry.submit_decoded(
                session,
                kind,
                data,
                parameters,
                explain=explain,
                output=output,
                received_at=received_at(request.scope),
            )
        )

    submit.__annotations__["parameters"] = Annotated[kind.parameters, Query()]
    submit.__name__ = submit.__qualname__ = f"submit_{kind.tag}"
    submit.__doc__ = kind.description
    body = {"schema": {"type": "string", "format": "binary"}}
    router.add_api_route(
        f"/{{sid}}/{kind.tag}",
        submit,
        methods=["POST"],
        response_model=kind.answer_model,
        responses=problem_responses(401, 403, 404, 409, 408, 413, 422, 503),
        name=submit.__name__,
        openapi_extra={"requestBody": {"required": True, "content": {kind.media_type: body}}},
    )


def input_routes() -> APIRouter:
    """``POST /v1/sessions/{sid}/{tag}`` for every registered input kind (:mod:`app.inputs`),
    built when the application is."""
    router = APIRouter(prefix="/v1/sessions", tags=["fusion"], route_class=WireRoute)
    for kind in INPUT_KINDS.values():
        _submit_route(router, kind)
    for decoded in DECODED_KINDS.values():
        _decoded_route(router, decoded)
    return router
