"""Over the real API: session origin, sensor sites, polar detections, tracks in other frames.

Each bad input is a 422 naming its field and leaves the session as it was
(picture and event log). The accepted conversions are checked against PROJ
(geodetic ↔ ENU) and against positions worked by hand (a sensor's frame,
range-azimuth).
"""

from __future__ import annotations

import json
import math
from typing import Any

import httpx
import numpy as np
import pymap3d
import pytest
from websockets.sync.client import connect

from .conftest import LiveServer
from .proj_oracle import proj_enu

ORIGIN = {"lat": 48.85, "lon": 2.35, "alt": 100.0}
LAYOUT_2D = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}
LAYOUT_3D = {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]}
COVARIANCE_4 = (np.diag([25.0, 1.0, 25.0, 1.0])).tolist()
COVARIANCE_6 = (np.diag([25.0, 1.0, 25.0, 1.0, 25.0, 1.0])).tolist()
POLAR = {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2}


def _session(client: httpx.Client, config: dict[str, Any]) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    return created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}


def _locations(answer: httpx.Response) -> list[str]:
    assert answer.status_code == 422, answer.text
    assert answer.headers["content-type"].startswith("application/problem+json")
    return [str(error["loc"]) for error in answer.json()["errors"]]


def _state_of(client: httpx.Client, sid: str, headers: dict[str, str]) -> tuple[Any, Any]:
    picture = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
    log = client.get(f"/v1/sessions/{sid}/events", headers=headers).json()
    return picture, log["last_seq"]


@pytest.mark.parametrize(
    ("config", "field"),
    [
        (  # a geodetic site without an origin
            {
                "state": LAYOUT_2D,
                "sensors": [{"id": "r", "site": {"lat": 48.9, "lon": 2.3, "alt": 0.0}}],
            },
            "site",
        ),
        ({"state": LAYOUT_2D, "origin": {**ORIGIN, "lat": 91.0}}, "lat"),
        ({"state": LAYOUT_2D, "origin": {**ORIGIN, "lon": -180.5}}, "lon"),
        (  # a polar sensor without its azimuth σ
            {
                "state": LAYOUT_2D,
                "sensors": [{"id": "r", "measurement": {"kind": "polar", "sigma_range": 20.0}}],
            },
            "sigma_azimuth_deg",
        ),
        (  # a polar sensor of a 3-D session without its elevation σ
            {"state": LAYOUT_3D, "sensors": [{"id": "r", "measurement": POLAR}]},
            "sigma_elevation_deg",
        ),
    ],
)
def test_bad_configs_name_the_field(
    live_server: LiveServer, config: dict[str, Any], field: str
) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        locations = _locations(client.post("/v1/sessions", json=config))
        assert any(field in location for location in locations), locations


def test_bad_inputs_are_refused_by_field_and_change_nothing(live_server: LiveServer) -> None:
    plain = {
        "state": LAYOUT_2D,
        "sensors": [{"id": "cart", "measurement": {"r": [[25.0, 0], [0, 25.0]]}}],
    }
    solid = {
        "state": LAYOUT_3D,
        "origin": ORIGIN,
        "sensors": [{"id": "r3", "measurement": {**POLAR, "sigma_elevation_deg": 0.3}}],
    }
    with httpx.Client(base_url=live_server.url) as client:
        for config, sensor, kind, body, field in [
            (
                plain,
                "cart",
                "detections",
                {"detections": [{"range": 1e3, "azimuth_deg": 5}]},
                "range",
            ),
            (  # a range of 0: the converted covariance would be singular
                {**plain, "sensors": [{"id": "cart", "measurement": POLAR}]},
                "cart",
                "detections",
                {"detections": [{"range": 0.0, "azimuth_deg": 5}]},
                "range",
            ),
            (
                solid,
                "r3",
                "detections",
                {"detections": [{"range": 1e3, "azimuth_deg": 5}]},
                "elevation_deg",
            ),
            (
                plain,
                "cart",
                "tracks",
                {
                    "frame": "geodetic",
                    "tracks": [{"id": "a", "state": [48.9, 0, 2.3, 0], "covariance": COVARIANCE_4}],
                },
                "frame",
            ),
            (
                {**plain, "origin": ORIGIN},
                "cart",
                "tracks",
                {
                    "frame": "geodetic",
                    "tracks": [{"id": "a", "state": [95.0, 0, 2.3, 0], "covariance": COVARIANCE_4}],
                },
                "'state', 0",
            ),
        ]:
            sid, headers = _session(client, config)
            url = f"/v1/sessions/{sid}/{kind}"
            before = _state_of(client, sid, headers)
            answer = client.post(url, json={"sensor": sensor, "time": 1.0, **body}, headers=headers)
            locations = _locations(answer)
            assert any(field in location for location in locations), (field, locations)
            assert _state_of(client, sid, headers) == before


