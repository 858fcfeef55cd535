"""A track leaving a sensor's view, through the service (docs/algorithms.md §8.16).

One sensor with a sector field of view (apex at the origin, ±45° about +x, out to 20 km)
sees an aircraft flying north at 20 m/s along x = 7071 m, across the sector's +45° side.
At the first scans after the crossing the track's predicted position is a few metres
outside the view; its gate still reaches in. With the defaults the scan is a miss scored
``ln(p_region − P_D p)``: the track's score falls by ``ln(1 − 0.9 p)``, p = Φ(m / σ_n)
worked by hand from the track's own estimate on the wire (m the signed distance to the
side, σ_n² = nᵀPn across it; the range edge is kilometres away: p_region = 1). With the
paper profile the predicted position outside every view is a blind zone: a phantom.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient

EDGE = 7071.0
SPEED = 20.0
P_DETECT = 0.9


def _config(profile: str | None) -> dict[str, Any]:
    tracking: dict[str, Any] = {"preset": "aircraft", "time_interval": 1.0}
    if profile is not None:
        tracking["profile"] = profile
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [
            {
                "id": "a",
                "p_detect": P_DETECT,
                "measurement": {"r": [[25, 0], [0, 25]]},
                "clutter_density": 1e-7,
                "fov": {
                    "kind": "sector",
                    "origin": [0, 0],
                    "heading_deg": 0,
                    "half_angle_deg": 45,
                    "range": [0, 20000],
                },
            }
        ],
        "tracking": tracking,
    }


def _run(client: TestClient, profile: str | None, scans: int) -> list[dict[str, Any]]:
    """The track of each scan's answer: detected at y = 6901 … 7061 m (k = 1 … 9, inside the
    side y ≤ x), none from k = 10 on (the aircraft is outside)."""
    created = client.post("/v1/sessions", json=_config(profile))
    assert created.status_code == 201, created.text
    sid = created.json()["id"]
    headers = {"Authorization": f"Bearer {created.json()['token']}"}
    tracks = []
    for k in range(scans):
        y = EDGE - 10.0 - SPEED * (9 - k)
        detections = [{"z": [EDGE, y]}] if y <= EDGE else []
        body = {"sensor": "a", "time": float(k), "detections": detections}
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        found = answer.json()["tracks"]
        assert len(found) <= 1
        tracks.append(found[0] if found else {})
    return tracks


def _p(track: dict[str, Any]) -> float:
    """Φ(m / σ_n) across the +45° side, from the track's position and covariance."""
    state, covariance = np.array(track["state"]), np.array(track["covariance"])
    position, spread = state[[0, 2]], covariance[np.ix_([0, 2], [0, 2])]
    inward = np.array([math.sin(math.pi / 4), -math.cos(math.pi / 4)])
    margin = float(inward @ position)
    sigma = math.sqrt(float(inward @ spread @ inward))
    assert margin < 0.0 < margin + 4.0 * sigma  # outside, its gate (4.03 σ) reaching in
    return 0.5 * (1.0 + math.erf(margin / sigma / math.sqrt(2.0)))


def test_a_track_leaving_a_view_by_its_gate_is_missed_by_its_probability(
    client: TestClient,
) -> None:
    tracks = _run(client, None, 13)
    assert tracks[9]["status"] == "confirmed"
    for k in (10, 11):  # undetected: the answer's estimate is the prediction the scan saw
        p = _p(tracks[k])
        assert 0.05 < p < 0.5
        assert tracks[k]["status"] != "phantom"
        expected = tracks[k - 1]["score"] + math.log1p(-P_DETECT * p)
        assert tracks[k]["score"] == pytest.approx(expected, abs=1e-9)
    # a third miss in a row where no sensor sees it with p ≥ ½: more likely hidden
    assert _p(tracks[12]) < 0.5
    assert (tracks[12]["status"], tracks[12]["reason"]) == ("phantom", "blind_zone")


def test_the_paper_profile_makes_it_a_phantom_at_its_predicted_position(
    client: TestClient,
) -> None:
    tracks = _run(client, "paper", 11)
    assert tracks[9]["status"] == "confirmed"
    assert (tracks[10]["status"], tracks[10]["reason"]) == ("phantom", "blind_zone")
