"""An ``Idempotency-Key`` on inputs (issue 28): a retried input returns its first answer."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.api.examples import SESSION_CONFIG
from tests.api.scenario import track_report


def test_a_retried_input_is_applied_once_and_answered_the_same(client: TestClient) -> None:
    created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
    path = f"/v1/sessions/{created['id']}/tracks"
    headers = {"Authorization": f"Bearer {created['token']}", "Idempotency-Key": "scan-0001"}
    report = track_report("radar-1", 12.5, seed=1)
    first = client.post(path, json=report, headers=headers)
    again = client.post(path, json=report, headers=headers)
    assert first.status_code == again.status_code == 200
    assert again.content == first.content and first.json()["seq"] == 1
    summary = client.get(f"/v1/sessions/{created['id']}", headers=headers).json()
    assert summary["seq"] == 1  # applied once
    other = client.post(path, json=track_report("radar-1", 13.0, seed=2), headers=headers)
    assert other.status_code == 409
    assert other.json()["type"] == "urn:credal-fusion:problem:idempotency-key-reused"
