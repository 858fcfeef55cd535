"""An engine that fails after it changed: the session is rebuilt from its log, nothing is lost."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from core.errors import InvalidInput
from core.fusion.engine import SessionEngine

from .scenario import session_config, track_report


def post(client: TestClient, sid: str, headers: dict[str, str], body: dict[str, Any]) -> Any:
    return client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)


def test_an_input_refused_after_the_engine_changed_leaves_the_session_as_its_log_says(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    created = client.post("/v1/sessions", json=session_config()).json()
    sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
    first, second = track_report("radar-1", 1.0, seed=1), track_report("radar-2", 1.5, seed=2)
    assert post(client, sid, headers, first).status_code == 200
    picture = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()

    def fail_after_changing(engine: SessionEngine, *args: object) -> None:
        raise InvalidInput("time: a failure after the step changed the engine")

    with monkeypatch.context() as patched:  # the life cycle runs after the step moved seq on
        patched.setattr(SessionEngine, "_manage", fail_after_changing)
        refused = post(client, sid, headers, second)
    assert refused.status_code == 422, refused.text
    assert client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json() == picture

    accepted = post(client, sid, headers, second)
    assert accepted.status_code == 200 and accepted.json()["seq"] == 2
    uninterrupted = client.post("/v1/sessions", json=session_config()).json()
    other = {"Authorization": f"Bearer {uninterrupted['token']}"}
    post(client, uninterrupted["id"], other, first)
    assert accepted.json() == post(client, uninterrupted["id"], other, second).json()
