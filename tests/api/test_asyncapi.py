"""docs/asyncapi.yaml documents exactly the WebSocket message models."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from app.asyncapi import MESSAGES, render_asyncapi
from app.inputs import DECODED_KINDS, INPUT_KINDS
from tests.api.examples import STEP_RESULT, TRACK_REPORT

COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "asyncapi.yaml"


@pytest.fixture(scope="module")
def document() -> dict[str, Any]:
    loaded: dict[str, Any] = yaml.safe_load(COMMITTED.read_text(encoding="utf-8"))
    return loaded


def resolve(document: dict[str, Any], reference: str) -> dict[str, Any]:
    node: Any = document
    for part in reference.removeprefix("#/").split("/"):
        node = node[part]
    assert isinstance(node, dict)
    return node


def test_committed_asyncapi_matches_the_models() -> None:
    assert COMMITTED.read_text(encoding="utf-8") == render_asyncapi(), (
        "docs/asyncapi.yaml drifted: run `make openapi`"
    )


def test_document_shape(document: dict[str, Any]) -> None:
    assert document["asyncapi"] == "3.0.0"
    answers = {f"{tag}_result" for tag in DECODED_KINDS}
    assert set(document["channels"]["stream"]["messages"]) == {
        *INPUT_KINDS,
        *DECODED_KINDS,
        *answers,
        "result",
        "error",
        "ack",
    }
    assert {"tracks", "detections"} <= set(INPUT_KINDS)
    assert document["channels"]["stream"]["address"] == "/v1/sessions/{sid}/stream"
    assert document["channels"]["subscribe"]["address"] == "/v1/sessions/{sid}/subscribe"
    for operation in document["operations"].values():
        for message in operation["messages"]:
            resolve(document, message["$ref"])


@pytest.mark.parametrize("name", sorted(MESSAGES))
def test_message_payload_matches_its_model(document: dict[str, Any], name: str) -> None:
    model, direction, _ = MESSAGES[name]
    message = document["components"]["messages"][name]
    payload = resolve(document, message["payload"]["$ref"])
    assert set(payload["properties"]) == set(model.model_fields)
    required = {field for field, info in model.model_fields.items() if info.is_required()}
    if direction == "client":
        assert set(payload.get("required", [])) == required
    else:
        assert required <= set(payload.get("required", []))
    tag = payload["properties"]["type"]
    assert tag.get("const") == name, "the type tag must be a required Literal"
    assert "type" in payload["required"] and "default" not in tag
    assert payload.get("additionalProperties") is False


def test_example_messages_only_use_documented_fields(document: dict[str, Any]) -> None:
    tracks_model = MESSAGES["tracks"][0]
    result_model = MESSAGES["result"][0]
    examples = {
        "tracks": tracks_model.model_validate({"type": "tracks", "ref": "a", **TRACK_REPORT}),
        "result": result_model.model_validate(
            {"type": "result", "ref": "a", "result": STEP_RESULT}
        ),
    }
    for name, example in examples.items():
        payload = resolve(document, document["components"]["messages"][name]["payload"]["$ref"])
        assert set(example.model_dump(mode="json")) <= set(payload["properties"])
