"""Two detecting sensors over REST: one central tracker (docs/algorithms.md §8.9).

One aircraft is seen by radar a at every scan, or alternately by radars a and b of
the same physics. Tracked centrally, the alternating radars confirm it at the same
scan as radar a alone, under the source ``central``, and each sensor's tally counts its
own detections; flagged ``local_tracker``, each radar's own tracker has half the
detections: nothing is confirmed by then.
"""

from __future__ import annotations

from typing import Any

import httpx

from tests.api.conftest import LiveServer

SCANS = 4


def _config(sensors: str, local: bool) -> dict[str, Any]:
    radar = {
        "p_detect": 0.9,
        "measurement": {"r": [[100, 0], [0, 100]]},
        "clutter_density": 1e-6,
        "local_tracker": local,
    }
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [{"id": name, **radar} for name in sensors],
        "tracking": {"preset": "aircraft", "time_interval": 1.0},
    }


def _run(
    client: httpx.Client, sensors: str, local: bool = False
) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    created = client.post("/v1/sessions", json=_config(sensors, local))
    assert created.status_code == 201, created.text
    sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
    assert [s["local_tracker"] for s in created.json()["config"]["sensors"]] == [local] * len(
        sensors
    )
    answers = []
    for k in range(SCANS):
        body = {
            "sensor": sensors[k % len(sensors)],
            "time": float(k),
            "detections": [{"z": [1000.0 + 200.0 * k, 5000.0 - 3.0 * k]}],
        }
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        answers.append(answer.json())
    return answers, client.get(f"/v1/sessions/{sid}", headers=headers).json()


def _first_confirmed(answers: list[dict[str, Any]]) -> int | None:
    for k, answer in enumerate(answers):
        if any(track["status"] == "confirmed" for track in answer["tracks"]):
            return k
    return None


def test_two_detecting_sensors_share_one_central_tracker(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        alone, _ = _run(client, "a")
        central, session = _run(client, "ab")
        local, _ = _run(client, "ab", local=True)
    first = _first_confirmed(alone)
    assert first is not None and _first_confirmed(central) == first
    (track,) = central[-1]["tracks"]
    assert [source["sensor"] for source in track["sources"]] == ["central"]
    assert central[-1]["sensor"] == "b"
    tallies = {s["id"]: s["detections"]["detections"] for s in session["sensors"]}
    assert tallies == {"a": SCANS // 2, "b": SCANS // 2}
    assert _first_confirmed(local) is None
