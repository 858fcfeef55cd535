"""Fields of view given in the sensor's own frame (relative to its site and heading).

A radar at site (10 km, 0) with heading 90° (east) looks ±30° about its
heading out to 30 km: ``{"frame": "sensor", "heading_deg": 90, ...}`` (the
sector's axis counter-clockwise from the sensor's x axis: 90° is forward).
In the session frame that is the sector with apex (10 km, 0) and axis 0°
(east), worked out by hand here. A target that an AIS-like source reports at
(0, 5 km), behind the radar, is outside that sector: once the radar has
carried it and AIS falls silent, the radar's scans, which no longer contain
it, must not count it as a miss. Read as a session-frame sector (apex at the
origin, axis 90°: north) the same numbers would cover it, and the radar's
scans would end its fused track: the contrast is run too.
"""

from __future__ import annotations

import math
from typing import Any

import httpx
import pytest

from api_schemas.config import SessionConfig
from app.sessions.translate import fusion_config
from core.geometry import PolygonView, Sector

from .conftest import LiveServer

LAYOUT = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}
SITE = {"position": [10_000.0, 0.0], "heading_deg": 90.0}
RELATIVE = {"kind": "sector", "frame": "sensor", "heading_deg": 90.0, "half_angle_deg": 30.0}
MISREAD = {"kind": "sector", "origin": [0.0, 0.0], "heading_deg": 90.0, "half_angle_deg": 30.0}
COVARIANCE = [[100.0, 0, 0, 0], [0, 4.0, 0, 0], [0, 0, 100.0, 0], [0, 0, 0, 4.0]]


def _config(fov: dict[str, Any]) -> dict[str, Any]:
    return {
        "state": LAYOUT,
        "motion": {"model": "constant_velocity", "q": 1.0},
        "sensors": [
            {
                "id": "radar",
                "site": SITE,
                "fov": fov | {"range": [0.0, 30_000.0]},
                "measurement": {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2},
            },
            {"id": "ais"},
        ],
        "tracking": {"thresholds": {"min_points": 3}},
    }


def test_a_sensor_frame_sector_and_polygon_are_placed_at_the_site_by_hand() -> None:
    sector = fusion_config(SessionConfig.model_validate(_config(RELATIVE))).sensor("radar").fov
    assert sector == Sector((10_000.0, 0.0), 0.0, 30.0, 0.0, 30_000.0)
    polygon = {"kind": "polygon", "frame": "sensor", "vertices": [[0, 0], [1000, 0], [0, 2000]]}
    config = _config(RELATIVE)
    config["sensors"][0]["fov"] = polygon
    config["sensors"][0]["site"] = {"position": [100.0, 200.0], "heading_deg": 30.0}
    view = fusion_config(SessionConfig.model_validate(config)).sensor("radar").fov
    assert isinstance(view, PolygonView)
    # sensor x (right) is 30° clockwise from east, sensor y (forward) 30° clockwise from north
    c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    expected = [
        (100.0, 200.0),
        (100.0 + 1000 * c, 200.0 - 1000 * s),
        (100.0 + 2000 * s, 200.0 + 2000 * c),
    ]
    for got, want in zip(view.vertices, expected, strict=True):
        assert got == pytest.approx(want, abs=1e-9)


def test_frames_of_view_that_cannot_be_refused_by_field(live_server: LiveServer) -> None:
    region = {"kind": "polygon", "frame": "sensor", "vertices": [[0, 0], [1, 0], [0, 1]]}
    without_origin = {k: v for k, v in MISREAD.items() if k != "origin"} | {"range": [0, 1]}
    with httpx.Client(base_url=live_server.url) as client:
        for config, field in (
            ({"state": LAYOUT, "region": region}, "frame"),
            ({"state": LAYOUT, "sensors": [{"id": "s", "fov": without_origin}]}, "origin"),
        ):
            answer = client.post("/v1/sessions", json=config)
            assert answer.status_code == 422, answer.text
            assert any(field in str(error["loc"]) for error in answer.json()["errors"])


def _statuses_after_radar_scans(client: httpx.Client, fov: dict[str, Any]) -> list[str]:
    """AIS and the radar both report target b (behind the radar: the radar's detections are
    planted) for 4 s, then AIS stops sending and the radar's scans no longer contain b. Once
    AIS is overdue (2.5 revisits), the radar's silence about b — a track it carried — is a
    miss only if b is inside its field of view (§8.2)."""
    created = client.post("/v1/sessions", json=_config(fov))
    assert created.status_code == 201, created.text
    sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
    behind: list[str] = []
    for scan in range(12):
        time = float(scan)
        y = 5_000.0 + 10.0 * time
        if scan < 4:
            ais = {
                "sensor": "ais",
                "time": time,
                "tracks": [{"id": "b", "state": [0.0, 0.0, y, 10.0], "covariance": COVARIANCE}],
            }
            answer = client.post(f"/v1/sessions/{sid}/tracks", json=ais, headers=headers)
            assert answer.status_code == 200, answer.text
        offset = (0.0 - 10_000.0, y + 5.0)  # b from the radar's site, at time + 0.5
        detection = {
            "range": math.hypot(*offset),
            "azimuth_deg": math.degrees(math.atan2(offset[0], offset[1])) % 360.0,
        }
        body = {
            "sensor": "radar",
            "time": time + 0.5,
            "detections": [detection] if scan < 4 else [],
        }
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        tracks = answer.json()["tracks"]
        mine = [t for t in tracks if any(s["sensor"] == "ais" for s in t["sources"])]
        behind.append(mine[0]["status"] if mine else "gone")
    return behind


def test_a_target_outside_the_site_relative_sector_is_not_missed(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        relative = _statuses_after_radar_scans(client, RELATIVE)
        misread = _statuses_after_radar_scans(client, MISREAD)
    print(f"after each radar scan: relative {relative}, misread {misread}")
    assert "confirmed" in relative[:4], relative  # the radar joined AIS's track
    # b is behind the radar: its scans never count it missed; it coasts, overdue for both
    assert relative[-1] == "coasting" and "terminated" not in relative, relative
    assert "terminated" in misread, misread  # the contrast: read in the session frame
