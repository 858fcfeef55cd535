"""GeoJSON and geodetic output of fused tracks, checked with PROJ, numpy and by hand."""

from __future__ import annotations

import math
from typing import Any

import httpx
import numpy as np
import pytest
from numpy.testing import assert_allclose
from pyproj import Geod

from app.geo.geodesy import LocalFrame
from app.geo.geojson import GeodeticOutput, feature_collection, with_geodetic
from tests.api.conftest import LiveServer
from tests.api.proj_oracle import proj_enu

ORIGIN = (52.0, 4.4, 12.0)
WGS84 = Geod(ellps="WGS84")


def track(
    track_id: str,
    state: list[float],
    covariance: list[list[float]] | None = None,
    sources: tuple[str, ...] = ("s",),
) -> dict[str, Any]:
    dim = len(state)
    return {
        "id": track_id,
        "status": "confirmed",
        "state": state,
        "covariance": np.eye(dim).tolist() if covariance is None else covariance,
        "sources": [{"sensor": sensor, "track": f"{sensor}-1", "time": 0.0} for sensor in sources],
        "classification": {
            "decision": None,
            "decision_state": "tied",
            "pignistic": {"a": 0.5, "b": 0.5},
        },
    }


def ellipse_at_origin(block: list[list[float]]) -> dict[str, Any]:
    """The feature's ellipse for a 2-D track at the origin whose position covariance is
    ``block`` (east, north): there the session's axes are the local ones."""
    covariance = np.zeros((4, 4))
    covariance[np.ix_([0, 2], [0, 2])] = block
    covariance[1, 1] = covariance[3, 3] = 1.0
    collection = feature_collection(
        [track("F", [0.0, 0.0, 0.0, 0.0], covariance.tolist())],
        GeodeticOutput(LocalFrame(*ORIGIN), (0, 2), (1, 3)),
    )
    ellipse = collection["features"][0]["properties"]["position_ellipse"]
    assert isinstance(ellipse, dict)
    return ellipse


