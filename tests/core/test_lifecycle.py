"""Track score and gate-emptiness termination, worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core.errors import InvalidInput
from core.lifecycle import (
    CONFIRMED,
    TENTATIVE,
    Evidence,
    LifeCycleConfig,
    LifeState,
    ScoreModel,
    advance,
    gate_emptiness_factor,
    gate_volume,
    unit_ball_volume,
)


def test_thresholds_follow_wald() -> None:
    # α = 0.01, β = 0.1: confirm at ln(0.9 / 0.01) = ln 90, delete at ln(0.1 / 0.99).
    score = (
        LifeCycleConfig(false_confirmation=0.01, true_deletion=0.1)
        .for_dimension(2)
        .score_model(0.9)
    )
    assert score.confirm_threshold == pytest.approx(4.499809670330265)
    assert score.delete_threshold == pytest.approx(-2.2925347571405443)
    assert score.confirm_threshold > 0.0 > score.delete_threshold


def test_initial_score_and_increments() -> None:
    score = LifeCycleConfig(false_target_density=1e-4, new_target_density=1e-5).score_model(0.9)
    assert score.initial == pytest.approx(math.log(0.1))
    assert score.miss_increment == pytest.approx(math.log(0.1))
    # q = 2, |S| = 4 (√|S| = 2), D = 1:
    # ΔL = ln(0.9 / (2π · 1e-4 · 2)) − 0.5 = ln(716.197...) − 0.5 = 6.57395... − 0.5.
    delta = score.hit_increment(np.array([1.0]), np.array([math.log(4.0)]), dim=2)
    assert delta[0] == pytest.approx(math.log(0.9 / (2 * math.pi * 1e-4 * 2.0)) - 0.5)
    assert delta[0] == pytest.approx(6.0739, abs=1e-4)


def test_unit_ball_volumes() -> None:
    assert_allclose([unit_ball_volume(q) for q in (1, 2, 3)], [2.0, math.pi, 4 * math.pi / 3])


def test_gate_emptiness_probability() -> None:
    # q = 2, γ = 9 (3σ), |S| = 16: A_G = π · 9 · 4 = 36π ≈ 113.1 m².
    volume = gate_volume(9.0, np.array([math.log(16.0)]), dim=2)
    assert volume[0] == pytest.approx(36 * math.pi)
    factor = gate_emptiness_factor(2e-3, 1e-3, volume)
    assert factor[0] == pytest.approx(1 - 3e-3 * 36 * math.pi)
    # Two such scans: P = 0.6607² ≈ 0.4365 < 0.5 → terminate on the second.
    assert factor[0] > 0.5 > factor[0] ** 2
    # A huge gate clips at 0 instead of going negative.
    assert gate_emptiness_factor(1.0, 1.0, np.array([10.0]))[0] == 0.0


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("p_detect", 1.0, "p_detect must be in \\(0, 1\\)"),
        ("false_confirmation", 0.0, "false_confirmation must be in \\(0, 1\\)"),
        ("false_target_density", -1.0, "false_target_density must be a positive number"),
        ("new_target_density", float("nan"), "new_target_density must be a positive number"),
    ],
)
def test_invalid_score_parameters(field: str, value: float, message: str) -> None:
    with pytest.raises(InvalidInput, match=message):
        ScoreModel(
            **{
                "p_detect": 0.9,
                "false_target_density": 1e-6,
                "new_target_density": 1e-6,
                "false_confirmation": 1e-3,
                "true_deletion": 1e-2,
                field: value,
            }
        )


def test_a_two_point_start_scores_both_detections() -> None:
    """L₀ + ln[P_D N(z₁ − z₀; 0, S₂) / β_FT], the density by scipy (Blackman & Popoli p. 330)."""
    from scipy.stats import multivariate_normal

    model = LifeCycleConfig(false_target_density=3e-5, new_target_density=1e-6).score_model(0.9)
    pair = np.array([[2.0, 0.0], [1.0, 3.0]]) @ np.array([[2.0, 0.0], [1.0, 3.0]]).T
    displacement = np.array([[0.5, -1.0], [4.0, 2.0]])
    expected = [
        math.log(1e-6 / 3e-5) + math.log(0.9 * multivariate_normal(np.zeros(2), pair).pdf(d) / 3e-5)
        for d in displacement
    ]
    np.testing.assert_allclose(model.two_point_initial(displacement, pair), expected, rtol=1e-12)


def test_the_default_ceiling_restarts_the_test_of_established_tracks_only() -> None:
    """Ceiling 0 (the default): a tentative track is scored above it up to the confirm
    threshold; the scan that confirms it puts it under the ceiling, as every established track.
    (min_points off: this is the score's own confirmation.)"""
    config = LifeCycleConfig(min_points=None)
    assert config.ceiling == 0.0
    state = LifeState.new(3, 5.0, hits=2)
    state = LifeState(
        np.array([TENTATIVE, TENTATIVE, CONFIRMED]),
        state.reason,
        state.score,
        state.hits,
        state.empty_gate,
        state.phantom_since,
        state.misses,
    )
    evidence = Evidence(
        time=1.0,
        detected=np.array([True, True, True]),
        hit_increment=np.array([1.0, 3.0, 3.0]),
        seen=np.ones(3, dtype=bool),
        miss_increment=math.log(0.1),
        gate_log_det=np.zeros(3),
        gate_dim=2,
        visibility=np.zeros(3, dtype=np.int64),
        occluded=np.zeros(3, dtype=bool),
    )
    after, confirmed = advance(config, state, evidence)
    # 5 + 1 = 6 stays tentative above the ceiling; 5 + 3 ≥ 6.9 confirms, then 0
    np.testing.assert_allclose(after.score, [6.0, 0.0, 0.0])
    assert confirmed.tolist() == [False, True, False]
    with pytest.raises(InvalidInput):
        LifeCycleConfig(score_ceiling=-7.0)  # under the delete threshold −6.9068


def test_a_local_tracks_report_is_scored_against_its_sensors_false_detections() -> None:
    """docs/algorithms.md §8.1: the fused layer's β_FT for a report is its own (one per km³
    in 3-D), or the source sensor's β_FT where that is smaller."""
    layer = LifeCycleConfig().for_dimension(3)
    # a 3-D radar's local track 12 s after its last report: √|S| = 400³ m³, D = 3
    distance, log_det = np.array([3.0]), np.array([6.0 * math.log(400.0)])
    by_hand = {
        density: math.log(0.9 / ((2.0 * math.pi) ** 1.5 * density * 400.0**3)) - 1.5
        for density in (1e-9, 8.5e-15)
    }
    assert by_hand[1e-9] < 0.0 < by_hand[8.5e-15]  # the layer's own density: a true hit lowers L
    for source, expected in ((None, 1e-9), (1e-6, 1e-9), (8.5e-15, 8.5e-15)):
        score = layer.report_score(0.9, source)
        assert score.false_target_density == expected
        assert score.hit_increment(distance, log_det, 3)[0] == pytest.approx(by_hand[expected])
