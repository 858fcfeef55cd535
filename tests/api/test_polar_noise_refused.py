"""A polar sensor's σ outside its documented bounds is a 422 at its field, on session creation.

The bounds (``api_schemas.config``): sigma_range 0.001 m to 100 km, an angle σ 0.0001° to 180°
(above π the angle is spread over more than the circle), sigma_range_rate 0.001 to 10 000 m/s.
Beyond them no sensor measures; before them, a finite absurd σ (1e30 m, 1e-30 m, 200°) was
accepted and the radar's covariances were 1e60 m² or 1e-60 m². The σ whose square is no
double at all (1e-170² underflows to 0, 1e200² overflows: hand-worked IEEE doubles) are
refused at the same place.
"""

from __future__ import annotations

from typing import Any

import httpx
import pytest

from tests.api.conftest import LiveServer


def _radar(**measurement: float) -> dict[str, Any]:
    """A 3-D session of one radar with range-rate, its σ overridden by ``measurement``."""
    noise: dict[str, Any] = {
        "kind": "polar",
        "sigma_range": 20.0,
        "sigma_azimuth_deg": 0.2,
        "sigma_elevation_deg": 0.3,
        "sigma_range_rate": 1.5,
    }
    noise.update(measurement)
    return {
        "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
        "sensors": [{"id": "radar", "site": {"position": [0.0, 0.0, 10.0]}, "measurement": noise}],
    }


@pytest.mark.parametrize(
    ("name", "sigma", "words"),
    [
        ("sigma_range", 1e30, "less than or equal to 100000"),
        ("sigma_range", 1e-30, "greater than or equal to 0.001"),
        ("sigma_range", 1e-170, "greater than or equal to 0.001"),
        ("sigma_range", 1e200, "less than or equal to 100000"),
        ("sigma_azimuth_deg", 200.0, "less than or equal to 180"),
        ("sigma_azimuth_deg", 1e-170, "greater than or equal to 0.0001"),
        ("sigma_elevation_deg", 1e200, "less than or equal to 180"),
        ("sigma_elevation_deg", 1e-30, "greater than or equal to 0.0001"),
        ("sigma_range_rate", 1e-170, "greater than or equal to 0.001"),
        ("sigma_range_rate", 1e30, "less than or equal to 10000"),
    ],
)
def test_a_sigma_outside_its_bounds_is_refused_at_its_field(
    live_server: LiveServer, name: str, sigma: float, words: str
) -> None:
    answer = httpx.post(f"{live_server.url}/v1/sessions", json=_radar(**{name: sigma}))
    assert answer.status_code == 422
    assert answer.headers["content-type"] == "application/problem+json"
    errors = answer.json()["errors"]
    assert [error["pointer"] for error in errors] == [f"#/sensors/0/measurement/{name}"]
    assert words in errors[0]["detail"]


@pytest.mark.parametrize(
    "bounds",
    [
        {"sigma_range": 1e-3, "sigma_azimuth_deg": 1e-4, "sigma_elevation_deg": 180.0},
        {"sigma_range": 1e5, "sigma_range_rate": 1e4, "sigma_elevation_deg": 1e-4},
        {"sigma_azimuth_deg": 180.0, "sigma_range_rate": 1e-3},
    ],
)
def test_the_bounds_themselves_are_accepted(
    live_server: LiveServer, bounds: dict[str, float]
) -> None:
    assert httpx.post(f"{live_server.url}/v1/sessions", json=_radar(**bounds)).status_code == 201


def test_the_same_radar_with_usable_sigmas_is_created(live_server: LiveServer) -> None:
    assert httpx.post(f"{live_server.url}/v1/sessions", json=_radar()).status_code == 201
