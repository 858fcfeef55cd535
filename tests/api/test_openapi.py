"""The committed openapi.json is exactly what the app generates; its conventions hold."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from app.main import create_app
from app.openapi import render_openapi
from tests.api.conftest import make_settings

COMMITTED = Path(__file__).resolve().parents[2] / "openapi.json"


def generated() -> str:
    return render_openapi(create_app(make_settings()))


def test_committed_openapi_matches_the_app() -> None:
    assert COMMITTED.exists(), "openapi.json is missing: run `make openapi`"
    assert COMMITTED.read_text(encoding="utf-8") == generated(), (
        "openapi.json drifted: run `make openapi`"
    )


def test_rendering_is_deterministic() -> None:
    assert generated() == generated()


def operations(document: dict[str, Any]) -> list[dict[str, Any]]:
    return [
        operation for path_item in document["paths"].values() for operation in path_item.values()
    ]


def test_operation_ids_are_readable_and_unique() -> None:
    document = json.loads(generated())
    ids = [operation["operationId"] for operation in operations(document)]
    assert len(ids) == len(set(ids))
    assert all(identifier.isidentifier() and identifier.islower() for identifier in ids)
    assert {"create_session", "list_sessions", "delete_session", "get_health"} <= set(ids)


def test_errors_are_documented_as_problem_json() -> None:
    document = json.loads(generated())
    for operation in operations(document):
        for status, response in operation["responses"].items():
            if status.startswith(("4", "5")):
                assert list(response["content"]) == ["application/problem+json"], (
                    operation["operationId"],
                    status,
                )
    assert "HTTPValidationError" not in json.dumps(document)


def test_every_route_with_a_body_documents_the_413_and_408_of_its_body_limits() -> None:
    document = json.loads(generated())
    with_body = [
        (path, method, operation)
        for path, item in document["paths"].items()
        for method, operation in item.items()
        if "requestBody" in operation
    ]
    assert len(with_body) >= 4  # sessions, tracks, detections, associate
    for path, method, operation in with_body:
        assert {"408", "413"} <= operation["responses"].keys(), (method, path)
