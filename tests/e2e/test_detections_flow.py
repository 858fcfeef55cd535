"""Detections end to end: a sensor with a measurement model is tracked by the session.

A live server (sqlite store) receives the raw detections of the ``aircraft``
scenario; the fused tracks carry the class assessment of the local credal
classifier; after a restart the session is rebuilt (snapshot + replay of the
logged detections) to exactly the same fused picture.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx
import pytest

from core.simulation import aircraft_scenario

from .test_crash_safety import fused_tracks, server

SCANS = 45


def session_config() -> dict[str, Any]:
    return {
        "name": "radar tracking aircraft",
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "motion": {"model": "constant_velocity", "q": 100.0},
        "classes": ["liner", "bomber", "fighter"],
        "sensors": [{"id": "radar", "p_detect": 0.9, "measurement": {"r": [[0.2, 0], [0, 0.2]]}}],
        "tracking": {"preset": "aircraft", "time_interval": 1.0},
    }


def detection_bodies() -> list[dict[str, Any]]:
    scenario = aircraft_scenario(seed=0)
    return [
        {
            "sensor": "radar",
            "time": scan.time,
            "detections": [{"z": z.tolist()} for z in scan.measurements],
        }
        for scan in scenario.scans[:SCANS]
    ]


def test_detections_are_tracked_classified_and_survive_a_restart(tmp_path: Path) -> None:
    database = tmp_path / "detections.db"
    with server(database) as (url, _):
        created = httpx.post(f"{url}/v1/sessions", json=session_config(), timeout=30)
        assert created.status_code == 201, created.text
        sid = created.json()["id"]
        headers = {"Authorization": f"Bearer {created.json()['token']}"}
        with httpx.Client(base_url=url, headers=headers, timeout=30) as client:
            results = []
            for body in detection_bodies():
                answer = client.post(f"/v1/sessions/{sid}/detections", json=body)
                assert answer.status_code == 200, answer.text
                results.append(answer.json())
            stale = client.post(f"/v1/sessions/{sid}/detections", json=detection_bodies()[3])
        before = fused_tracks(url, sid, headers)

    assert stale.status_code == 409 and stale.json()["last_time"] == results[-1]["time"]
    assert [result["seq"] for result in results] == list(range(1, SCANS + 1))
    # Targets 1, 2 and 3 (appears at step 30) fly straight until step 45: three
    # confirmed fused tracks, each undecided between the classes (BetP ≈ 1/3).
    tracks = results[-1]["tracks"]
    confirmed = [track for track in tracks if track["status"] == "confirmed"]
    assert len(confirmed) == 3
    for track in confirmed:
        pignistic = track["classification"]["pignistic"]
        assert sum(pignistic.values()) == pytest.approx(1.0, abs=1e-12)
        assert all(abs(value - 1 / 3) < 0.1 for value in pignistic.values())
        assert sum(focal["mass"] for focal in track["classification"]["mass"]) == pytest.approx(1.0)

    with server(database) as (url, _):
        assert fused_tracks(url, sid, headers) == before
