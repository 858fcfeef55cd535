"""GeoJSON and geodetic output of fused tracks, checked with PROJ."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from app.geo.geodesy import LocalFrame
from app.geo.geojson import GeodeticOutput, feature_collection, with_geodetic
from tests.api.proj_oracle import proj_enu

ORIGIN = (52.0, 4.4, 12.0)


def track(track_id: str, state: list[float]) -> dict[str, object]:
    return {
        "id": track_id,
        "status": "confirmed",
        "state": state,
        "classification": {"decision": None, "pignistic": {"a": 0.5, "b": 0.5}},
    }


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
        state = fused["state"]
        assert isinstance(state, list)
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
