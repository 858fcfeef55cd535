"""``motion.q``: one meaning in both layers, and its default derived from the tracking preset."""

from __future__ import annotations

from datetime import timedelta
from typing import Any

import numpy as np
import pytest
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)

from api_schemas.config import SessionConfig
from app.sessions.translate import fusion_config

G = 9.81


def _config(preset: str | None, motion: dict[str, Any] | None, axes: int = 2) -> SessionConfig:
    body: dict[str, Any] = {
        "state": {
            "dim": 2 * axes,
            "position": list(range(0, 2 * axes, 2)),
            "velocity": list(range(1, 2 * axes, 2)),
        },
        "sensors": [{"id": "radar", "measurement": {"r": np.eye(axes).tolist()}}],
        "tracking": {"preset": preset},
    }
    if motion is not None:
        body["motion"] = motion
    return SessionConfig.model_validate(body)


@pytest.mark.parametrize(
    ("preset", "expected"),
    [
        # the largest velocity change in one 1 s scan at 3σ: Δv² / (9 ΔT)
        ("aircraft", (4 * G) ** 2 * 2 / 9),  # m10..m13: (±4g, ±4g)
        ("pedestrian", 6.0**2 * 2 / 9),  # (0, 0) → (6, 6) m/s
        (None, 1.0),
    ],
)
def test_default_motion_q_comes_from_the_preset(preset: str | None, expected: float) -> None:
    config = _config(preset, None)
    assert config.motion.q is None
    assert fusion_config(config).motion.q == pytest.approx(expected, rel=1e-12)


def test_an_explicit_q_is_the_white_noise_density_of_both_layers() -> None:
    """The fused model and the local CV model (no preset, 3-D) are Stone Soup's ConstantVelocity."""
    q, dt = 5.0, 0.7
    engine_config = fusion_config(_config(None, {"q": q}, axes=3))
    axis = ConstantVelocity(noise_diff_coeff=q)
    stone_soup = CombinedLinearGaussianTransitionModel([axis, axis, axis])
    expected = stone_soup.covar(time_interval=timedelta(seconds=dt))
    _, fused_noise = engine_config.motion.matrices(np.array(dt))
    np.testing.assert_allclose(fused_noise, expected, rtol=1e-12)
    tracker = engine_config.sensors[0].tracker
    assert tracker is not None
    local = tracker.model_bank().at(dt)
    np.testing.assert_allclose(local.process_noise[0], expected, rtol=1e-12)
    np.testing.assert_allclose(
        local.transition[0], stone_soup.matrix(time_interval=timedelta(seconds=dt)), rtol=1e-12
    )
