"""One scene seen by five sources of three kinds, fused over the real API.

Three radars at three geodetic sites (range-azimuth detections), one
ADS-B-like source reporting geodetic tracks (lat, lon, east/north velocity),
one sensor reporting tracks in its own frame (site and heading). Each
target must keep one fused id from the first confirmations on, and the fused
position error must be below that of the best source alone (each source run
in its own session on the same inputs). The geodetic inputs are made with
PROJ (each radar's range and azimuth in the ENU plane at its own site), the
sensor-frame ones by hand: none with the service's own conversions.
"""

from __future__ import annotations

import math
from typing import Any

import httpx
import numpy as np

from .conftest import LiveServer
from .proj_oracle import proj_enu

ORIGIN = (43.6, 1.44, 150.0)
RADAR_SITES = [(43.75, 1.30, 200.0), (43.45, 1.30, 180.0), (43.60, 1.75, 220.0)]
OWN_SITE, OWN_HEADING = (5000.0, -3000.0), 30.0
SCANS, WARM = 20, 8
SIGMA_ADSB, SIGMA_OWN = 30.0, 40.0


def _truth(time: float) -> list[np.ndarray]:
    """Two targets [x, vx, y, vy], 6 km apart, straight lines."""
    return [
        np.array([-4000.0 + 120.0 * time, 120.0, 2000.0, 0.0]),
        np.array([3000.0, 0.0, 8000.0 - 100.0 * time, -100.0]),
    ]


def _diag(*variances: float) -> list[list[float]]:
    return np.diag(variances).tolist()


def _inputs(rng: np.random.Generator) -> list[tuple[str, str, dict[str, Any]]]:
    """Every source's input at every scan: (source, endpoint, body), in time order."""
    oracle = proj_enu(ORIGIN)
    at_sites = [proj_enu(site) for site in RADAR_SITES]  # each radar measures in its own ENU
    theta = math.radians(OWN_HEADING)
    forward, right = (
        np.array([math.sin(theta), math.cos(theta)]),
        np.array([math.cos(theta), -math.sin(theta)]),
    )
    inputs = []
    for scan in range(SCANS):
        for index, at_site in enumerate(at_sites):
            time = scan + 0.1 * index
            detections = []
            for truth in _truth(time):
                point = oracle.transform(truth[0], truth[2], 0.0, direction="INVERSE")
                offset = np.asarray(at_site.transform(*point))[:2]
                detections.append(
                    {
                        "range": float(np.hypot(*offset) + rng.normal(0, 20.0)),
                        "azimuth_deg": float(
                            math.degrees(math.atan2(offset[0], offset[1])) + rng.normal(0, 0.2)
                        ),
                    }
                )
            body = {"sensor": f"radar-{index}", "time": time, "detections": detections}
            inputs.append((f"radar-{index}", "detections", body))
        time = scan + 0.5
        tracks = []
        for number, truth in enumerate(_truth(time)):
            east, north = truth[[0, 2]] + rng.normal(0, SIGMA_ADSB, 2)
            lat, lon, _ = oracle.transform(east, north, 0.0, direction="INVERSE")
            # velocities east/north at the point: within 0.5 m/s of the origin's axes here
            velocity = truth[[1, 3]] + rng.normal(0, 2.0, 2)
            tracks.append(
                {
                    "id": f"a{number}",
                    "state": [lat, float(velocity[0]), lon, float(velocity[1])],
                    "covariance": _diag(SIGMA_ADSB**2, 4.0, SIGMA_ADSB**2, 4.0),
                }
            )
        body = {"sensor": "adsb", "time": time, "frame": "geodetic", "tracks": tracks}
        inputs.append(("adsb", "tracks", body))
        time = scan + 0.7
        tracks = []
        for number, truth in enumerate(_truth(time)):
            relative = truth[[0, 2]] - OWN_SITE + rng.normal(0, SIGMA_OWN, 2)
            velocity = truth[[1, 3]] + rng.normal(0, 2.0, 2)
            tracks.append(
                {
                    "id": f"o{number}",
                    "state": [
                        float(relative @ right),
                        float(velocity @ right),
                        float(relative @ forward),
                        float(velocity @ forward),
                    ],
                    "covariance": _diag(SIGMA_OWN**2, 4.0, SIGMA_OWN**2, 4.0),
                }
            )
        body = {"sensor": "own", "time": time, "frame": "sensor", "tracks": tracks}
        inputs.append(("own", "tracks", body))
    return inputs


def _config(sources: set[str]) -> dict[str, Any]:
    polar = {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2}
    sensors: list[dict[str, Any]] = [
        {
            "id": f"radar-{index}",
            "site": {"lat": site[0], "lon": site[1], "alt": site[2]},
            "measurement": polar,
            "p_detect": 0.99,
        }
        for index, site in enumerate(RADAR_SITES)
    ]
    sensors += [
        {"id": "adsb", "p_detect": 0.99},
        {
            "id": "own",
            "site": {"position": list(OWN_SITE), "heading_deg": OWN_HEADING},
            "p_detect": 0.99,
        },
    ]
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "origin": {"lat": ORIGIN[0], "lon": ORIGIN[1], "alt": ORIGIN[2]},
        "motion": {"model": "constant_velocity", "q": 1.0},
        "sensors": [sensor for sensor in sensors if sensor["id"] in sources],
        "tracking": {"thresholds": {"min_points": 3}},
    }


def _run(
    client: httpx.Client, sources: set[str], inputs: list[tuple[str, str, dict[str, Any]]]
) -> tuple[float, list[set[str]]]:
    """Position RMSE of the nearest confirmed fused track after warm-up, and the ids used."""
    created = client.post("/v1/sessions", json=_config(sources))
    assert created.status_code == 201, created.text
    sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
    squared: list[float] = []
    covering: list[set[str]] = [set(), set()]
    for source, endpoint, body in inputs:
        if source not in sources:
            continue
        answer = client.post(f"/v1/sessions/{sid}/{endpoint}", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        if body["time"] < WARM:
            continue
        confirmed = [t for t in answer.json()["tracks"] if t["status"] == "confirmed"]
        for target, truth in enumerate(_truth(body["time"])):
            errors = [
                float(np.linalg.norm(np.asarray(t["state"])[[0, 2]] - truth[[0, 2]]))
                for t in confirmed
            ]
            assert errors and min(errors) < 300.0, (source, body["time"], errors)
            squared.append(min(errors) ** 2)
            covering[target].add(confirmed[int(np.argmin(errors))]["id"])
    return math.sqrt(float(np.mean(squared))), covering


def test_three_radars_adsb_and_an_own_frame_sensor_fuse_to_one_id_per_target(
    live_server: LiveServer,
) -> None:
    inputs = _inputs(np.random.default_rng(5))
    everyone = {"radar-0", "radar-1", "radar-2", "adsb", "own"}
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        fused, covering = _run(client, everyone, inputs)
        assert all(len(ids) == 1 for ids in covering), covering
        assert covering[0] != covering[1]
        alone = {source: _run(client, {source}, inputs)[0] for source in sorted(everyone)}
    print(f"fused position RMSE {fused:.1f} m; each source alone: {alone}")
    assert fused < min(alone.values()), (fused, alone)
