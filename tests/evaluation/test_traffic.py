"""The real-traffic scene of issue 22 (evaluation/traffic.py), on reduced data."""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import httpx
import numpy as np
import pymap3d
from pyproj import Transformer

from evaluation.service import live_service
from evaluation.traffic import (
    EARTH_RADIUS,
    ORIGIN,
    Radar,
    assess,
    horizon_visible,
    load_flights,
    run_service,
    simulate,
)


def test_the_truth_is_the_recorded_flights_in_the_sessions_enu_frame() -> None:
    flights = load_flights()
    assert len(flights) == 20
    assert {f.kind for f in flights} == {"airliner", "business jet", "private"}
    # PROJ as the oracle: geodetic → ECEF, then the ENU rotation at the origin by hand
    to_ecef = Transformer.from_crs("EPSG:4979", "EPSG:4978", always_xy=True)
    lat0, lon0, h0 = ORIGIN
    origin = np.array(to_ecef.transform(lon0, lat0, h0))
    phi, lam = math.radians(lat0), math.radians(lon0)
    rotation = np.array(
        [
            [-math.sin(lam), math.cos(lam), 0.0],
            [-math.sin(phi) * math.cos(lam), -math.sin(phi) * math.sin(lam), math.cos(phi)],
            [math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam), math.sin(phi)],
        ]
    )
    for flight in flights[::7]:
        lat, lon, height = flight.geodetic[::300].T
        ecef = np.stack(to_ecef.transform(lon, lat, height), axis=-1)
        np.testing.assert_allclose((ecef - origin) @ rotation.T, flight.enu[::300], atol=1e-3)


def test_a_glitch_is_dropped(tmp_path: Path) -> None:
    rows = ["t,icao24,callsign,lat,lon,alt_ft"]
    for k in range(60):  # 100 m/s north, one record 30 km off at t = 30
        lat = 48.9 + 100.0 * k / 111_200.0 + (0.27 if k == 30 else 0.0)
        rows.append(f"{k},abc123,AFR1,{lat:.6f},2.45,10000")
    path = tmp_path / "glitch.csv.gz"
    path.write_bytes(gzip.compress("\n".join(rows).encode()))
    (flight,) = load_flights(path)
    assert np.max(np.abs(np.diff(flight.enu[:, 1]) - 100.0)) < 1.0
    assert flight.kind == "airliner"


def test_the_radar_horizon_has_a_four_thirds_earth() -> None:
    radar = Radar("r", 48.0, 2.0, 150.0, 50.0, 0.1, 0.2, 4.0, 0.0, range_max=200_000.0)
    k = 2.0 * 4.0 / 3.0 * EARTH_RADIUS
    for height, visible_to in (
        (0.0, math.sqrt(k * 150.0)),
        (500.0, math.sqrt(k * 150.0) + math.sqrt(k * 500.0)),
    ):
        for distance, seen in ((visible_to - 2000.0, True), (visible_to + 2000.0, False)):
            # due east of the site, at that height above the ellipsoid
            lat, lon, _ = pymap3d.aer2geodetic(90.0, 0.0, distance, radar.lat, radar.lon, 0.0)
            point = np.array([[float(lat), float(lon), height]])
            assert bool(horizon_visible(radar, point)[0]) is seen, (height, distance)


def test_a_reduced_scene_through_the_service() -> None:
    """Two minutes, the aircraft flying from the start: ADS-B given its id alone, defaults
    otherwise. The
    equipped aircraft are held as soon as their first lists arrive, and no fused track
    changes status more than once a minute."""
    flights = [f for f in load_flights() if f.present(0.0) and f.present(120.0)]
    scene = simulate(seed=3, duration=120.0, flights=flights)
    with live_service() as url, httpx.Client(base_url=url, timeout=60) as client:
        run = run_service(client, scene)
    score = assess(scene, run)
    assert score.flickering_tracks == 0
    equipped = [f.callsign for f in flights if f.callsign in scene.equipped]
    assert equipped and all(score.coverage[c] >= 0.8 for c in equipped)
    assert score.rmse(equipped) < 100.0  # ADS-B: 15 m horizontally, 10 m vertically
