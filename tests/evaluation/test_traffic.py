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
    EXTRACT,
    FEET,
    MAX_GAP,
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


def test_an_altitude_jump_that_persists_ends_the_flight(tmp_path: Path) -> None:
    """At 100 m/s north and 3000 ft, the altitude jumps to 18 000 ft at 50 s and stays: the
    first record within 6000 ft/min (30.48 m/s) of the last good one (49 s) is the one
    150 s later (15 000 ft = 4572 m = 30.48 m/s × 150 s), past the 120 s bridged. At 60 m/s
    the record of 126 s (4572 m ≤ 60 × 77 m) was kept and the truth climbed at 59 m/s."""
    rows = ["t,icao24,callsign,lat,lon,alt_ft"]
    for k in range(300):
        lat = 48.9 + 100.0 * k / 111_200.0
        rows.append(f"{k},abc123,AFR1,{lat:.6f},2.45,{3000 if k < 50 else 18000}")
    path = tmp_path / "jump.csv.gz"
    path.write_bytes(gzip.compress("\n".join(rows).encode()))
    (flight,) = load_flights(path)
    assert flight.times[-1] == 49.0
    assert np.max(np.abs(flight.velocity[:, 2])) < 1.0  # ENU up bends with the Earth: 0.2


def test_ryr43zu_ends_where_its_records_stop_being_an_aircrafts() -> None:
    """The extract by brute force: RYR43ZU's latitude and longitude stop changing at 898 s
    (750 ft, on final to Beauvais), its altitude jumps to 25 375 ft at 918 s; the first
    record after 917 s within 6000 ft/min of 750 ft comes more than MAX_GAP later, so the
    truth ends at 917 s. No aircraft of the truth climbs or descends faster than 20 m/s
    (the fastest airline climbs; a business jet's 19 m/s is the scene's fastest)."""
    import csv
    import io

    text = gzip.decompress(EXTRACT.read_bytes()).decode()
    rows = [r for r in csv.DictReader(io.StringIO(text)) if r["callsign"] == "RYR43ZU"]
    records = {int(r["t"]): (r["lat"], r["lon"], int(r["alt_ft"])) for r in rows}
    assert all(records[t][:2] == records[898][:2] for t in range(898, 1202) if t in records)
    assert records[917][2] == 750 and records[918][2] == 25_375
    after = [t for t in sorted(records) if t > 917]
    within = [t for t in after if abs(records[t][2] - 750) <= 100.0 * (t - 917)]  # ft/s
    assert within[0] == 1109 and within[0] - 917 > MAX_GAP
    # 60 m/s (196.85 ft/s) let the record of 1032 s in, 115 s after
    assert next(t for t in after if abs(records[t][2] - 750) * FEET <= 60.0 * (t - 917)) == 1032
    flights = {f.callsign: f for f in load_flights()}
    assert flights["RYR43ZU"].times[-1] == 917.0
    for flight in flights.values():
        assert np.max(np.abs(flight.velocity[:, 2])) < 20.0, flight.callsign


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
