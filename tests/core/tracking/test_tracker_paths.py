"""LocalTracker paths the scenario tests do not reach, checked against a hand-written Kalman filter.

Every test runs a single constant-velocity model (an IMM of one model is the
Kalman filter: mode probability 1), ΔT = 1 s, R = I, Q = q B Bᵀ with
B = [[ΔT²/2, 0], [ΔT, 0], [0, ΔT²/2], [0, ΔT]] ([MTT] eq 24). The reference
filter below is written from those formulas, not from the library's models.
The 0.999 gate on D for q = 2 is the χ²₂ quantile −2 ln(1 − 0.999).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.geometry import Sector
from core.lifecycle import LifeCycleConfig, ScoreModel, StatusReason, TrackStatus
from core.tracking import ModelBank
from core.tracking.config import LocalTrackerConfig
from core.tracking.tracker import LocalTracker

NOISE_INTENSITY = 0.01
BANK = ModelBank.from_config(
    {
        "time_interval": 1.0,
        "measurement": {"variance": 1.0},
        "models": [{"kind": "constant_velocity", "name": "cv", "noise_intensity": NOISE_INTENSITY}],
    }
)
F = np.array(
    [[1.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0]]
)
B = np.array([[0.5, 0.0], [1.0, 0.0], [0.0, 0.5], [0.0, 1.0]])
Q = NOISE_INTENSITY * B @ B.T
H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
R = np.eye(2)
GATE = -2.0 * math.log(1.0 - 0.999)  # χ²₂ quantile at 0.999


def predict(x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return F @ x, F @ p @ F.T + Q


def kalman_update(
    x: np.ndarray, p: np.ndarray, z: np.ndarray, noise: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Posterior mean, covariance, and the hit's D and ln|S|."""
    s = H @ p @ H.T + noise
    gain = p @ H.T @ np.linalg.inv(s)
    innovation = z - H @ x
    distance = float(innovation @ np.linalg.solve(s, innovation))
    return x + gain @ innovation, (np.eye(4) - gain @ H) @ p, distance, math.log(np.linalg.det(s))


def hit_increment(score: ScoreModel, distance: float, log_det: float) -> float:
    """[MTT] §4.3 for q = 2: ln[P_D / (2π β_FT √|S|)] − D/2."""
    return (
        math.log(score.p_detect / (2.0 * math.pi * score.false_target_density))
        - 0.5 * log_det
        - 0.5 * distance
    )


def two_point_covariance() -> np.ndarray:
    """Two-point initiation with ΔT = 1: position R, velocity 2R, cross-covariance R."""
    p = np.zeros((4, 4))
    pos, vel = [0, 2], [1, 3]
    p[np.ix_(pos, pos)] = R
    p[np.ix_(vel, vel)] = 2.0 * R
    p[np.ix_(pos, vel)] = R
    p[np.ix_(vel, pos)] = R
    return p


# ---------------------------------------------------------- gate emptiness
def test_a_vanished_target_is_terminated_by_gate_emptiness_when_the_product_predicts() -> None:
    """[HZ] §4.2: P = Π_k [1 − (ρ_FA + ρ_NT) A_G(k)], A_G = π γ √|S| (q = 2), terminate at P < 0.5.

    A stationary target at the origin (exact detections) for scans 0..7, then
    nothing. Densities 1e-3 make the gate fill fast; ``score_ceiling=None``
    keeps the raw SPRT score far above the delete threshold, so only gate
    emptiness can end the track.
    """
    rho = 1e-3
    life = LifeCycleConfig.paper(
        2, false_target_density=rho, new_target_density=rho, score_ceiling=None
    )
    config = LocalTrackerConfig.paper(bank=BANK, p_detect=0.9, life_cycle=life)
    score = config.score
    tracker = LocalTracker(config)
    last_hit = 7
    steps = {
        t: tracker.step(float(t), [[0.0, 0.0]] if t <= last_hit else np.zeros((0, 2)))
        for t in range(last_hit + 1)
    }
    assert steps[last_hit].track("L1").status is TrackStatus.CONFIRMED

    # Reference: two-point track at scan 1, updated at scans 2..7 with z = 0.
    x, p = np.zeros(4), two_point_covariance()
    # The pair's start: L₀ plus the second detection's ΔL, z₁ − z₀ = 0 under
    # 2R + σ_v² I (Δt = 1, σ_v the default 300 m/s): |S₂| = (2 + 300²)².
    expected_score = score.initial + hit_increment(score, 0.0, 2.0 * math.log(2.0 + 300.0**2))
    for _ in range(2, last_hit + 1):
        x, p = predict(x, p)
        x, p, distance, log_det = kalman_update(x, p, np.zeros(2), R)
        expected_score += hit_increment(score, distance, log_det)
    assert steps[last_hit].track("L1").score == pytest.approx(expected_score, rel=1e-9)
    np.testing.assert_allclose(steps[last_hit].track("L1").covariance, p, rtol=1e-9, atol=1e-12)
    # Misses until the empty-gate probability falls below 0.5.
    probability, misses = 1.0, 0
    while probability >= 0.5:
        x, p = predict(x, p)
        s = H @ p @ H.T + R
        area = math.pi * GATE * math.sqrt(np.linalg.det(s))
        probability *= 1.0 - 2.0 * rho * area
        misses += 1
    assert misses == 4  # worked out above: P ≈ 0.853, 0.700, 0.544, then < 0.5
    assert expected_score + misses * score.miss_increment > score.delete_threshold

    for k in range(1, misses + 1):
        track = tracker.step(float(last_hit + k), np.zeros((0, 2))).track("L1")
        assert track.score == pytest.approx(expected_score + k * score.miss_increment, rel=1e-9)
        if k < misses:
            assert (track.status, track.reason) == (TrackStatus.COASTING, StatusReason.MISSED)
        else:
            assert (track.status, track.reason) == (
                TrackStatus.TERMINATED,
                StatusReason.GATE_EMPTINESS,
            )
    assert tracker.n_tracks == 0


