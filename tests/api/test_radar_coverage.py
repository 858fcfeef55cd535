"""A radar's data-sheet coverage on the wire (``sensors[i].coverage``, docs/algorithms.md
§8.11): bad fields are refused with a 422 problem+json naming the field, and a good one
reaches the core as a volume at the radar's site in its own ENU axes."""

from __future__ import annotations

from typing import Any

import httpx
import numpy as np
import pymap3d
import pytest

from api_schemas.config import SessionConfig
from app.sessions.translate import fusion_config

from .conftest import LiveServer

LAYOUT_3D = {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]}
ORIGIN = {"lat": 48.85, "lon": 2.45, "alt": 100.0}
POLAR_3D = {
    "kind": "polar",
    "sigma_range": 40.0,
    "sigma_azimuth_deg": 0.12,
    "sigma_elevation_deg": 0.25,
}


def radar(coverage: dict[str, Any], **fields: Any) -> dict[str, Any]:
    return {
        "id": "radar-n",
        "site": {"lat": 49.45, "lon": 2.10, "alt": 150.0},
        "measurement": POLAR_3D,
        "coverage": coverage,
        **fields,
    }


def session(sensor: dict[str, Any], state: dict[str, Any] = LAYOUT_3D) -> dict[str, Any]:
    return {"state": state, "origin": ORIGIN, "sensors": [sensor]}


CARTESIAN = {"kind": "cartesian", "r": [[100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [0.0, 0.0, 100.0]]}


@pytest.mark.parametrize(
    ("config", "loc"),
    [
        (session(radar({"range_max": 0})), ["body", "sensors", 0, "coverage", "range_max"]),
        (session(radar({"range_max": -5e4})), ["body", "sensors", 0, "coverage", "range_max"]),
        (session(radar({"range_max": 1e300})), ["body", "sensors", 0, "coverage", "range_max"]),
        (
            session(radar({"antenna_height": 1e308})),  # its square overflows: no horizon
            ["body", "sensors", 0, "coverage", "antenna_height"],
        ),
        (
            session(radar({"elevation_max_deg": 120})),
            ["body", "sensors", 0, "coverage", "elevation_max_deg"],
        ),
        (
            session(radar({"elevation_min_deg": 10, "elevation_max_deg": 5})),
            ["body", "sensors", 0, "coverage", "elevation_min_deg"],
        ),
        (
            session(radar({"antenna_height": -3})),
            ["body", "sensors", 0, "coverage", "antenna_height"],
        ),
        (
            session(radar({"range_max": 1e5, "beam": 3})),
            ["body", "sensors", 0, "coverage", "beam"],
        ),
        (  # a cartesian sensor has no site-centred volume
            session(radar({"range_max": 1e5}, measurement=CARTESIAN)),
            ["body", "sensors", 0, "coverage"],
        ),
        (  # nor has a 2-D session's radar an elevation: its fov says where it looks
            session(
                radar(
                    {"range_max": 1e5},
                    measurement={"kind": "polar", "sigma_range": 40.0, "sigma_azimuth_deg": 0.1},
                ),
                state={"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            ),
            ["body", "sensors", 0, "coverage"],
        ),
    ],
)
def test_bad_coverage_fields_are_refused_naming_the_field(
    live_server: LiveServer, config: dict[str, Any], loc: list[Any]
) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        answer = client.post("/v1/sessions", json=config)
    assert answer.status_code == 422, answer.text
    assert answer.headers["content-type"].startswith("application/problem+json")
    locations = [error["loc"] for error in answer.json()["errors"]]
    assert loc in locations, locations
    pointer = "#/" + "/".join(str(part) for part in loc[1:])
    assert pointer in [error["pointer"] for error in answer.json()["errors"]]


def test_a_radar_coverage_reaches_the_core_at_its_site_in_its_axes() -> None:
    """The volume's site is the radar's place in the session frame, its axes the site's ENU
    unit vectors in the session's axes (pymap3d, by way of ECEF), its limits as given;
    without ``coverage`` there is none (the behaviour of before)."""
    coverage = {
        "range_max": 150_000.0,
        "elevation_min_deg": -2.0,
        "elevation_max_deg": 30.0,
        "antenna_height": 150.0,
    }
    engine = fusion_config(SessionConfig.model_validate(session(radar(coverage))))
    volume = engine.sensor("radar-n").volume
    assert volume is not None
    site = pymap3d.geodetic2enu(49.45, 2.10, 150.0, ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"])
    np.testing.assert_allclose(volume.site, site, atol=1e-6)
    for row, unit in zip(volume.axes, np.eye(3), strict=True):
        ecef = pymap3d.enu2uvw(*unit, 49.45, 2.10)
        np.testing.assert_allclose(
            row, pymap3d.uvw2enu(*ecef, ORIGIN["lat"], ORIGIN["lon"]), atol=1e-12
        )
    assert (volume.range_max, volume.elevation_min_deg, volume.elevation_max_deg) == (
        150_000.0,
        -2.0,
        30.0,
    )
    assert volume.antenna_height == 150.0
    tracker = engine.sensor("radar-n").tracker
    assert tracker is not None and tracker.volumes["radar-n"] == volume
    bare = radar(coverage)
    del bare["coverage"]
    plain = fusion_config(SessionConfig.model_validate(session(bare))).sensor("radar-n")
    assert plain.volume is None and plain.tracker is not None and not plain.tracker.volumes
