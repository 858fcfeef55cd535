"""Schemathesis against the app's own OpenAPI document: no 5xx, no answer that breaks the schema.

Requests go to a live uvicorn server. Cases of a session route get a real
session id and its token (always for reads, half of the time for writes, never for DELETE;
otherwise they keep whatever schemathesis generated), so the auth and
validation paths and the engine's answers are all checked. The number of examples per operation is bounded to keep the suite fast.
"""

from __future__ import annotations

from collections.abc import Iterator

import httpx
import hypothesis
import pytest
import schemathesis
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
)

from app.main import create_app
from tests.api.conftest import LiveServer, make_settings, serving
from tests.api.scenario import session_config, track_report

EXAMPLES_PER_OPERATION = 25

schema = schemathesis.openapi.from_dict(create_app(make_settings()).openapi())


@pytest.fixture(scope="module")
def server() -> Iterator[tuple[LiveServer, str, dict[str, str]]]:
    with serving(make_settings()) as live:
        created = httpx.post(f"{live.url}/v1/sessions", json=session_config()).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        for index, sensor in enumerate(("radar-1", "radar-2")):
            body = track_report(sensor, 1.0 + index / 2, seed=index)
            answer = httpx.post(
                f"{live.url}/v1/sessions/{created['id']}/tracks", json=body, headers=headers
            )
            assert answer.status_code == 200, answer.text
        yield live, created["id"], headers


@schema.parametrize()
@hypothesis.settings(
    max_examples=EXAMPLES_PER_OPERATION,
    deadline=None,
    derandomize=True,
    suppress_health_check=list(hypothesis.HealthCheck),
    # the documented request examples are posted by test_openapi_examples.py (schemathesis
    # cannot run them beside `given`)
    phases=[hypothesis.Phase.generate],
)
@schema.given(real_session=hypothesis.strategies.booleans())
def test_no_server_error_and_answers_match_the_schema(
    case: schemathesis.Case,
    real_session: bool,
    server: tuple[LiveServer, str, dict[str, str]],
) -> None:
    live, sid, headers = server
    method = case.method.upper()
    reading = method == "GET"  # few distinct cases: always reach the real data
    use_real = (real_session or reading) and method != "DELETE"  # the session must live on
    if use_real and case.path_parameters and "sid" in case.path_parameters:
        case.path_parameters["sid"] = sid
        case.headers = {**(case.headers or {}), **headers}
    response = case.call(base_url=live.url)
    assert response.status_code < 500, response.text
    case.validate_response(response, checks=[response_schema_conformance, content_type_conformance])
