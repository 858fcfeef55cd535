"""Subscribers see every ``seq`` or an explicit ``gap`` (issue 28): a result whose ``seq`` does not
follow the last one sent comes after a ``gap`` message naming the results not delivered
(before: a subscriber saw a silent jump, e.g. when an instance died between logging an input
and publishing its result)."""

from __future__ import annotations

from fastapi.testclient import TestClient

from app.outputs import JSON
from app.sessions.hub import Published
from app.sessions.pipeline import result_message
from app.sessions.registry import SessionRegistry
from tests.api.examples import SESSION_CONFIG
from tests.api.scenario import track_report


def test_a_result_that_skips_seq_is_announced_by_a_gap(client: TestClient) -> None:
    created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
    headers = {"Authorization": f"Bearer {created['token']}"}
    path = f"/v1/sessions/{created['id']}"
    registry: SessionRegistry = client.app.state.registry  # type: ignore[attr-defined]
    with client.websocket_connect(path + "/subscribe", headers=headers) as subscriber:
        assert subscriber.receive_json() == {"type": "ack", "ref": None, "seq": 0}
        first = client.post(
            path + "/tracks", json=track_report("radar-1", 1.0, seed=1), headers=headers
        )
        assert subscriber.receive_json()["result"]["seq"] == 1
        # results 2 and 3 never published (their instance died): the next one is seq 4
        text = first.text.replace('{"seq":1,', '{"seq":4,', 1)
        session = client.portal.call(registry.get, created["id"])  # type: ignore[union-attr]
        client.portal.call(session.hub.publish, Published({JSON: result_message(text)}))  # type: ignore[union-attr]
        assert subscriber.receive_json() == {"type": "gap", "ref": None, "after": 1, "next": 4}
        assert subscriber.receive_json()["result"]["seq"] == 4
