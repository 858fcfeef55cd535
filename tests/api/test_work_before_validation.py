"""A large input beyond ``max_input_work`` is refused on its parsed body, before it is validated
(:func:`app.routes.inputs._work_precheck`): the same refusal as after validation, at a fraction
of the CPU (an anonymous crowd's refused inputs cost their parse, not their validation)."""

from __future__ import annotations

import json
from typing import Any

from fastapi.testclient import TestClient

from app.http.requests import OFFLOAD_BYTES
from app.main import create_app
from tests.api.conftest import make_settings
from tests.api.scenario import session_config, track_report

TARGETS = 150
MAX_WORK = 2 * TARGETS  # the first list (150 × (0 + 1)) passes, a second (150 × 151) does not


def refusal(answer: Any) -> tuple[int, str | None, str]:
    problem = answer.json()
    return answer.status_code, problem.get("limit"), json.dumps(problem.get("errors"))


def test_work_is_refused_before_the_body_is_validated() -> None:
    settings = make_settings(max_input_work=MAX_WORK, max_body_bytes=1 << 20)
    with TestClient(create_app(settings)) as client:
        created = client.post("/v1/sessions", json=session_config()).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        path = f"/v1/sessions/{created['id']}/tracks"
        first = track_report("radar-1", 1.0, seed=1, targets=TARGETS)
        assert len(json.dumps(first)) > OFFLOAD_BYTES  # a body parsed off the event loop
        assert client.post(path, json=first, headers=headers).status_code == 200

        second = track_report("radar-2", 1.0, seed=2, targets=TARGETS)
        valid = client.post(path, json=second, headers=headers)
        assert valid.status_code == 422 and valid.json()["limit"] == "max_input_work"
        assert valid.json()["actual"] == TARGETS * (TARGETS + 1)  # items × (known + 1)

        # the same list with its last track's covariance broken: validation would name it; the
        # work check comes first and gives the same refusal as for the valid list
        broken = json.loads(json.dumps(second))
        broken["tracks"][-1]["covariance"] = "not a matrix"
        answer = client.post(path, json=broken, headers=headers)
        assert refusal(answer) == refusal(valid)
        summary = client.get(f"/v1/sessions/{created['id']}", headers=headers).json()
        assert summary["seq"] == 1  # nothing else applied


def test_another_sessions_token_gets_no_precheck() -> None:
    """The check runs for the session the token opens only: another session's token is left
    to the route, which refuses it as it always has (no existence oracle in the check)."""
    settings = make_settings(max_input_work=MAX_WORK, max_body_bytes=1 << 20)
    with TestClient(create_app(settings)) as client:
        mine = client.post("/v1/sessions", json=session_config()).json()
        other = client.post("/v1/sessions", json=session_config()).json()
        headers = {"Authorization": f"Bearer {other['token']}"}
        path = f"/v1/sessions/{mine['id']}/tracks"
        first = track_report("radar-1", 1.0, seed=1, targets=TARGETS)
        answer = client.post(path, json=first, headers=headers)
        assert answer.status_code in (401, 403, 404)
