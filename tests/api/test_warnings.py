"""Warnings for implausible but legal values, and where each site lands (README "Warnings").

Through a live server: a radar site with lat/lon swapped, an origin in
radians, σs in km and radians, detections in the blind range, an ADS-B
track with lat/lon swapped — each accepted (201/200) with a warning whose
pointer names the field, in the creation answer, ``GET`` of the session and
the step results over REST and the WebSocket ``stream``. The sites' local
positions are checked against PROJ. The same inputs sent to a server whose
rules are switched off give the same answers but for ``warnings``: a warning
changes nothing.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Iterator
from typing import Any

import httpx
import numpy as np
import pytest
from websockets.sync.client import connect

from app import plausibility
from tests.api.conftest import LiveServer, make_settings, serving

from .proj_oracle import proj_enu

ORIGIN = {"lat": 48.85, "lon": 2.35, "alt": 0.0}
SITE = {"lat": 48.85, "lon": 2.90, "alt": 60.0}  # ~40 km east of the origin
RADAR: dict[str, Any] = {
    "id": "radar",
    "site": SITE,
    "fov": {
        "kind": "sector",
        "frame": "sensor",
        "heading_deg": 90,
        "half_angle_deg": 180,
        "range": [500.0, 60_000.0],
    },
    "measurement": {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2},
}
STATE = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}
EYE4 = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def config(**changes: Any) -> dict[str, Any]:
    """A sane geodetic session (a radar and an ADS-B feed), with ``changes``."""
    body: dict[str, Any] = {
        "state": STATE,
        "origin": ORIGIN,
        "sensors": [copy.deepcopy(RADAR), {"id": "adsb"}],
    }
    body.update(changes)
    return body


def warned(answer: dict[str, Any]) -> list[tuple[str, str]]:
    return [(entry["pointer"], entry["code"]) for entry in answer["warnings"]]


def great_circle_km(lat: float, lon: float, lat0: float, lon0: float) -> float:
    """Spherical law of cosines (an independent formula from the service's haversine)."""
    p, p0, dl = math.radians(lat), math.radians(lat0), math.radians(lon - lon0)
    cosine = math.sin(p) * math.sin(p0) + math.cos(p) * math.cos(p0) * math.cos(dl)
    return 6371.0 * math.acos(max(-1.0, min(1.0, cosine)))


@pytest.fixture(scope="module")
def server() -> Iterator[LiveServer]:
    with serving(make_settings(max_body_bytes=256 * 1024)) as live:
        yield live


def create(server: LiveServer, body: dict[str, Any]) -> dict[str, Any]:
    answer = httpx.post(f"{server.url}/v1/sessions", json=body)
    assert answer.status_code == 201, answer.text
    created: dict[str, Any] = answer.json()
    return created


# ------------------------------------------------------------------ the session answer
def test_a_sane_session_shows_its_sites_from_proj_and_no_warning(server: LiveServer) -> None:
    created = create(server, config())
    assert created["warnings"] == []
    radar, adsb = created["sites"]
    east, north, up = proj_enu((ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"])).transform(
        SITE["lat"], SITE["lon"], SITE["alt"]
    )
    assert radar["sensor"] == "radar"
    np.testing.assert_allclose(radar["position"], [east, north, up], atol=1e-3)
    assert radar["distance"] == pytest.approx(math.sqrt(east**2 + north**2 + up**2), abs=1e-3)
    assert adsb == {
        "sensor": "adsb",
        "position": [0.0, 0.0, 0.0],
        "distance": 0.0,
        "heading_deg": 0.0,
    }
    headers = {"Authorization": f"Bearer {created['token']}"}
    summary = httpx.get(f"{server.url}/v1/sessions/{created['id']}", headers=headers).json()
    assert summary["sites"] == created["sites"] and summary["warnings"] == []


def test_swapped_site_lat_lon_is_named_with_where_it_would_be(server: LiveServer) -> None:
    swapped = copy.deepcopy(RADAR)
    swapped["site"] = {"lat": SITE["lon"], "lon": SITE["lat"], "alt": 60.0}
    created = create(server, config(sensors=[swapped]))
    assert warned(created) == [("#/sensors/0/site", "lat_lon_swapped")]
    message = created["warnings"][0]["message"]
    far = great_circle_km(SITE["lon"], SITE["lat"], ORIGIN["lat"], ORIGIN["lon"])
    assert far > 1000 and f"{created['sites'][0]['distance'] / 1000:.0f} km from" in message
    near = great_circle_km(SITE["lat"], SITE["lon"], ORIGIN["lat"], ORIGIN["lon"])
    assert f"it would be {near:.1f} km from the origin" in message
    # accepted as given: the site stands where the config says
    east, north, up = proj_enu((ORIGIN["lat"], ORIGIN["lon"], 0.0)).transform(
        SITE["lon"], SITE["lat"], 60.0
    )
    np.testing.assert_allclose(created["sites"][0]["position"], [east, north, up], atol=1e-2)


def test_an_origin_in_radians_is_named_at_the_origin(server: LiveServer) -> None:
    radians = {"lat": math.radians(ORIGIN["lat"]), "lon": math.radians(ORIGIN["lon"])}
    created = create(server, config(origin=radians))
    assert warned(created) == [
        ("#/sensors/0/site", "far_from_origin"),
        ("#/origin", "origin_in_radians"),
    ]
    assert created["sites"][0]["distance"] > 4_000_000  # the site lands thousands of km away
    assert (
        "origin looks like radians (as degrees: 48.8500, 2.3500)"
        in (created["warnings"][1]["message"])
    )


def test_sigmas_and_ranges_in_the_wrong_unit(server: LiveServer) -> None:
    radar = copy.deepcopy(RADAR)
    radar["measurement"] = {
        "kind": "polar",
        "sigma_range": 0.02,  # km
        "sigma_azimuth_deg": math.radians(0.2),  # radians
    }
    other = copy.deepcopy(RADAR) | {"id": "radar-2"}
    other["fov"]["range"] = [0.5, 60.0]  # km
    other["measurement"]["sigma_azimuth_deg"] = 17.0  # milliradians
    created = create(server, config(sensors=[radar, other]))
    assert warned(created) == [
        ("#/sensors/0/measurement/sigma_range", "sigma_range_small"),
        ("#/sensors/0/measurement/sigma_azimuth_deg", "sigma_angle_small"),
        ("#/sensors/1/measurement/sigma_azimuth_deg", "sigma_angle_large"),
        ("#/sensors/1/fov/range", "range_in_km"),
    ]
    assert "(0.00349066 rad = 0.2°)" in created["warnings"][1]["message"]


def test_sites_far_apart_without_an_origin(server: LiveServer) -> None:
    sensors = [
        {"id": "a", "site": {"position": [0.0, 0.0]}},
        {"id": "b", "site": {"position": [1.2e6, 0.0]}},
    ]
    created = create(server, {"state": STATE, "sensors": sensors})
    assert warned(created) == [("#/sensors/0/site", "far_apart"), ("#/sensors/1/site", "far_apart")]
    assert [site["distance"] for site in created["sites"]] == [0.0, 1.2e6]


# ------------------------------------------------------------------ step results
SCAN = {
    "sensor": "radar",
    "time": 1.0,
    "detections": [
        {"range": 20_000.0, "azimuth_deg": 30.0},
        {"range": 120.0, "azimuth_deg": 200.0},  # inside the 500 m blind range
        {"range": 35_000.0, "azimuth_deg": 300.0},
    ],
}
ADSB = {
    "sensor": "adsb",
    "time": 1.5,
    "frame": "geodetic",
    "tracks": [
        {"id": "ok", "state": [48.9, 0.0, 2.4, 0.0], "covariance": EYE4},
        {"id": "swapped", "state": [2.4, 0.0, 48.9, 0.0], "covariance": EYE4},
    ],
}
RADIANS_SCAN = {
    "sensor": "radar",
    "time": 2.0,
    "detections": [{"range": 20_000.0 + 1000 * i, "azimuth_deg": 0.5 * i} for i in range(5)],
}


def run_inputs(server: LiveServer) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """One session, the three inputs (REST, REST as GeoJSON, WebSocket): the answers."""
    created = create(server, config())
    sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
    with httpx.Client(base_url=server.url, headers=headers) as client:
        scan = client.post(f"/v1/sessions/{sid}/detections", json=SCAN)
        adsb = client.post(f"/v1/sessions/{sid}/tracks", params={"format": "geojson"}, json=ADSB)
        assert scan.status_code == adsb.status_code == 200, (scan.text, adsb.text)
    ws = server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
    with connect(ws, additional_headers=[("Authorization", headers["Authorization"])]) as stream:
        assert json.loads(stream.recv(timeout=30))["type"] == "ack"
        stream.send(json.dumps({"type": "detections", "ref": "r", **RADIANS_SCAN}))
        streamed = json.loads(stream.recv(timeout=30))
    assert streamed["type"] == "result" and streamed["ref"] == "r"
    with httpx.Client(base_url=server.url, headers=headers) as client:
        picture = client.get(f"/v1/sessions/{sid}/tracks").json()
    return picture, [scan.json(), adsb.json(), streamed["result"]]


def test_step_results_carry_their_inputs_warnings(server: LiveServer) -> None:
    _, (scan, adsb, streamed) = run_inputs(server)
    assert warned(scan) == [("#/detections/1/range", "blind_range")]
    assert "range 120 m is inside the radar's blind range" in scan["warnings"][0]["message"]
    assert warned(adsb) == [("#/tracks/1/state", "lat_lon_swapped")]
    near = great_circle_km(48.9, 2.4, ORIGIN["lat"], ORIGIN["lon"])
    assert f"it would be {near:.1f} km from the origin" in adsb["warnings"][0]["message"]
    assert warned(streamed) == [("#/detections", "azimuth_radians")]


def test_warnings_change_nothing(server: LiveServer, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every answer with the rules on equals the answer with no rule at all, but for
    ``warnings``; and the fused picture after them is the same."""
    picture, answers = run_inputs(server)
    assert all(answer["warnings"] for answer in answers)
    monkeypatch.setattr(plausibility, "CONFIG_RULES", [])
    monkeypatch.setattr(plausibility, "INPUT_RULES", {})
    bare_picture, bare = run_inputs(server)
    assert all(answer["warnings"] == [] for answer in bare)
    strip = [{k: v for k, v in answer.items() if k != "warnings"} for answer in answers]
    assert strip == [{k: v for k, v in answer.items() if k != "warnings"} for answer in bare]
    assert picture == bare_picture and picture["tracks"]


# ------------------------------------------------------------------ the rules themselves
def test_many_warnings_are_capped_and_counted() -> None:
    from api_schemas.config import SessionConfig
    from api_schemas.reports import DetectionReport

    session = SessionConfig.model_validate(config())
    report = DetectionReport.model_validate(
        {
            "sensor": "radar",
            "time": 1.0,
            "detections": [{"range": 100.0 + i, "azimuth_deg": 90.0} for i in range(30)],
        }
    )
    found = plausibility.input_warnings("detections", report, session)
    assert len(found) == plausibility.MAX_WARNINGS + 1
    assert found[-1].code == "more_warnings" and found[-1].message == "and 10 more warnings"


def test_every_rule_code_is_documented() -> None:
    with open("README.md", encoding="utf-8") as file:
        readme = file.read()
    section = readme[readme.index("## Warnings") :]
    section = section[: section.index("\n## ", 1)]
    for code in plausibility.rule_codes():
        assert f"`{code}`" in section, code


def config_codes(body: dict[str, Any]) -> list[tuple[str, str]]:
    from api_schemas.config import SessionConfig

    found = plausibility.config_warnings(SessionConfig.model_validate(body))
    return [(entry.pointer, entry.code) for entry in found]


def test_an_origin_with_lat_lon_swapped_is_named_at_the_origin() -> None:
    from api_schemas.config import SessionConfig

    receiver = {"id": "adsb", "site": {"lat": 48.5, "lon": 2.0}}
    body = config(origin={"lat": ORIGIN["lon"], "lon": ORIGIN["lat"]})
    body["sensors"][1] = receiver
    found = plausibility.config_warnings(SessionConfig.model_validate(body))
    # each site alone could be the swapped one; both at once point at the origin
    assert [(w.pointer, w.code) for w in found] == [
        ("#/sensors/0/site", "lat_lon_swapped"),
        ("#/sensors/1/site", "lat_lon_swapped"),
        ("#/origin", "origin_lat_lon_swapped"),
    ]
    assert all("(or the origin's)" in w.message for w in found[:2])
    near = [
        great_circle_km(lat, lon, ORIGIN["lat"], ORIGIN["lon"])
        for lat, lon in ((48.85, 2.9), (48.5, 2.0))
    ]
    assert f"they would be {near[0]:.1f} km, {near[1]:.1f} km from it" in found[2].message


def test_a_site_in_radians_and_far_positions() -> None:
    radar = copy.deepcopy(RADAR)
    radar["site"] = {"lat": math.radians(SITE["lat"]), "lon": math.radians(SITE["lon"])}
    sited = {"id": "far", "site": {"position": [3.0e6, 0.0]}}
    apex = {
        "id": "apex",
        "fov": {
            "kind": "sector",
            "origin": [0.0, 2.0e6],
            "heading_deg": 0,
            "half_angle_deg": 30,
            "range": [0, 1000],
        },
    }
    assert config_codes(config(sensors=[radar, sited, apex])) == [
        ("#/sensors/0/site", "in_radians"),
        ("#/sensors/1/site/position", "far_from_origin"),
        ("#/sensors/2/fov/origin", "far_from_origin"),
    ]


def test_track_and_detection_rules_without_a_server() -> None:
    from api_schemas.config import SessionConfig
    from api_schemas.reports import DetectionReport, TrackReport

    session = SessionConfig.model_validate(config())
    far = TrackReport.model_validate(
        {
            "sensor": "adsb",
            "time": 1.0,
            "tracks": [
                {"id": "near", "state": [1e5, 0, 1e5, 0], "covariance": EYE4},
                {"id": "far", "state": [1e6, 0, 1e5, 0], "covariance": EYE4},  # 1005 km
            ],
        }
    )
    assert [(w.pointer, w.code) for w in plausibility.input_warnings("tracks", far, session)] == [
        ("#/tracks/1/state", "far_from_origin")
    ]
    km_scan = DetectionReport.model_validate(
        {"sensor": "radar", "time": 1.0, "detections": [{"range": 12.0, "azimuth_deg": 40.0}]}
    )
    found = plausibility.input_warnings("detections", km_scan, session)
    assert [(w.pointer, w.code) for w in found] == [
        ("#/detections", "range_in_km"),  # 12 m ≤ 60 000 m / 1000
        ("#/detections/0/range", "blind_range"),
        ("#/detections/0/range", "range_in_km"),  # nearer than sigma_range 20 m
    ]
    camera = copy.deepcopy(RADAR) | {"id": "camera", "measurement": {"r": [[25, 0], [0, 25]]}}
    with_camera = SessionConfig.model_validate(config(sensors=[camera]))
    east, north = plausibility.site_placements(with_camera)[0].position[:2]
    near = DetectionReport.model_validate(
        {
            "sensor": "camera",
            "time": 1.0,
            "detections": [{"z": [east + 30.0, north + 40.0]}, {"z": [east + 600.0, north]}],
        }
    )
    found = plausibility.input_warnings("detections", near, with_camera)
    assert [(w.pointer, w.code) for w in found] == [("#/detections/0/z", "blind_range")]
    assert "50 m from its sensor's field-of-view apex" in found[0].message
    # without an origin nothing is far: a session frame may be UTM
    plain = SessionConfig.model_validate({"state": STATE})
    assert plausibility.input_warnings("tracks", far, plain) == []


def test_large_range_and_range_rate_sigmas_in_the_wrong_unit(server: LiveServer) -> None:
    """sigma_range 2000 (20 m in cm) and sigma_range_rate 150 (1.5 m/s in cm/s) are legal and
    warned about; sigma_range_rate 0.0015 (1.5 m/s in km/s) too; 20 m and 1.5 m/s are not."""
    radar = copy.deepcopy(RADAR)
    radar["measurement"] = {
        "kind": "polar",
        "sigma_range": 2000.0,  # cm
        "sigma_azimuth_deg": 0.2,
        "sigma_range_rate": 150.0,  # cm/s
    }
    del radar["fov"]  # its reach in σ_range would be flagged too (range_in_km)
    other = copy.deepcopy(RADAR) | {"id": "radar-2"}
    other["measurement"] = {
        "kind": "polar",
        "sigma_range": 20.0,
        "sigma_azimuth_deg": 0.2,
        "sigma_range_rate": 0.0015,  # km/s
    }
    plain = copy.deepcopy(RADAR) | {"id": "radar-3"}
    plain["measurement"] = {
        "kind": "polar",
        "sigma_range": 20.0,
        "sigma_azimuth_deg": 0.2,
        "sigma_range_rate": 1.5,
    }
    created = create(server, config(sensors=[radar, other, plain]))
    assert warned(created) == [
        ("#/sensors/0/measurement/sigma_range", "sigma_range_large"),
        ("#/sensors/0/measurement/sigma_range_rate", "sigma_range_rate_large"),
        ("#/sensors/1/measurement/sigma_range_rate", "sigma_range_rate_small"),
    ]
    assert "(150 cm/s = 1.5 m/s)" in created["warnings"][1]["message"]
    assert "(0.0015 km/s = 1.5 m/s)" in created["warnings"][2]["message"]
