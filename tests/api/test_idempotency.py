"""An ``Idempotency-Key`` on inputs (issue 28): a retried input returns its first answer."""

from __future__ import annotations

from datetime import UTC, datetime

from fastapi.testclient import TestClient

from app.sessions.live import IDEMPOTENCY_BYTES, IDEMPOTENCY_KEYS, new_session
from app.stores import SessionRecord
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


def test_a_stream_message_with_a_key_is_applied_once(client: TestClient) -> None:
    created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
    headers = {"Authorization": f"Bearer {created['token']}"}
    report = track_report("radar-1", 12.5, seed=1)
    rest = client.post(
        f"/v1/sessions/{created['id']}/tracks",
        json=report,
        headers=headers | {"Idempotency-Key": "scan-0001"},
    )
    with client.websocket_connect(
        f"/v1/sessions/{created['id']}/stream", headers=headers
    ) as stream:
        assert stream.receive_json()["seq"] == 1
        message = {"type": "tracks", "ref": "a", "idempotency_key": "scan-0001", **report}
        stream.send_json(message)
        again = stream.receive_json()  # one key for REST and stream: the REST answer comes back
        assert (again["type"], again["ref"]) == ("result", "a")
        assert again["result"] == rest.json()
        later = track_report("radar-1", 13.0, seed=2)
        stream.send_json({"type": "tracks", "idempotency_key": "scan-0001", **later})
        refused = stream.receive_json()
        assert refused["type"] == "error"
        assert refused["problem"]["status"] == 409
        stream.send_json({"type": "tracks", "idempotency_key": "bad key", **later})
        invalid = stream.receive_json()
        assert invalid["type"] == "error" and invalid["problem"]["status"] == 422
    assert client.get(f"/v1/sessions/{created['id']}", headers=headers).json()["seq"] == 1


def test_a_session_keeps_its_latest_keys_within_both_bounds() -> None:
    session = new_session(
        SessionRecord(id="s", config=SESSION_CONFIG, token_hash="h", created_at=datetime.now(UTC))
    )
    for index in range(IDEMPOTENCY_KEYS + 10):
        session.remember(f"k{index}", "f", "x")
    assert list(session.answered) == [f"k{index}" for index in range(10, IDEMPOTENCY_KEYS + 10)]
    big = "y" * (IDEMPOTENCY_BYTES // 3)
    for index in range(4):
        session.remember(f"big{index}", "f", big)
    # the answers beyond the latest fit IDEMPOTENCY_BYTES: the latest three big ones, no small one
    assert list(session.answered) == ["big1", "big2", "big3"]
    huge = "z" * (2 * IDEMPOTENCY_BYTES)
    session.remember("huge", "f", huge)
    assert list(session.answered) == ["huge"]  # the latest is kept whatever its size
    assert session.answered_chars == len(huge)
