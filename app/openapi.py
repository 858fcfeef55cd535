"""The committed ``openapi.json``: deterministic rendering and the ``make openapi`` entry point.

Error answers are documented as ``application/problem+json`` (FastAPI would
say ``application/json``), and FastAPI's default 422 ``HTTPValidationError``
schema is replaced by :class:`~api_schemas.problem.Problem`; every output
format's models are listed (answers in each format's media type refer to them).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi

from api_schemas.problem import Problem
from app.http.errors import PROBLEM_MEDIA_TYPE
from app.outputs import OUTPUT_FORMATS

DEFAULT_PATH = Path("openapi.json")


PROBLEM_REF = "#/components/schemas/Problem"
FASTAPI_VALIDATION_REF = "#/components/schemas/HTTPValidationError"


def _problem_media_types(schema: dict[str, Any]) -> dict[str, Any]:
    for path_item in schema.get("paths", {}).values():
        for operation in path_item.values():
            for status, response in operation.get("responses", {}).items():
                content = response.get("content", {})
                if status[:1] in {"4", "5"} and "application/json" in content:
                    media = content.pop("application/json")
                    if media.get("schema", {}).get("$ref") == FASTAPI_VALIDATION_REF:
                        media["schema"] = {"$ref": PROBLEM_REF}
                        response["description"] = (
                            "Invalid request (every invalid field is listed in `errors`)"
                        )
                    content[PROBLEM_MEDIA_TYPE] = media
    schemas = schema.setdefault("components", {}).setdefault("schemas", {})
    for unused in ("HTTPValidationError", "ValidationError"):
        schemas.pop(unused, None)
    if "Problem" not in schemas:
        problem = Problem.model_json_schema(ref_template="#/components/schemas/{model}")
        schemas.update(problem.pop("$defs", {}))
        schemas["Problem"] = problem
    return schema


def _output_models(schema: dict[str, Any]) -> dict[str, Any]:
    """Every output format's models (:mod:`app.outputs`) under ``components/schemas``: the
    routes list each format's media type with its model (``output_responses``)."""
    schemas = schema.setdefault("components", {}).setdefault("schemas", {})
    for output in OUTPUT_FORMATS.values():
        for model in (output.step_model, output.picture_model):
            if model.__name__ not in schemas:
                found = model.model_json_schema(
                    ref_template="#/components/schemas/{model}", mode="serialization"
                )
                schemas.update(found.pop("$defs", {}))
                schemas[model.__name__] = found
    return schema


def install_openapi(app: FastAPI) -> None:
    """Make ``app.openapi()`` return the service's document (cached after the first call)."""

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            schema = get_openapi(
                title=app.title,
                version=app.version,
                description=app.description,
                routes=app.routes,
            )
            app.openapi_schema = _output_models(_problem_media_types(schema))
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]


def render_openapi(app: FastAPI) -> str:
    """The OpenAPI document as canonical JSON text (sorted keys, two-space indent, final newline)."""
    return json.dumps(app.openapi(), sort_keys=True, indent=2, ensure_ascii=False) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Write the document: ``python -m app.openapi [PATH]`` (default ``openapi.json``)."""
    from app.main import create_app
    from app.settings import Settings

    args = list(sys.argv[1:] if argv is None else argv)
    target = Path(args[0]) if args else DEFAULT_PATH
    target.write_text(render_openapi(create_app(Settings(store="memory"))), encoding="utf-8")
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
