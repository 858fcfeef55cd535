"""Over the API: a target every sensor misses for a few scans keeps its fused id
(docs/algorithms.md §8.15).

Two detecting sensors of the same physics (tracked centrally, §8.9) take turns every
second on one aircraft flying 200 m/s along x, with two false alarms per scan. Both miss it
from 6 s to 11 s: the central tracker deletes its track and confirms a new one when the
detections come back, 1–2 s later than the deletion; the fused picture hands the new
track the old id (the target is predicted there over the gap and nothing else is near).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from fastapi.testclient import TestClient

SCANS = 20
MISSED = range(6, 12)


def _config() -> dict[str, Any]:
    radar = {"p_detect": 0.9, "measurement": {"r": [[100, 0], [0, 100]]}, "clutter_density": 1e-7}
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [{"id": name, **radar} for name in "ab"],
        "tracking": {"preset": "aircraft", "time_interval": 1.0},
    }


def test_a_target_every_sensor_misses_for_a_few_scans_keeps_its_id(client: TestClient) -> None:
    rng = np.random.default_rng(23)
    created = client.post("/v1/sessions", json=_config())
    assert created.status_code == 201, created.text
    sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
    near: list[list[tuple[str, str]]] = []
    for k in range(SCANS):
        truth = np.array([1000.0 + 200.0 * k, 5000.0])
        clutter = rng.uniform((-20_000.0, -20_000.0), (20_000.0, 20_000.0), (2, 2))
        points = list(clutter) + ([] if k in MISSED else [truth + rng.normal(0.0, 10.0, 2)])
        body = {
            "sensor": "ab"[k % 2],
            "time": float(k),
            "detections": [{"z": [float(x), float(y)]} for x, y in points],
        }
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        near.append(
            [
                (track["id"], track["status"])
                for track in answer.json()["tracks"]
                if np.hypot(*(np.asarray(track["state"])[[0, 2]] - truth)) < 500.0
            ]
        )
    before = {track for step in near[2:6] for track, status in step if status == "confirmed"}
    after = {track for step in near[15:] for track, status in step if status == "confirmed"}
    assert len(before) == 1 and after == before, near
    # a deletion and a restart, not a coasting track: the fused track ended in between
    assert any(status == "terminated" for step in near[6:15] for _, status in step), near
    assert any(not step for step in near[6:15]), near