def test_reports_in_sensor_and_geodetic_frames_land_where_proj_says(
    live_server: LiveServer,
) -> None:
    """A track 300 m ahead of a sensor at (1000, 2000) heading 90° (east) is at (1300, 2000);
    a geodetic track (lat, lon, alt) is where PROJ puts it, its east/north velocity turned by
    the angle between the two tangent planes; both read back in lat/lon and as GeoJSON."""
    config = {
        "state": LAYOUT_3D,
        "origin": ORIGIN,
        "motion": {"model": "constant_velocity", "q": 0.1},
        "sensors": [
            {"id": "own", "site": {"position": [1000.0, 2000.0, 0.0], "heading_deg": 90.0}},
            {"id": "adsb"},
        ],
    }
    point = (48.95, 2.55, 9000.0)  # ~15 km east, ~11 km north of the origin
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = _session(client, config)
        own = {
            "sensor": "own",
            "time": 1.0,
            "frame": "sensor",
            "tracks": [
                {"id": "t", "state": [0.0, 0.0, 300.0, 10.0, 50.0, 0.0], "covariance": COVARIANCE_6}
            ],
        }
        answer = client.post(f"/v1/sessions/{sid}/tracks", json=own, headers=headers)
        assert answer.status_code == 200, answer.text
        (track,) = answer.json()["tracks"]
        np.testing.assert_allclose(
            track["state"], [1300.0, 10.0, 2000.0, 0.0, 50.0, 0.0], atol=1e-9
        )

        adsb = {
            "sensor": "adsb",
            "time": 2.0,
            "frame": "geodetic",
            "tracks": [
                {
                    "id": "a",
                    "state": [point[0], 0.0, point[1], 200.0, point[2], 0.0],
                    "covariance": COVARIANCE_6,
                }
            ],
        }
        answer = client.post(
            f"/v1/sessions/{sid}/tracks?frame=geodetic", json=adsb, headers=headers
        )
        assert answer.status_code == 200, answer.text
        fused = {t["sources"][0]["sensor"]: t for t in answer.json()["tracks"]}["adsb"]
        oracle = proj_enu((ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"]))
        east, north, up = oracle.transform(*point)
        np.testing.assert_allclose(
            np.asarray(fused["state"])[[0, 2, 4]], [east, north, up], atol=1e-3
        )
        # 200 m/s north at the point, seen from the origin's plane: the meridians converge
        tip = oracle.transform(point[0] + 1e-4, point[1], point[2])
        expected = 200.0 * (
            np.subtract(tip, (east, north, up))
            / np.linalg.norm(np.subtract(tip, (east, north, up)))
        )
        np.testing.assert_allclose(np.asarray(fused["state"])[[1, 3, 5]], expected, atol=0.02)
        assert abs(fused["state"][1]) > 0.3  # the turn is there (≈ 200 m/s · 0.15°)
        geodetic = fused["geodetic"]
        np.testing.assert_allclose(
            [geodetic["lat"], geodetic["lon"], geodetic["alt"]], point, atol=1e-7 * 1e3
        )

        picture = client.get(f"/v1/sessions/{sid}/tracks?frame=geodetic", headers=headers).json()
        by_sensor = {t["sources"][0]["sensor"]: t for t in picture["tracks"]}
        back = oracle.transform(1300.0 + 10.0, 2000.0, 50.0, direction="INVERSE")  # at t = 2
        assert math.isclose(by_sensor["own"]["geodetic"]["lat"], back[0], abs_tol=1e-8)
        assert math.isclose(by_sensor["own"]["geodetic"]["lon"], back[1], abs_tol=1e-8)

        geojson = client.get(f"/v1/sessions/{sid}/tracks?format=geojson", headers=headers)
        assert geojson.status_code == 200, geojson.text
        assert geojson.headers["content-type"].startswith("application/geo+json")
        collection = geojson.json()
        assert collection["type"] == "FeatureCollection"
        features = {f["id"]: f for f in collection["features"]}
        assert features[fused["id"]]["geometry"]["type"] == "Point"
        np.testing.assert_allclose(
            features[fused["id"]]["geometry"]["coordinates"],
            [point[1], point[0], point[2]],
            atol=1e-6,
        )
        velocity = features[fused["id"]]["properties"]["velocity_enu"]
        np.testing.assert_allclose(velocity, [0.0, 200.0, 0.0], atol=0.05)


def test_geodetic_reads_need_an_origin(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = _session(client, {"state": LAYOUT_2D})
        for query, field in (("frame=geodetic", "frame"), ("format=geojson", "format")):
            answer = client.get(f"/v1/sessions/{sid}/tracks?{query}", headers=headers)
            locations = _locations(answer)
            assert any(field in location for location in locations)
            assert "origin" in answer.text
        answer = client.get(f"/v1/sessions/{sid}/tracks/F1?frame=geodetic", headers=headers)
        assert any("frame" in location for location in _locations(answer))
        assert "origin" in answer.text


def test_one_track_read_in_geodetic(live_server: LiveServer) -> None:
    """``GET …/tracks/{tid}?frame=geodetic``: the track's WGS84 position is PROJ's, and so
    is each history point's (pymap3d's too)."""
    config = {"state": LAYOUT_2D, "origin": ORIGIN, "sensors": [{"id": "s"}]}
    state = [12_000.0, 5.0, -7_000.0, 0.0]
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = _session(client, config)
        report = {
            "sensor": "s",
            "time": 1.0,
            "tracks": [{"id": "t", "state": state, "covariance": COVARIANCE_4}],
        }
        answer = client.post(f"/v1/sessions/{sid}/tracks", json=report, headers=headers)
        assert answer.status_code == 200, answer.text
        (fused,) = answer.json()["tracks"]
        detail = client.get(
            f"/v1/sessions/{sid}/tracks/{fused['id']}?frame=geodetic", headers=headers
        )
        assert detail.status_code == 200, detail.text
        track = detail.json()["track"]
        assert track["state"] == fused["state"]  # the session frame kept
        np.testing.assert_allclose(track["state"], state, atol=1.0)  # near the report's
        east, north = track["state"][0], track["state"][2]
        oracle = proj_enu((ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"]))
        lat, lon, alt = oracle.transform(east, north, 0.0, direction="INVERSE")
        geodetic = track["geodetic"]
        np.testing.assert_allclose([geodetic["lat"], geodetic["lon"]], [lat, lon], atol=1e-8)
        assert math.isclose(geodetic["alt"], alt, abs_tol=1e-3)  # ≈ 100 m + 15 m of the curve
        for time in (2.0, 3.0):
            moved = [state[0] + 5.0 * (time - 1.0), 5.0, state[2], 0.0]
            report = {
                "sensor": "s",
                "time": time,
                "tracks": [{"id": "t", "state": moved, "covariance": COVARIANCE_4}],
            }
            answer = client.post(f"/v1/sessions/{sid}/tracks", json=report, headers=headers)
            assert answer.status_code == 200, answer.text
        detail = client.get(
            f"/v1/sessions/{sid}/tracks/{fused['id']}?frame=geodetic", headers=headers
        )
        history = detail.json()["history"]
        assert len(history) == 3, history
        for point in history:
            east, north = point["state"][0], point["state"][2]
            lat, lon, alt = oracle.transform(east, north, 0.0, direction="INVERSE")
            other = pymap3d.enu2geodetic(
                east, north, 0.0, ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"]
            )
            geodetic = point["geodetic"]
            np.testing.assert_allclose([geodetic["lat"], geodetic["lon"]], [lat, lon], atol=1e-8)
            np.testing.assert_allclose([geodetic["lat"], geodetic["lon"]], other[:2], atol=1e-8)
            assert math.isclose(geodetic["alt"], alt, abs_tol=1e-3)
        plain = client.get(f"/v1/sessions/{sid}/tracks/{fused['id']}", headers=headers).json()
        assert plain["track"].get("geodetic") is None
        assert all(point.get("geodetic") is None for point in plain["history"])


def test_polar_detections_are_converted_at_the_geodetic_site(live_server: LiveServer) -> None:
    """A radar at a geodetic site: a target on a straight line, seen in range and azimuth,
    is confirmed where the truth is (the site from PROJ, the polar map worked by hand)."""
    site = (48.80, 2.30, 50.0)
    config = {
        "state": LAYOUT_2D,
        "origin": ORIGIN,
        "motion": {"model": "constant_velocity", "q": 1.0},
        "sensors": [
            {
                "id": "radar",
                "site": {"lat": site[0], "lon": site[1], "alt": site[2]},
                "measurement": POLAR,
            }
        ],
        "tracking": {"thresholds": {"min_points": 3}},
    }
    oracle = proj_enu((ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"]))
    site_east, site_north, _ = oracle.transform(*site)
    rng = np.random.default_rng(3)
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = _session(client, config)
        for scan in range(8):
            truth = np.array([site_east + 8000.0 + 50.0 * scan, site_north + 6000.0])
            offset = truth - (site_east, site_north)
            rho = float(np.hypot(*offset)) + rng.normal(0, 20.0)
            azimuth = math.degrees(math.atan2(offset[0], offset[1])) + rng.normal(0, 0.2)
            body = {
                "sensor": "radar",
                "time": float(scan),
                "detections": [{"range": rho, "azimuth_deg": azimuth, "range_rate": 1.0}],
            }
            answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
            assert answer.status_code == 200, answer.text
        tracks = answer.json()["tracks"]
        assert len(tracks) == 1
        state = np.asarray(tracks[0]["state"])
        assert np.linalg.norm(state[[0, 2]] - truth) < 60.0
        assert abs(state[1] - 50.0) < 15.0 and abs(state[3]) < 15.0


def test_stream_messages_keep_their_frame(live_server: LiveServer) -> None:
    """On the ``stream`` channel too, a track 300 m ahead of a sensor at (1000, 2000) heading
    90° (east) is at (1300, 2000); the event log keeps the message's ``frame``."""
    config = {
        "state": LAYOUT_3D,
        "sensors": [
            {"id": "own", "site": {"position": [1000.0, 2000.0, 0.0], "heading_deg": 90.0}}
        ],
    }
    message = {
        "type": "tracks",
        "ref": "ahead",
        "sensor": "own",
        "time": 1.0,
        "frame": "sensor",
        "tracks": [
            {"id": "t", "state": [0.0, 0.0, 300.0, 10.0, 50.0, 0.0], "covariance": COVARIANCE_6}
        ],
    }
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = _session(client, config)
        stream_url = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
        with connect(stream_url, additional_headers=headers, open_timeout=10) as stream:
            assert json.loads(stream.recv(timeout=10))["type"] == "ack"
            stream.send(json.dumps(message))
            answer = json.loads(stream.recv(timeout=10))
        assert answer["type"] == "result" and answer["ref"] == "ahead", answer
        (track,) = answer["result"]["tracks"]
        np.testing.assert_allclose(
            track["state"], [1300.0, 10.0, 2000.0, 0.0, 50.0, 0.0], atol=1e-9
        )
        (event,) = client.get(f"/v1/sessions/{sid}/events", headers=headers).json()["events"]
        assert event["report"]["frame"] == "sensor"
