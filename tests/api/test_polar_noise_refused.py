"""A polar sensor's σ that gives no usable variance is a 422 at its field, on session creation.

Hand-worked IEEE doubles: 1e-170² = 1e-340 underflows to 0 (the least subnormal is
4.9e-324), 1e200² overflows (the largest double is 1.8e308): neither is a variance. Before,
the underflow was a 422 pointing at the document's root ("#") and the overflow a 500.
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
    ("name", "sigma"),
    [
        ("sigma_range", 1e-170),
        ("sigma_range", 1e200),
        ("sigma_azimuth_deg", 1e-170),
        ("sigma_elevation_deg", 1e200),
        ("sigma_range_rate", 1e-170),
    ],
)
def test_a_sigma_without_a_variance_is_refused_at_its_field(
    live_server: LiveServer, name: str, sigma: float
) -> None:
    answer = httpx.post(f"{live_server.url}/v1/sessions", json=_radar(**{name: sigma}))
    assert answer.status_code == 422
    assert answer.headers["content-type"] == "application/problem+json"
    errors = answer.json()["errors"]
    assert [error["pointer"] for error in errors] == [f"#/sensors/0/measurement/{name}"]
    assert "no usable variance" in errors[0]["detail"]


def test_the_same_radar_with_usable_sigmas_is_created(live_server: LiveServer) -> None:
    assert httpx.post(f"{live_server.url}/v1/sessions", json=_radar()).status_code == 201
