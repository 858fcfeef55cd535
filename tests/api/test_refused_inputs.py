"""Refused inputs leave a session as it was, across a restart (real uvicorn, sqlite store).

An all-zero class-likelihood report (no class possible) and an overflowing state
are 422 naming the field; the session's picture, its log and the ids of new
tracks are exactly those of a session that never saw them, before and after
the server restarts from its store.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx

from .conftest import make_settings, serving
from .scenario import session_config, track_report

ZERO = {"liner": 0.0, "bomber": 0.0, "fighter": 0.0}


def new_target(sensor: str, time: float, track_id: str, x: float) -> dict[str, Any]:
    """One track far from the scene's targets: the engine starts a new fused track."""
    return {
        "sensor": sensor,
        "time": time,
        "tracks": [
            {
                "id": track_id,
                "state": [x, 0.0, -50_000.0, 0.0],
                "covariance": [[4.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 4.0, 0], [0, 0, 0, 1.0]],
            }
        ],
    }


def refused_bodies() -> list[tuple[dict[str, Any], str]]:
    zero = track_report("radar-2", 1.5, seed=2)
    zero["tracks"][1]["classification"] = {"likelihoods": ZERO}
    overflow = track_report("radar-2", 1.5, seed=2)
    overflow["tracks"][0]["state"] = [1.7e308, 1e308, 0.0, 0.0]
    return [(zero, "likelihoods are all zero"), (overflow, "tracks[0].state[0]")]


def test_refused_reports_change_nothing_and_ids_continue_alike_after_a_restart(
    tmp_path: Path,
) -> None:
    settings = make_settings(store=f"sqlite:{tmp_path / 'store.db'}")
    with serving(settings) as server, httpx.Client(base_url=server.url) as client:
        sessions = {}
        for name in ("refusing", "control"):
            created = client.post("/v1/sessions", json=session_config()).json()
            sessions[name] = (created["id"], {"Authorization": f"Bearer {created['token']}"})

        def post(name: str, body: dict[str, Any]) -> httpx.Response:
            sid, headers = sessions[name]
            return client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)

        def picture(name: str) -> Any:
            sid, headers = sessions[name]
            return client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()

        for name in sessions:
            assert post(name, track_report("radar-1", 1.0, seed=1)).status_code == 200
        before = picture("refusing")
        for body, field in refused_bodies():
            refused = post("refusing", body)
            assert refused.status_code == 422, refused.text
            assert field in refused.json()["detail"]
            assert picture("refusing") == before
        for name in sessions:
            step = post(name, new_target("radar-2", 2.0, "far-1", 90_000.0))
            assert step.status_code == 200
        assert picture("refusing") == picture("control")
        assert {track["id"] for track in picture("refusing")["tracks"]} >= {"F4"}
        sid, headers = sessions["refusing"]
        log = client.get(f"/v1/sessions/{sid}/events", headers=headers).json()
        assert log["last_seq"] == 2 and len(log["events"]) == 2  # the accepted inputs only

    with serving(settings) as server, httpx.Client(base_url=server.url) as client:
        ids = {}
        for name, (sid, headers) in sessions.items():
            step = client.post(
                f"/v1/sessions/{sid}/tracks",
                json=new_target("radar-1", 3.0, "far-2", -90_000.0),
                headers=headers,
            )
            assert step.status_code == 200, step.text
            ids[name] = sorted(track["id"] for track in step.json()["tracks"])
            assert step.json()["seq"] == 3
        assert ids["refusing"] == ids["control"]
        assert "F5" in ids["refusing"]