def test_gate_emptiness_product_matches_the_reference_scan_by_scan() -> None:
    """The exported empty-gate probability after each miss is the reference product."""
    rho = 1e-3
    life = LifeCycleConfig.paper(
        2, false_target_density=rho, new_target_density=rho, score_ceiling=None
    )
    # a velocity prior of 1 m/s: the standing pair's start score confirms it by the 4th scan
    config = LocalTrackerConfig.paper(
        bank=BANK, p_detect=0.9, life_cycle=life, initial_velocity_std=1.0
    )
    tracker = LocalTracker(config)
    for t in range(4):
        tracker.step(float(t), [[0.0, 0.0]])
    x, p = np.zeros(4), two_point_covariance()
    for _ in range(2, 4):
        x, p = predict(x, p)
        x, p, _, _ = kalman_update(x, p, np.zeros(2), R)
    probability = 1.0
    for k in range(1, 3):
        tracker.step(float(3 + k), np.zeros((0, 2)))
        x, p = predict(x, p)
        area = math.pi * GATE * math.sqrt(np.linalg.det(H @ p @ H.T + R))
        probability *= 1.0 - 2.0 * rho * area
        (entry,) = tracker.export()["tracks"]
        assert entry["empty_gate_probability"] == pytest.approx(probability, rel=1e-9)


# -------------------------------------------------------------- occlusion
@pytest.mark.parametrize("radius", [0.0, 2.0])
def test_a_track_hidden_behind_a_known_track_is_not_penalised(radius: float) -> None:
    """[HZ] §2.1: A at (0, 50) hides B at (0, 100) from a radar at the origin looking north.

    Both are confirmed (two-point at scan 1, the third hit adds ≈ 11.7 ≥ 6.9),
    their scores clamped at the confirm threshold; at scan 3 only A is
    detected. With radius 2 B is hidden: no miss, score unchanged, phantom
    (reason ``occluded``). With radius 0 B is a plain miss: coasting, score
    + ln(1 − P_D) = ln 0.1.
    """
    view = Sector(
        origin=(0.0, 0.0), heading_deg=90.0, half_angle_deg=30.0, range_min=0.0, range_max=500.0
    )
    config = LocalTrackerConfig.paper(
        bank=BANK,
        fields_of_view={"radar": view},
        life_cycle=LifeCycleConfig.paper(2, occlusion_radius=radius),
    )
    tracker = LocalTracker(config)
    a, b = [0.0, 50.0], [0.0, 100.0]
    for t in range(3):
        step = tracker.step(float(t), [a, b])
    assert step.assignment == ("L1", "L2")
    before = step.track("L2")
    assert before.status is TrackStatus.CONFIRMED
    assert before.score == pytest.approx(config.score.confirm_threshold)
    after = tracker.step(3.0, [a])
    hidden = after.track("L2")
    assert after.track("L1").status is TrackStatus.CONFIRMED
    if radius > 0.0:
        assert hidden.score == before.score
        assert (hidden.status, hidden.reason) == (TrackStatus.PHANTOM, StatusReason.OCCLUDED)
    else:
        assert hidden.score == pytest.approx(before.score + math.log(0.1), rel=1e-12)
        assert (hidden.status, hidden.reason) == (TrackStatus.COASTING, StatusReason.MISSED)


