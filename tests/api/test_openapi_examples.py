"""Every request example of the app's OpenAPI document works: posted to a live server, 2xx.

The examples are read out of ``app.openapi()`` (what ``/docs`` shows, and "Try it out"
sends), never from :mod:`api_schemas.examples` directly. A route under
``/v1/sessions/{sid}`` gets a session made from the ``POST /v1/sessions`` example of the
same name (the pairing :mod:`api_schemas.examples` documents). Binary bodies (ASTERIX)
carry no JSON example.
"""

from __future__ import annotations

from typing import Any

import httpx
import pytest

from app.main import create_app
from tests.api.conftest import LiveServer, live_server, make_settings

__all__ = ["live_server"]

DOCUMENT = create_app(make_settings()).openapi()
SESSIONS = "/v1/sessions"


def json_bodies() -> list[tuple[str, str, dict[str, Any]]]:
    """(path, method, examples) of every operation with a JSON request body."""
    found = []
    for path, item in DOCUMENT["paths"].items():
        for method, operation in item.items():
            content = operation.get("requestBody", {}).get("content", {})
            if "application/json" in content:
                found.append((path, method, content["application/json"].get("examples", {})))
    return found


EXAMPLES = [
    pytest.param(path, method, name, example["value"], id=f"{method} {path} {name}")
    for path, method, examples in json_bodies()
    for name, example in examples.items()
]
SESSION_EXAMPLES = DOCUMENT["paths"][SESSIONS]["post"]["requestBody"]["content"][
    "application/json"
]["examples"]


def test_the_only_bodies_without_a_json_example_are_binary() -> None:
    """ASTERIX data blocks (``application/octet-stream``): Swagger UI offers a file to send."""
    others = {
        (path, media)
        for path, item in DOCUMENT["paths"].items()
        for operation in item.values()
        for media in operation.get("requestBody", {}).get("content", {})
        if media != "application/json"
    }
    assert others == {(f"{SESSIONS}/{{sid}}/asterix", "application/octet-stream")}


def test_every_json_request_body_has_examples_with_a_summary() -> None:
    bodies = json_bodies()
    assert {(path, method) for path, method, _ in bodies} >= {
        (SESSIONS, "post"),
        (f"{SESSIONS}/{{sid}}/tracks", "post"),
        (f"{SESSIONS}/{{sid}}/detections", "post"),
        ("/v1/associate", "post"),
    }
    for path, method, examples in bodies:
        assert examples, f"{method} {path} has no request example"
        for name, example in examples.items():
            assert example["summary"] and set(example) <= {"summary", "description", "value"}, (
                path,
                name,
            )
            if "{sid}" in path:
                assert name in SESSION_EXAMPLES, f"{method} {path} {name}: no session example"


@pytest.mark.parametrize(("path", "method", "name", "body"), EXAMPLES)
def test_each_request_example_is_accepted_by_the_running_app(
    live_server: LiveServer, path: str, method: str, name: str, body: dict[str, Any]
) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30.0) as client:
        headers: dict[str, str] = {}
        if "{sid}" in path:
            created = client.post(SESSIONS, json=SESSION_EXAMPLES[name]["value"])
            assert created.status_code == 201, created.text
            session = created.json()
            path = path.replace("{sid}", session["id"])
            headers["Authorization"] = f"Bearer {session['token']}"
        answer = client.request(method, path, json=body, headers=headers)
        assert 200 <= answer.status_code < 300, answer.text
        if path.endswith(("/tracks", "/detections")):
            assert answer.json()["seq"] == 1
