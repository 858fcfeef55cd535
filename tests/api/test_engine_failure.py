"""Refused inputs change nothing: the engine's transactions, and the registry's last defence.

A step that fails inside the engine (any exception) is rolled back by the engine itself:
the session is as before and nothing is rebuilt. Only an engine that changed anyway (a bug
in that rollback, simulated here) makes the registry rebuild the session from its log,
which ``/metrics`` counts.
"""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from core.errors import InvalidInput
from core.fusion.engine import SessionEngine

from .scenario import session_config, track_report

REBUILDS = 'credal_session_rebuilds_total{reason="refused_after_change"}'


def post(client: TestClient, sid: str, headers: dict[str, str], body: dict[str, Any]) -> Any:
    return client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)


def rebuilds(client: TestClient) -> float:
    for line in client.get("/metrics").text.splitlines():
        if line.startswith(REBUILDS):
            return float(line.split()[-1])
    return 0.0


def check_refused_then_continues(
    client: TestClient, monkeypatch: pytest.MonkeyPatch, name: str, failing: Any
) -> None:
    created = client.post("/v1/sessions", json=session_config()).json()
    sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
    first, second = track_report("radar-1", 1.0, seed=1), track_report("radar-2", 1.5, seed=2)
    assert post(client, sid, headers, first).status_code == 200
    picture = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
    session = client.get(f"/v1/sessions/{sid}", headers=headers).json()

    with monkeypatch.context() as patched:
        patched.setattr(SessionEngine, name, failing)
        refused = post(client, sid, headers, second)
    assert refused.status_code == 422, refused.text
    assert client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json() == picture
    assert client.get(f"/v1/sessions/{sid}", headers=headers).json() == session

    accepted = post(client, sid, headers, second)
    assert accepted.status_code == 200 and accepted.json()["seq"] == 2
    uninterrupted = client.post("/v1/sessions", json=session_config()).json()
    other = {"Authorization": f"Bearer {uninterrupted['token']}"}
    post(client, uninterrupted["id"], other, first)
    assert accepted.json() == post(client, uninterrupted["id"], other, second).json()


def test_a_step_failing_inside_the_engine_is_rolled_back_by_the_engine(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    def fail_after_changing(engine: SessionEngine, *args: object) -> None:
        assert engine.seq == 2  # the step had moved on: the transaction undoes it
        raise InvalidInput("time: a failure after the step changed the engine")

    check_refused_then_continues(client, monkeypatch, "_life_cycle", fail_after_changing)
    assert rebuilds(client) == 0.0  # no last defence needed


def test_an_engine_changed_by_a_refused_input_is_rebuilt_from_the_log_and_counted(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    def change_then_fail(engine: SessionEngine, *args: object, **options: object) -> None:
        engine.seq += 1  # a rollback bug: the engine changed, and refuses the input
        engine.next_number += 1
        raise InvalidInput("time: a failure that the engine did not undo")

    check_refused_then_continues(client, monkeypatch, "apply", change_then_fail)
    assert rebuilds(client) == 1.0
