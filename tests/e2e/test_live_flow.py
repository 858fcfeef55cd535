"""Against a real uvicorn server on 127.0.0.1: two sensors fuse over REST, ``stream`` and ``subscribe``."""

from __future__ import annotations

import json
from typing import Any

import httpx
import pytest
from websockets.exceptions import ConnectionClosedOK
from websockets.sync.client import ClientConnection, connect

from api_schemas.results import FusedPicture, FusedTrackDetail, StepResult
from api_schemas.sessions import SessionSummary
from api_schemas.ws import server_message_adapter
from tests.api.conftest import LiveServer
from tests.api.scenario import check_fused_track, reports, session_config

STEPS = 8
RECEIVE_TIMEOUT_S = 30.0


def create(client: httpx.Client) -> tuple[str, dict[str, str]]:
    answer = client.post("/v1/sessions", json=session_config())
    assert answer.status_code == 201, answer.text
    created = answer.json()
    return created["id"], {"Authorization": f"Bearer {created['token']}"}


def ws_url(server: LiveServer, sid: str, channel: str) -> str:
    return server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/{channel}"


def receive(connection: ClientConnection) -> dict[str, Any]:
    message = json.loads(connection.recv(timeout=RECEIVE_TIMEOUT_S))
    server_message_adapter.validate_python(
        message
    )  # every server message matches asyncapi's models
    assert isinstance(message, dict)
    return message


def post_all(client: httpx.Client, sid: str, headers: dict[str, str]) -> list[dict[str, Any]]:
    results = []
    for body in reports(STEPS):
        answer = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        results.append(answer.json())
    return results


def test_two_sensors_fuse_over_rest(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = create(client)
        results = post_all(client, sid, headers)
        for seq, result in enumerate(results, start=1):
            StepResult.model_validate(result)
            assert result["seq"] == seq
            for track in result["tracks"]:
                check_fused_track(track)
        final = results[-1]
        assert [track["status"] for track in final["tracks"]] == ["confirmed"] * 3
        assert all(
            {source["sensor"] for source in track["sources"]} == {"radar-1", "radar-2"}
            for track in final["tracks"]
        )
        assert {pair["basis"] for pair in final["association"]["pairs"]} == {"continuity"}
        # Target 0's evidence is all on {bomber, fighter}: BetP ties them, nothing is decided.
        decisions = [
            (track["classification"]["decision"], track["classification"]["decision_state"])
            for track in final["tracks"]
        ]
        assert decisions == [(None, "tied"), ("liner", "decided"), ("fighter", "decided")]

        picture = FusedPicture.model_validate(
            client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
        )
        assert picture.seq == STEPS and [t.id for t in picture.tracks] == ["F1", "F2", "F3"]
        ahead = client.get(
            f"/v1/sessions/{sid}/tracks", params={"time": final["time"] + 10}, headers=headers
        ).json()
        assert ahead["time"] == final["time"] + 10
        assert ahead["tracks"][0]["state"][0] > picture.tracks[0].state[0]  # moving in +x

        detail = FusedTrackDetail.model_validate(
            client.get(f"/v1/sessions/{sid}/tracks/F1", headers=headers).json()
        )
        assert [point.time for point in detail.history] == [r["time"] for r in results]

        summary = SessionSummary.model_validate(
            client.get(f"/v1/sessions/{sid}", headers=headers).json()
        )
        assert summary.seq == STEPS and summary.time == final["time"]
        assert [(s.id, s.inputs) for s in summary.sensors] == [("radar-1", 4), ("radar-2", 4)]
        assert summary.counts.confirmed == 3 and summary.counts.terminated == 0

        explained = client.post(
            f"/v1/sessions/{sid}/tracks",
            params={"explain": "true"},
            json=reports(STEPS + 1)[-1] | {"tracks": reports(STEPS + 1)[-1]["tracks"][:1]},
            headers=headers,
        ).json()
        assert explained["association"]["matrix"] is not None


def test_same_flow_over_stream_gives_the_same_results(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        rest_sid, rest_headers = create(client)
        rest_results = post_all(client, rest_sid, rest_headers)
        sid, headers = create(client)
    with connect(ws_url(live_server, sid, "stream"), additional_headers=headers) as stream:
        assert receive(stream) == {"type": "ack", "ref": None, "seq": 0}
        for index, body in enumerate(reports(STEPS)):  # send everything, then read
            stream.send(json.dumps(body | {"type": "tracks", "ref": f"r{index}"}))
        answers = [receive(stream) for _ in range(STEPS)]
        stream.send(json.dumps(reports(1)[0] | {"type": "tracks", "ref": "late"}))
        stale = receive(stream)
        stream.send(
            '{"type": "tracks", "ref": "bad", "sensor": "radar-1", "time": NaN, "tracks": []}'
        )
        bad = receive(stream)
        stream.send(json.dumps(reports(STEPS + 1)[-1] | {"type": "tracks", "ref": "after"}))
        after = receive(stream)
    assert [answer["ref"] for answer in answers] == [f"r{index}" for index in range(STEPS)]
    assert [answer["result"] for answer in answers] == rest_results
    assert stale["type"] == "error" and stale["ref"] == "late"
    assert stale["problem"]["status"] == 409 and stale["problem"]["last_time"] == 4.0
    assert bad["type"] == "error" and bad["ref"] == "bad"
    assert bad["problem"]["errors"][0]["loc"] == ["time"]
    assert after["type"] == "result" and after["result"]["seq"] == STEPS + 1


def test_subscriber_receives_every_result_in_order(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = create(client)
        with connect(ws_url(live_server, sid, "subscribe"), additional_headers=headers) as sub:
            assert receive(sub)["type"] == "ack"
            results = post_all(client, sid, headers)
            received = [receive(sub) for _ in range(STEPS)]
            assert client.delete(f"/v1/sessions/{sid}", headers=headers).status_code == 204
            with pytest.raises(ConnectionClosedOK):
                sub.recv(timeout=RECEIVE_TIMEOUT_S)
        assert [message["result"] for message in received] == results
        assert [message["result"]["seq"] for message in received] == list(range(1, STEPS + 1))


def test_websocket_upgrade_needs_the_sessions_token(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, _ = create(client)
        _, other = create(client)
    for headers, status in (({}, 401), (other, 404)):  # 404: no existence oracle
        try:
            with connect(ws_url(live_server, sid, "stream"), additional_headers=headers):
                raise AssertionError("the upgrade should have been refused")
        except Exception as refused:  # websockets.InvalidStatus
            response = getattr(refused, "response", None)
            assert response is not None and response.status_code == status
            assert json.loads(response.body)["status"] == status
