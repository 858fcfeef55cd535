"""A cartesian R (a sensor's, or a detection's own) outside its documented bounds is a 422 at its
field, before any work.

The bounds (``api_schemas.linalg.NOISE_VARIANCE_BOUNDS_M2``): every eigenvalue of R, the
variance along one of its axes, between (1 mm)² = 1e-6 m² and (100 km)² = 1e10 m², as a polar
sensor's ``sigma_range``. Before them, a sensor with ``r = 1e-60·I`` was accepted and its first
detection was a 500: its clutter box ``z ± 3·1e-30`` rounds back to ``z`` (the spacing of the
doubles near 1 m is 2.2e-16), a box of volume 0 divided by.

The eigenvalues below are worked by hand: diag(a, b) has eigenvalues a and b;
[[1, c], [c, 1]] has eigenvalues 1 ± c.
"""

from __future__ import annotations

from typing import Any

import httpx
import pytest

from tests.api.conftest import LiveServer

ONE_METRE = [[1.0, 0.0], [0.0, 1.0]]


def _post_detections(
    server: LiveServer, created: httpx.Response, detections: list[dict[str, Any]]
) -> httpx.Response:
    """POST one batch of the camera's detections at time 0 to the session ``created``."""
    session = created.json()
    return httpx.post(
        f"{server.url}/v1/sessions/{session['id']}/detections",
        json={"sensor": "camera", "time": 0.0, "detections": detections},
        headers={"Authorization": f"Bearer {session['token']}"},
    )


def _session(r: list[list[float]]) -> dict[str, Any]:
    """A 2-D session of one cartesian sensor whose R is ``r`` (m²)."""
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [{"id": "camera", "measurement": {"kind": "cartesian", "r": r}}],
    }


REFUSED = [
    pytest.param([[1e-60, 0.0], [0.0, 1e-60]], "below", id="1e-60 I (the 500)"),
    pytest.param([[1.0, 0.0], [0.0, 1e-7]], "below", id="one axis 0.3 mm"),
    pytest.param([[1.0, 1.0 - 1e-7], [1.0 - 1e-7, 1.0]], "below", id="correlated, 1e-7 m² across"),
    pytest.param([[1e11, 0.0], [0.0, 1.0]], "above", id="one axis 316 km"),
    pytest.param([[1e60, 0.0], [0.0, 1e60]], "above", id="1e60 I"),
]
ACCEPTED = [
    pytest.param([[1e-6, 0.0], [0.0, 1e-6]], id="the lower bound"),
    pytest.param([[1e10, 0.0], [0.0, 1e10]], id="the upper bound"),
    pytest.param([[2.0, 1.0], [1.0, 2.0]], id="correlated, 1 and 3 m²"),
]


@pytest.mark.parametrize(("r", "words"), REFUSED)
def test_a_sensor_r_outside_its_bounds_is_refused_at_its_field(
    live_server: LiveServer, r: list[list[float]], words: str
) -> None:
    answer = httpx.post(f"{live_server.url}/v1/sessions", json=_session(r))
    assert answer.status_code == 422
    assert answer.headers["content-type"] == "application/problem+json"
    errors = answer.json()["errors"]
    assert [error["pointer"] for error in errors] == ["#/sensors/0/measurement/r"]
    assert words in errors[0]["detail"]


@pytest.mark.parametrize(("r", "words"), REFUSED)
def test_a_detection_r_outside_its_bounds_is_refused_at_its_field(
    live_server: LiveServer, r: list[list[float]], words: str
) -> None:
    created = httpx.post(f"{live_server.url}/v1/sessions", json=_session(ONE_METRE))
    assert created.status_code == 201
    answer = _post_detections(
        live_server, created, [{"z": [1.0, 2.0]}, {"z": [50.0, 60.0], "r": r}]
    )
    assert answer.status_code == 422
    assert answer.headers["content-type"] == "application/problem+json"
    errors = answer.json()["errors"]
    assert [error["pointer"] for error in errors] == ["#/detections/1/r"]
    assert words in errors[0]["detail"]
    # the session still takes the sensor's detections
    again = _post_detections(live_server, created, [{"z": [1.0, 2.0]}])
    assert again.status_code == 200, again.text


@pytest.mark.parametrize("r", ACCEPTED)
def test_an_r_within_its_bounds_is_accepted_and_its_detections_fused(
    live_server: LiveServer, r: list[list[float]]
) -> None:
    created = httpx.post(f"{live_server.url}/v1/sessions", json=_session(r))
    assert created.status_code == 201
    answer = _post_detections(live_server, created, [{"z": [1.0, 2.0], "r": r}])
    assert answer.status_code == 200, answer.text
