"""Against a real server: a tie at the top of BetP decides nothing, on every channel.

The README's example is a tie: radar-1 (reliability λ = 0.9) reports
m({bomber, fighter}) = 0.6, m(Ω) = 0.4. Discounted ([MTT] eq 7):
m({bomber, fighter}) = 0.54, m(Ω) = 0.46, so by hand
BetP(bomber) = BetP(fighter) = 0.54 / 2 + 0.46 / 3 = 0.42333…,
BetP(liner) = 0.46 / 3 = 0.15333….
"""

from __future__ import annotations

import json
from typing import Any

import httpx
import pytest
from websockets.sync.client import connect

from tests.api.conftest import LiveServer
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT

HAND_WORKED_BETP = {"liner": 0.46 / 3, "bomber": 0.27 + 0.46 / 3, "fighter": 0.27 + 0.46 / 3}
RECEIVE_TIMEOUT_S = 30.0


def check_tied(classification: dict[str, Any]) -> None:
    assert classification["pignistic"] == pytest.approx(HAND_WORKED_BETP, abs=1e-12)
    assert classification["decision"] is None
    assert classification["decision_state"] == "tied"


def test_a_tie_gives_a_null_decision_over_rest_stream_and_subscribe(
    live_server: LiveServer,
) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
        sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
        ws = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}"
        with connect(f"{ws}/subscribe", additional_headers=headers) as subscriber:
            assert json.loads(subscriber.recv(timeout=RECEIVE_TIMEOUT_S))["type"] == "ack"
            step = client.post(f"/v1/sessions/{sid}/tracks", json=TRACK_REPORT, headers=headers)
            assert step.status_code == 200, step.text
            check_tied(step.json()["tracks"][0]["classification"])
            pushed = json.loads(subscriber.recv(timeout=RECEIVE_TIMEOUT_S))
            check_tied(pushed["result"]["tracks"][0]["classification"])
        picture = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
        check_tied(picture["tracks"][0]["classification"])
        detail = client.get(f"/v1/sessions/{sid}/tracks/F1", headers=headers).json()
        check_tied(detail["track"]["classification"])
        # A second report leaning to the fighter breaks the tie.
        leaning = json.loads(json.dumps(TRACK_REPORT))
        leaning["time"] = 13.5
        leaning["tracks"][0]["state"] = [103.0, 3.0, 249.0, -1.0]
        leaning["tracks"][0]["classification"] = {
            "mass": [
                {"set": ["fighter"], "mass": 0.2},
                {"set": ["liner", "bomber", "fighter"], "mass": 0.8},
            ]
        }
        with connect(f"{ws}/stream", additional_headers=headers) as stream:
            assert json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))["type"] == "ack"
            stream.send(json.dumps(leaning | {"type": "tracks"}))
            answer = json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))
    decided = answer["result"]["tracks"][0]["classification"]
    assert decided["decision"] == "fighter" and decided["decision_state"] == "decided"
