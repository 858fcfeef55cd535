"""The 3-D aircraft bank's vertical axis (core/tracking/presets.py, docs/algorithms.md §8.13):
a constant velocity driven by white acceleration of σ 0.1 g, so that a level-off is followed.

Every model of the bank has the same vertical axis (no input, the same q) and the detections
a diagonal R, so the tracker's vertical estimate is a Kalman filter on [z, ż] alone. The
oracle is that filter written out here: a single-point start (z₀, ż = 0 ± 100 m/s, the
no-prior σ_v), then predict with ``F = [[1, Δt], [0, 1]]``, ``Q = q [[Δt⁴/4, Δt³/2],
[Δt³/2, Δt²]]`` and update with ``H = [1, 0]`` — and the level-off's error of the papers'
q = 0.005 (σ 0.07 m/s²) from the same filter.
"""

from __future__ import annotations

import numpy as np

from core.tracking.config import LocalTrackerConfig
from core.tracking.tracker import LocalTracker

PERIOD, SIGMA = 4.0, 60.0
CLIMB, LEVEL = 15.0, 12
"""15 m/s up for 12 scans, then level (a level-off in 4 s: 3.75 m/s²)."""


def _truth(scans: int) -> np.ndarray:
    t = np.arange(scans) * PERIOD
    east = 20_000.0 + 200.0 * t
    up = 3_000.0 + CLIMB * np.minimum(t, LEVEL * PERIOD)
    return np.stack([east, np.full_like(t, 5_000.0), up], axis=1)


def _kalman(heights: np.ndarray, q: float) -> np.ndarray:
    """[z, ż] after each detection, by hand."""
    transition = np.array([[1.0, PERIOD], [0.0, 1.0]])
    noise = q * np.array([[PERIOD**4 / 4, PERIOD**3 / 2], [PERIOD**3 / 2, PERIOD**2]])
    state = np.array([heights[0], 0.0])
    covariance = np.diag([SIGMA**2, 100.0**2])
    out = [state]
    for z in heights[1:]:
        state = transition @ state
        covariance = transition @ covariance @ transition.T + noise
        gain = covariance[:, 0] / (covariance[0, 0] + SIGMA**2)
        state = state + gain * (z - state[0])
        covariance = covariance - np.outer(gain, covariance[0])
        out.append(state)
    return np.array(out)


def test_the_vertical_axis_is_a_kalman_filter_of_white_acceleration_of_a_tenth_of_g() -> None:
    rng = np.random.default_rng(3)
    truth = _truth(30)
    detections = truth + rng.normal(0.0, SIGMA, truth.shape)
    r = SIGMA**2 * np.eye(3)
    tracker = LocalTracker(
        LocalTrackerConfig(
            preset="aircraft",
            axes=3,
            time_interval=PERIOD,
            measurement_noise=tuple(tuple(row) for row in r.tolist()),
            classification=None,
        )
    )
    vertical = []
    for k, point in enumerate(detections):
        step = tracker.step(k * PERIOD, point[None])
        # the start of the first detection (each detection also starts one of its own)
        track = min((t for t in step.tracks if t.hits == k + 1), key=lambda t: t.id)
        vertical.append(np.asarray(track.state)[[4, 5]])
    expected = _kalman(detections[:, 2], 0.981**2)  # σ = 0.1 × 9.81 m/s²
    np.testing.assert_allclose(np.array(vertical), expected, rtol=1e-6, atol=1e-6)
    # after the level-off: the σ 0.1 g filter follows within the detections' own σ (RMS
    # ≈ 50 m here); the papers' q = 0.005 keeps the climb's velocity and overshoots (RMS
    # ≈ 130 m, 170 m at worst)
    after = slice(LEVEL + 3, None)
    stiff = _kalman(detections[:, 2], 0.005)

    def rms(estimates: np.ndarray) -> float:
        return float(np.sqrt(np.mean((estimates[after, 0] - truth[after, 2]) ** 2)))

    assert rms(expected) < SIGMA < 2 * SIGMA < rms(stiff)