@pytest.mark.parametrize(
    ("block", "major", "minor", "bearing"),
    [
        # by hand: σ_east 20 m, σ_north 10 m, uncorrelated → 2-σ axes 40 m (east) and 20 m
        ([[400.0, 0.0], [0.0, 100.0]], 40.0, 20.0, 90.0),
        ([[100.0, 0.0], [0.0, 400.0]], 40.0, 20.0, 0.0),
        # [[250, 150], [150, 250]]: eigenvalues 400 along (1, 1)/√2 (north-east), 100 across
        ([[250.0, 150.0], [150.0, 250.0]], 40.0, 20.0, 45.0),
        ([[250.0, -150.0], [-150.0, 250.0]], 40.0, 20.0, 135.0),  # south-east = north-west axis
        # a circle: no axis to orient, 0 by convention
        ([[225.0, 0.0], [0.0, 225.0]], 30.0, 30.0, 0.0),
    ],
)
def test_the_ellipse_of_worked_examples(
    block: list[list[float]], major: float, minor: float, bearing: float
) -> None:
    ellipse = ellipse_at_origin(block)
    assert ellipse["sigma"] == 2.0
    assert ellipse["semi_major_m"] == pytest.approx(major, rel=1e-12)
    assert ellipse["semi_minor_m"] == pytest.approx(minor, rel=1e-12)
    assert ellipse["orientation_deg"] == pytest.approx(bearing, abs=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_the_ellipse_is_numpys_eigen_decomposition(seed: int) -> None:
    """Random covariances at the origin: the axes are 2·√(numpy's eigenvalues) and the major
    axis is numpy's eigenvector of the largest one, read as a bearing (clockwise from north)."""
    rng = np.random.default_rng(seed)
    root = rng.normal(scale=30.0, size=(2, 2))
    block = root @ root.T
    ellipse = ellipse_at_origin(block.tolist())
    values, vectors = np.linalg.eigh(block)  # ascending
    east, north = vectors[:, 1]
    expected = math.degrees(math.atan2(east, north)) % 180.0
    assert ellipse["semi_major_m"] == pytest.approx(2 * math.sqrt(values[1]), rel=1e-9)
    assert ellipse["semi_minor_m"] == pytest.approx(2 * math.sqrt(values[0]), rel=1e-9)
    assert min(
        abs(ellipse["orientation_deg"] - expected), 180 - abs(ellipse["orientation_deg"] - expected)
    ) == pytest.approx(0.0, abs=1e-9)


def test_the_ellipse_is_oriented_in_the_tangent_plane_at_the_track() -> None:
    """A track 300 km east of the origin whose covariance is long along the session's north:
    at the track, that axis points where the geodesic from the track to a point 100 m along
    it leaves (PROJ's forward azimuth), not due north (the meridians converge)."""
    frame = LocalFrame(*ORIGIN)
    east, north = 300_000.0, 50_000.0
    covariance = np.diag([100.0, 1.0, 2500.0, 1.0])
    collection = feature_collection(
        [track("F", [east, 0.0, north, 0.0], covariance.tolist())],
        GeodeticOutput(frame, (0, 2), (1, 3)),
    )
    ellipse = collection["features"][0]["properties"]["position_ellipse"]
    inverse = proj_enu(ORIGIN)
    lat0, lon0, _ = inverse.transform(east, north, 0.0, direction="INVERSE")
    lat1, lon1, _ = inverse.transform(east, north + 100.0, 0.0, direction="INVERSE")
    azimuth, _, _ = WGS84.inv(lon0, lat0, lon1, lat1)
    assert abs(azimuth) > 1.0  # the test means something: ~2.8° off north here
    assert ellipse["orientation_deg"] == pytest.approx(azimuth % 180.0, abs=0.01)
    # the turn keeps the horizontal axes (the tilt changes them by ~(300/6378)²/2 ≈ 1e-3)
    assert ellipse["semi_major_m"] == pytest.approx(100.0, rel=2e-3)
    assert ellipse["semi_minor_m"] == pytest.approx(20.0, rel=2e-3)


def test_sources_are_sensor_ids_once_each() -> None:
    collection = feature_collection(
        [track("F", [0.0, 0.0, 0.0, 0.0], sources=("radar-2", "adsb", "radar-2"))],
        GeodeticOutput(LocalFrame(*ORIGIN), (0, 2), (1, 3)),
    )
    properties = collection["features"][0]["properties"]
    assert properties["sources"] == ["radar-2", "adsb"]
    assert properties["decision_state"] == "tied"


def test_feature_collection_positions_and_velocities() -> None:
    frame = LocalFrame(*ORIGIN)
    tracks = [
        track("F1", [20_000.0, 100.0, -35_000.0, 0.0, 9_000.0, 0.0]),
        track("F2", [0.0, 0.0, 0.0, 50.0, 0.0, -2.0]),
    ]
    collection = feature_collection(tracks, GeodeticOutput(frame, (0, 2, 4), (1, 3, 5)))
    assert collection["type"] == "FeatureCollection"
    features = collection["features"]
    assert [feature["id"] for feature in features] == ["F1", "F2"]
    inverse = proj_enu(ORIGIN)
    for feature, fused in zip(features, tracks, strict=True):
        state: list[float] = fused["state"]
        lat, lon, alt = inverse.transform(state[0], state[2], state[4], direction="INVERSE")
        lon_out, lat_out, alt_out = feature["geometry"]["coordinates"]
        assert_allclose([lat_out, lon_out], [lat, lon], atol=1e-8)  # ~1 mm
        assert_allclose(alt_out, alt, atol=1e-3)
        assert feature["properties"]["decision"] is None
    # At the origin the session's axes are the local ones: the velocity is unchanged.
    assert_allclose(features[1]["properties"]["velocity_enu"], [0.0, 50.0, -2.0], atol=1e-12)
    # 20 km east, 35 km south: the east-going track gains a small up/north part, speed kept.
    far = np.array(features[0]["properties"]["velocity_enu"])
    assert_allclose(np.linalg.norm(far), 100.0, rtol=1e-12)
    assert far[0] < 100.0 and abs(far[2]) > 1e-3


def test_geodetic_field_added_to_two_dimensional_tracks() -> None:
    frame = LocalFrame(*ORIGIN)
    out = with_geodetic([track("F1", [1000.0, 0.0, 2000.0, 0.0])], GeodeticOutput(frame, (0, 2)))
    lat, lon, alt = proj_enu(ORIGIN).transform(1000.0, 2000.0, 0.0, direction="INVERSE")
    assert_allclose(
        [out[0]["geodetic"]["lat"], out[0]["geodetic"]["lon"], out[0]["geodetic"]["alt"]],
        [lat, lon, alt],
        atol=1e-8,
    )


def test_geojson_over_the_api_carries_uncertainty_sources_and_decision_state(
    live_server: LiveServer,
) -> None:
    """A geodetic track list whose covariance is given in the ENU plane *at its point* comes
    back as a feature whose ellipse is that covariance's, by numpy (one source: the fused
    estimate is the report's); sources and decision state are the JSON picture's."""
    origin = {"lat": 48.85, "lon": 2.35, "alt": 100.0}
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "origin": origin,
        "sensors": [{"id": "adsb"}, {"id": "radar"}],
        "classes": ["liner", "fighter"],
    }
    block = np.array([[900.0, 500.0], [500.0, 400.0]])
    covariance = np.diag([0.0, 4.0, 0.0, 4.0])
    covariance[np.ix_([0, 2], [0, 2])] = block
    report = {
        "sensor": "adsb",
        "time": 1.0,
        "frame": "geodetic",
        "tracks": [
            {
                "id": "a",
                "state": [49.2, 0.0, 3.1, 150.0],  # ~40 km north, ~55 km east
                "covariance": covariance.tolist(),
                "classification": {
                    "mass": [
                        {"set": ["liner"], "mass": 0.8},
                        {"set": ["liner", "fighter"], "mass": 0.2},
                    ]
                },
            }
        ],
    }
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=config)
        assert created.status_code == 201, created.text
        sid, token = created.json()["id"], created.json()["token"]
        headers = {"Authorization": f"Bearer {token}"}
        answer = client.post(f"/v1/sessions/{sid}/tracks", json=report, headers=headers)
        assert answer.status_code == 200, answer.text
        (fused,) = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()["tracks"]
        geojson = client.get(f"/v1/sessions/{sid}/tracks?format=geojson", headers=headers)
        assert geojson.status_code == 200, geojson.text
    (feature,) = geojson.json()["features"]
    properties = feature["properties"]
    assert properties["sources"] == ["adsb"]
    assert properties["decision"] == "liner"
    assert properties["decision_state"] == fused["classification"]["decision_state"] == "decided"
    values, vectors = np.linalg.eigh(block)
    east, north = vectors[:, 1]
    ellipse = properties["position_ellipse"]
    # a 2-D session keeps the east/north block of the session plane: the two tangent planes
    # are tilted by distance / R ≈ 0.0105 rad here, and each cut drops ~tilt² of a variance
    tilt = math.hypot(fused["state"][0], fused["state"][2]) / 6.371e6
    assert ellipse["semi_major_m"] == pytest.approx(2 * math.sqrt(values[1]), rel=2 * tilt**2)
    assert ellipse["semi_minor_m"] == pytest.approx(2 * math.sqrt(values[0]), rel=2 * tilt**2)
    assert ellipse["orientation_deg"] == pytest.approx(
        math.degrees(math.atan2(east, north)) % 180.0, abs=math.degrees(tilt**2)
    )
