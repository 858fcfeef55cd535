"""A single-point start's second detection sets its velocity, not a manoeuvre (§8.3).

With the aircraft bank's held inputs a start 12 s old would otherwise be moved
2.8 km per axis by a 4g model — more than its 100 m/s prior's velocity — and
leave with a velocity wrong by hundreds of m/s (measured on the real-traffic
scene's 12 s radar)."""

from __future__ import annotations

import numpy as np

from core.tracking.config import LocalTrackerConfig
from core.tracking.tracker import LocalTracker


def test_a_start_second_detection_gives_every_model_the_two_point_velocity() -> None:
    """Per axis, independently of the tracker: the start is x ~ N(z₁, R), v ~ N(0, σ_v²);
    the second detection z₂ = x + v Δt + w + e, w the discrete white-noise acceleration
    (q B Bᵀ: q Δt⁴/4, q Δt³/2), e ~ N(0, R). Then E[v | z₂] =
    (σ_v² Δt + q Δt³/2) / (2R + σ_v² Δt² + q Δt⁴/4) · (z₂ − z₁) in every model."""
    r, sigma_v, q, dt = 2500.0, 100.0, 0.005, 12.0
    config = LocalTrackerConfig(measurement_noise=((r, 0.0), (0.0, r)))
    tracker = LocalTracker(config)
    first = np.array([[10_000.0, -4_000.0]])
    second = first + dt * np.array([[230.0, -150.0]])
    tracker.step(0.0, first)
    tracker.step(dt, second)
    gain = (sigma_v**2 * dt + q * dt**3 / 2) / (2 * r + sigma_v**2 * dt**2 + q * dt**4 / 4)
    expected = gain * (second[0] - first[0])
    (start,) = [row for row in range(tracker.n_tracks) if tracker._rows.life.hits[row] == 2]
    velocities = tracker._state.means[start][:, [1, 3]]  # every model's (ẋ, ẏ)
    np.testing.assert_allclose(velocities, np.broadcast_to(expected, velocities.shape), rtol=1e-9)
    # and no model is preferred: the mode probabilities are the start's (uniform)
    np.testing.assert_allclose(
        np.exp(tracker._state.log_mode_probabilities[start]), 1 / 13, rtol=1e-9
    )
