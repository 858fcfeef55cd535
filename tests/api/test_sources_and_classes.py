"""Issue 22 through the real service: a cooperative source's silence, status that follows the
sources' revisits, a session's own class names with a detecting sensor."""

from __future__ import annotations

from typing import Any

import httpx
import numpy as np

from core.simulation.nearby import crossing_scenario

from .conftest import LiveServer

CARTESIAN = {"state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]}}


def create(client: httpx.Client, config: dict[str, Any]) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    body = created.json()
    return body["id"], {"Authorization": f"Bearer {body['token']}"}


def test_an_adsb_source_given_only_its_id_never_deletes_a_radar_only_target(
    live_server: LiveServer,
) -> None:
    """A radar (detections every 4 s, 20 m noise) sees two aircraft; ADS-B (a track list
    every second, configured with its id alone) carries only the first. Over 60 s its lists
    never touch the second one's track: one id, confirmed in every answer (no flicker)."""
    config = CARTESIAN | {
        "sensors": [
            {"id": "radar", "measurement": {"r": [[400, 0], [0, 400]]}},
            {"id": "adsb"},
        ],
        "tracking": {"time_interval": 4.0},
    }
    rng = np.random.default_rng(5)
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = create(client, config)
        radar_only: list[tuple[str, str]] = []
        for second in range(60):
            t = float(second)
            equipped = np.array([150.0 * t, 0.0])
            other = np.array([20_000.0 - 150.0 * t, 5_000.0])
            if second % 4 == 0:
                body = {
                    "sensor": "radar",
                    "time": t,
                    "detections": [
                        {"z": (p + rng.normal(0.0, 20.0, 2)).tolist()} for p in (equipped, other)
                    ],
                }
                answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
                assert answer.status_code == 200, answer.text
            listed = {
                "sensor": "adsb",
                "time": t + 0.5,
                "tracks": [
                    {
                        "id": "3946e5",
                        "state": [150.0 * (t + 0.5), 150.0, 0.0, 0.0],
                        "covariance": np.diag([225.0, 4.0, 225.0, 4.0]).tolist(),
                    }
                ],
            }
            answer = client.post(f"/v1/sessions/{sid}/tracks", json=listed, headers=headers)
            assert answer.status_code == 200, answer.text
            for track in answer.json()["tracks"]:
                if {source["sensor"] for source in track["sources"]} == {"radar"}:
                    radar_only.append((track["id"], track["status"]))
    assert {track_id for track_id, _ in radar_only} == {radar_only[0][0]}
    statuses = [status for _, status in radar_only]
    confirmed = statuses.index("confirmed")
    assert len(statuses) - confirmed >= 30  # 36: ADS-B lists and radar scans alike
    assert set(statuses[confirmed:]) == {"confirmed"}


def test_a_sessions_own_class_names_work_with_a_detecting_sensor(
    live_server: LiveServer,
) -> None:
    """Classes ``airliner`` (allows b1: no manoeuvre) and ``military`` (allows b1, b2, b3):
    Γ(b1) = {airliner, military}, Γ(b2) = Γ(b3) = {military}. [MTT]'s crossing fighter
    (4g turns) is decided ``military``; the unknown aircraft (no manoeuvre) stays tied."""
    scenario = crossing_scenario(seed=0)
    config = CARTESIAN | {
        "classes": ["airliner", "military"],
        "sensors": [{"id": "radar", "measurement": {"r": [[0.2, 0], [0, 0.2]]}}],
        "tracking": {
            "preset": "aircraft",
            "class_behaviours": {"military": ["b1", "b2", "b3"], "airliner": ["b1"]},
        },
    }
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = create(client, config)
        assert client.get(f"/v1/sessions/{sid}", headers=headers).status_code == 200
        for scan in scenario.scans:
            body = {
                "sensor": "radar",
                "time": scan.time,
                "detections": [{"z": z.tolist()} for z in scan.measurements],
            }
            answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
            assert answer.status_code == 200, answer.text
        tracks = answer.json()["tracks"]
        fighter_y = scenario.truths[0].states[-1][2]
        by_distance = sorted(tracks, key=lambda track: abs(track["state"][2] - fighter_y))
        fighter, other = by_distance[0]["classification"], by_distance[-1]["classification"]
        assert set(fighter["pignistic"]) == {"airliner", "military"}
        assert fighter["decision"] == "military" and fighter["pignistic"]["military"] > 0.99
        assert other["decision_state"] == "tied"

        refused = client.post(
            "/v1/sessions",
            json=config
            | {
                "tracking": {
                    "preset": "aircraft",
                    "class_behaviours": {"airliner": ["b9"], "military": ["b1", "b2", "b3"]},
                }
            },
        )
        assert refused.status_code == 422
        (error,) = refused.json()["errors"]
        assert error["pointer"] == "#/tracking/class_behaviours" and "b9" in error["detail"]
        unnamed = client.post(
            "/v1/sessions",
            json=config
            | {
                "tracking": {
                    "preset": "aircraft",
                    "class_behaviours": {"airliner": ["b1", "b2", "b3"]},
                }
            },
        )
        assert unnamed.status_code == 422
        assert unnamed.json()["errors"][0]["pointer"] == "#/tracking/class_behaviours"
