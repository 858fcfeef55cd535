"""Over the real API: a 3-D polar radar confirms a straight-flying target and keeps its id."""

from __future__ import annotations

import math
from typing import Any

import httpx
import numpy as np

from .conftest import LiveServer

LAYOUT_3D = {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]}
POLAR_3D = {
    "kind": "polar",
    "sigma_range": 20.0,
    "sigma_azimuth_deg": 0.2,
    "sigma_elevation_deg": 0.2,
}


def _polar(offset: np.ndarray) -> dict[str, float]:
    east, north, up = (float(x) for x in offset)
    return {
        "range": math.sqrt(east**2 + north**2 + up**2),
        "azimuth_deg": math.degrees(math.atan2(east, north)),
        "elevation_deg": math.degrees(math.atan2(up, math.hypot(east, north))),
    }


def test_3d_polar_radar_confirms_and_keeps_one_fused_id(live_server: LiveServer) -> None:
    """Noise-free detections of a target at 20 km (σ_range 20 m, σ_az = σ_el = 0.2°), default
    densities (one per km³): a fused track within 5 scans, the same one id to scan 20, where
    the truth is (converted covariance at 20 km: ≈ 70 m cross-range)."""
    config: dict[str, Any] = {
        "state": LAYOUT_3D,
        "sensors": [{"id": "radar", "measurement": POLAR_3D}],
    }
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=config)
        assert created.status_code == 201, created.text
        sid = created.json()["id"]
        headers = {"Authorization": f"Bearer {created.json()['token']}"}
        ids: list[set[str]] = []
        for scan in range(20):
            truth = np.array([12000.0 + 150.0 * scan, 16000.0 - 60.0 * scan, 3000.0])
            body = {"sensor": "radar", "time": float(scan), "detections": [_polar(truth)]}
            answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
            assert answer.status_code == 200, answer.text
            tracks = answer.json()["tracks"]
            ids.append({t["id"] for t in tracks if t["status"] == "confirmed"})
        first = next(scan for scan, seen in enumerate(ids) if seen)
        assert first <= 4, ids
        assert all(len(seen) == 1 for seen in ids[first:]), ids
        assert len(set().union(*ids)) == 1, ids
        (track,) = (t for t in tracks if t["status"] == "confirmed")
        state = np.asarray(track["state"])
        assert np.linalg.norm(state[[0, 2, 4]] - truth) < 60.0
        assert np.linalg.norm(state[[1, 3, 5]] - (150.0, -60.0, 0.0)) < 10.0
