"""Against a real server: a ``stream`` message without a valid ``type`` is told which types exist."""

from __future__ import annotations

import json

import httpx
from websockets.sync.client import connect

from tests.api.conftest import LiveServer
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT

RECEIVE_TIMEOUT_S = 30.0


def test_the_rest_body_over_stream_gets_the_allowed_types(live_server: LiveServer) -> None:
    created = httpx.post(f"{live_server.url}/v1/sessions", json=SESSION_CONFIG).json()
    url = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{created['id']}/stream"
    headers = {"Authorization": f"Bearer {created['token']}"}
    with connect(url, additional_headers=headers) as stream:
        assert json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))["type"] == "ack"
        stream.send(json.dumps(TRACK_REPORT | {"ref": "untagged"}))  # the REST body as is
        untagged = json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))
        stream.send(json.dumps(TRACK_REPORT | {"type": "track", "ref": "typo"}))
        typo = json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))
        stream.send(json.dumps(TRACK_REPORT | {"type": "tracks", "ref": "right"}))
        right = json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))
    for answer, ref in ((untagged, "untagged"), (typo, "typo")):
        assert answer["type"] == "error" and answer["ref"] == ref
        assert answer["problem"]["status"] == 422
        [error] = answer["problem"]["errors"]
        assert error["loc"] == ["type"] and error["pointer"] == "#/type"
        assert "'tracks' or 'detections'" in error["detail"]
        assert "'tracks' or 'detections'" in answer["problem"]["detail"]
    assert untagged["problem"]["errors"][0]["detail"].startswith("Field required")
    assert typo["problem"]["errors"][0]["detail"].startswith("'track' is not a message type")
    assert right["type"] == "result" and right["ref"] == "right"
    assert right["result"]["tracks"][0]["id"] == "F1"