# ------------------------------------------------------- single-point start
def test_single_point_initiation_starts_at_once_and_the_sprt_confirms() -> None:
    """Position z (covariance R), velocity 0 (variance σ_v²), L₀ = ln(β_NT/β_FT) = 0.

    Repeated exact detections at (10, 20): the reference filter's score
    crosses ln(0.99/0.001) after the number of hits computed below.
    """
    sigma_v = 30.0
    config = LocalTrackerConfig.paper(
        bank=BANK, initiation="single_point", initial_velocity_std=sigma_v
    )
    score = config.score
    tracker = LocalTracker(config)
    z = np.array([10.0, 20.0])
    first = tracker.step(0.0, [z])
    assert first.assignment == ("L1",)
    track = first.track("L1")
    assert (track.status, track.reason, track.hits) == (
        TrackStatus.TENTATIVE,
        StatusReason.INITIATED,
        1,
    )
    assert track.score == pytest.approx(math.log(1e-6 / 1e-6))
    np.testing.assert_array_equal(track.state, [10.0, 0.0, 20.0, 0.0])
    np.testing.assert_array_equal(track.covariance, np.diag([1.0, sigma_v**2, 1.0, sigma_v**2]))

    x, p = track.state.copy(), np.diag([1.0, sigma_v**2, 1.0, sigma_v**2])
    expected = score.initial
    hits_to_confirm = 1
    while expected < score.confirm_threshold:
        x, p = predict(x, p)
        x, p, distance, log_det = kalman_update(x, p, z, R)
        expected += hit_increment(score, distance, log_det)
        hits_to_confirm += 1
    # First hit: |S| ≈ (1 + 900 + 1)², ΔL ≈ ln(0.9e6 / (2π · 902)) ≈ 5.07 < 6.9; the second confirms.
    assert hits_to_confirm == 3
    for t in range(1, hits_to_confirm):
        track = tracker.step(float(t), [z]).track("L1")
        assert track.hits == t + 1
        if t < hits_to_confirm - 1:
            assert track.status is TrackStatus.TENTATIVE
    assert (track.status, track.reason) == (TrackStatus.CONFIRMED, StatusReason.SCORE_CONFIRMED)
    np.testing.assert_allclose(track.state, x, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(track.covariance, p, rtol=1e-9, atol=1e-12)


# ------------------------------------------------ per-detection covariance
def test_a_detection_with_its_own_covariance_gets_the_kalman_update_with_it() -> None:
    """Scan 3 brings z = (1, −0.5) with R₃ = [[4, 1], [1, 2]]; the update must use R₃, not I."""
    config = LocalTrackerConfig.paper(
        bank=BANK, life_cycle=LifeCycleConfig.paper(2, score_ceiling=None)
    )
    own = np.array([[4.0, 1.0], [1.0, 2.0]])
    z = np.array([1.0, -0.5])
    with_own, default = LocalTracker(config), LocalTracker(config)
    for t in range(3):
        scan = with_own.step(float(t), [[0.0, 0.0]])
        default.step(float(t), [[0.0, 0.0]])
    prior = scan.track("L1")
    x_prior, p_prior = predict(prior.state, prior.covariance)

    x_own, p_own, d_own, log_det_own = kalman_update(x_prior, p_prior, z, own)
    x_r, p_r, _, _ = kalman_update(x_prior, p_prior, z, R)
    step = with_own.step(3.0, [z], measurement_covariances=[own])
    assert step.assignment == ("L1",)
    track = step.track("L1")
    np.testing.assert_allclose(track.state, x_own, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(track.covariance, p_own, rtol=1e-9, atol=1e-12)
    assert track.score == pytest.approx(
        prior.score + hit_increment(config.score, d_own, log_det_own), rel=1e-9
    )
    plain = default.step(3.0, [z]).track("L1")
    np.testing.assert_allclose(plain.state, x_r, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(plain.covariance, p_r, rtol=1e-9, atol=1e-12)
    # The two updates really differ (R₃ trusts the detection less on x, and correlates x, y).
    assert np.max(np.abs(x_own - x_r)) > 0.05
    assert np.max(np.abs(p_own - p_r)) > 0.05
