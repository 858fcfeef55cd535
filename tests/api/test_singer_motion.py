"""``motion.model: "singer"`` over the real API: the fused tracks are predicted with Singer's
model on the session's layout, as Stone Soup predicts with its own ``Singer``; a layout or
parameters that do not fit the model are refused with a 4xx naming the field."""

from __future__ import annotations

from datetime import timedelta
from typing import Any

import httpx
import numpy as np
import pytest
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, Singer

from .conftest import LiveServer

# the session's order [x, y, ẋ, ẏ, ẍ, ÿ]; Stone Soup's combined model is [x, ẋ, ẍ, y, ẏ, ÿ]
LAYOUT = {"dim": 6, "position": [0, 1], "velocity": [2, 3], "acceleration": [4, 5]}
STONE_SOUP_ORDER = [0, 2, 4, 1, 3, 5]
TAU, SIGMA = 12.0, 15.0


def _session(motion: dict[str, Any], **extra: Any) -> dict[str, Any]:
    return {
        "state": LAYOUT,
        "motion": motion,
        "sensors": [{"id": "a"}, {"id": "b"}],
        "fusion": {"state": "independent"},
        **extra,
    }


def test_fused_tracks_are_predicted_with_singers_model(live_server: LiveServer) -> None:
    """Sensor a reports at t = 0, sensor b at t = 2.5: the fused state at 2.5 is the
    information sum of a's estimate predicted by Stone Soup's Singer and b's estimate."""
    rng = np.random.default_rng(25)
    x_a = np.array([1000.0, 2000.0, 240.0, -30.0, 5.0, 12.0])
    x_b = x_a + rng.normal(0.0, [20.0, 20.0, 3.0, 3.0, 2.0, 2.0])
    x_b[:2] += 2.5 * x_a[2:4]
    p_a = np.diag([400.0, 400.0, 25.0, 25.0, 16.0, 16.0])
    p_b = np.diag([300.0, 500.0, 36.0, 16.0, 9.0, 25.0])
    config = _session({"model": "singer", "manoeuvre_time": TAU, "acceleration_std": SIGMA})
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=config)
        assert created.status_code == 201, created.text
        sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
        for sensor, time, state, covariance in (("a", 0.0, x_a, p_a), ("b", 2.5, x_b, p_b)):
            body = {
                "sensor": sensor,
                "time": time,
                "tracks": [
                    {"id": "t1", "state": state.tolist(), "covariance": covariance.tolist()}
                ],
            }
            answer = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
            assert answer.status_code == 200, answer.text
        (fused,) = answer.json()["tracks"]
    axis = Singer(damping_coeff=1.0 / TAU, noise_diff_coeff=2.0 / TAU * SIGMA**2)
    model = CombinedLinearGaussianTransitionModel([axis, axis])
    order = np.ix_(STONE_SOUP_ORDER, STONE_SOUP_ORDER)
    f = np.empty((6, 6))
    q = np.empty((6, 6))
    f[order] = model.matrix(time_interval=timedelta(seconds=2.5))
    q[order] = model.covar(time_interval=timedelta(seconds=2.5))
    predicted, predicted_cov = f @ x_a, f @ p_a @ f.T + q
    information = np.linalg.inv(predicted_cov) + np.linalg.inv(p_b)
    expected_cov = np.linalg.inv(information)
    expected = expected_cov @ (
        np.linalg.solve(predicted_cov, predicted) + np.linalg.solve(p_b, x_b)
    )
    np.testing.assert_allclose(fused["state"], expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fused["covariance"], expected_cov, rtol=1e-8, atol=1e-9)
    # the model matters: predicted by constant velocity (the accelerations kept, not used)
    # the fused position would be decimetres away (the check above holds to 1e-9)
    f_cv = np.eye(6)
    f_cv[[0, 1], [2, 3]] = 2.5
    predicted_cv = f_cv @ x_a
    moved_cv = expected_cov @ (
        np.linalg.solve(predicted_cov, predicted_cv) + np.linalg.solve(p_b, x_b)
    )
    assert np.abs(np.asarray(fused["state"][:2]) - moved_cv[:2]).max() > 0.1


@pytest.mark.parametrize(
    ("config", "field"),
    [
        # Singer moves accelerations: the state must have them
        (
            {
                **_session({"model": "singer"}),
                "state": {"dim": 4, "position": [0, 1], "velocity": [2, 3]},
            },
            ["state", "acceleration"],
        ),
        (_session({"model": "singer", "q": 5.0}), ["motion", "q"]),
        (
            _session({"model": "constant_velocity", "manoeuvre_time": 5.0}),
            ["motion", "manoeuvre_time"],
        ),
        (_session({"model": "singer", "manoeuvre_time": 0.0}), ["motion", "manoeuvre_time"]),
        (
            {**_session({"model": "singer"}), "state": {**LAYOUT, "acceleration": [4]}},
            ["state", "acceleration"],
        ),
        # detecting sensors are tracked with positions and velocities only
        (
            _session(
                {"model": "singer"},
                sensors=[{"id": "r", "measurement": {"r": [[1.0, 0.0], [0.0, 1.0]]}}],
            ),
            ["sensors", 0, "measurement"],
        ),
    ],
)
def test_a_session_that_does_not_fit_the_model_is_refused_naming_the_field(
    live_server: LiveServer, config: dict[str, Any], field: list[object]
) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        refused = client.post("/v1/sessions", json=config)
    assert refused.status_code == 422, refused.text
    assert refused.headers["content-type"].startswith("application/problem+json")
    locations = [error["loc"][-len(field) :] for error in refused.json()["errors"]]
    assert field in locations, refused.json()


def test_singer_defaults_need_no_tuning(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=_session({"model": "singer"}))
    assert created.status_code == 201, created.text


def test_a_sensor_frame_track_has_its_acceleration_turned_with_its_velocity(
    live_server: LiveServer,
) -> None:
    """A sensor at (1000, 2000) heading 90°: its y axis is the session's x (the rule of
    tests/api/test_sensor_frames.py). A track at y = 300 m, ẏ = 10 m/s, ÿ = 3 m/s² in its
    frame is at x = 1300 m, ẋ = 10 m/s, ẍ = 3 m/s² in the session's."""
    config = {
        "state": LAYOUT,
        "motion": {"model": "singer"},
        "sensors": [{"id": "own", "site": {"position": [1000.0, 2000.0], "heading_deg": 90.0}}],
    }
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=config)
        assert created.status_code == 201, created.text
        sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
        body = {
            "sensor": "own",
            "time": 1.0,
            "frame": "sensor",
            "tracks": [
                {
                    "id": "t",
                    "state": [0.0, 300.0, 0.0, 10.0, 0.0, 3.0],
                    "covariance": np.diag([25.0, 25.0, 1.0, 1.0, 4.0, 4.0]).tolist(),
                }
            ],
        }
        answer = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        (track,) = answer.json()["tracks"]
    np.testing.assert_allclose(track["state"], [1300.0, 2000.0, 10.0, 0.0, 3.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(
        np.diag(track["covariance"]), [25.0, 25.0, 1.0, 1.0, 4.0, 4.0], atol=1e-9
    )
