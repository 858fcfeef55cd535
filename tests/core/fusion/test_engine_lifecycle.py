"""Fused track life cycle when a sensor keeps missing a confirmed track: coasting, then the end.

One sensor ``s1`` (no field of view: it sees everything, P_D = 0.8) reports a
stationary object at the origin as track ``a`` at t = 0, 1, 2, 3 with
covariance P = diag(1, 0.25, 1, 0.25), then empty track lists at t = 4, 5, ...

Independent numbers (motion: constant velocity, q = 0.5, so after Δt the
position variance per axis is P_xx + Δt² P_vv + q Δt³/3; no cross terms since
P is diagonal; one sensor, so the fused estimate is that sensor's estimate):

- hit: S = predicted position block + reported block = (1 + 0.25 + 1/6 + 1) I,
  D = 0, ΔL = ln[P_D / (2π β_FT √|S|)] with β_FT = 1e-5; L₀ = ln(β_NT/β_FT) = 0;
- k-th miss (Δt = k from the last report at t = 3): the gate covariance of the
  engine is the fused position block predicted to the report time plus the
  newest estimate's own block, c_k I with c_k = 2 + 0.25 k² + k³/6; gate area
  A_G = π γ c_k, γ = −2 ln(1 − 0.999); P_k = Π [1 − (ρ_FA + ρ_NT) A_G];
- each miss adds ln(1 − 0.8) = ln 0.2; delete at L ≤ ln(β / (1 − α)).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core.fusion.config import SensorSpec
from core.fusion.engine import OVERDUE_REVISITS, SessionEngine
from core.fusion.reports import ReportedTrack, StepResult, TrackReport
from core.lifecycle import LifeCycleConfig, StatusReason, TrackStatus

from .engine_helpers import make_config

P_DETECT = 0.8
RHO_FA = RHO_NT = 1e-5
Q_MOTION = 0.5
COVARIANCE = np.diag([1.0, 0.25, 1.0, 0.25])
GATE = -2.0 * math.log(1.0 - 0.999)
LAST_HIT = 3


def management(score_margin: float | None) -> LifeCycleConfig:
    """The paper life cycle (gate emptiness from the first miss), the score ceiling at the
    confirm threshold + ``score_margin`` (None: the raw SPRT)."""
    paper = LifeCycleConfig.paper(
        2,
        false_target_density=RHO_FA,
        new_target_density=RHO_NT,
        true_deletion=1e-3,  # the worked numbers below: delete at ln(1e-3 / 0.999)
    )
    ceiling = None if score_margin is None else paper.confirm_threshold + score_margin
    return dataclasses.replace(paper, score_ceiling=ceiling)


def run_until_gone(score_margin: float | None) -> tuple[SessionEngine, list[StepResult]]:
    engine = SessionEngine(
        make_config(
            [SensorSpec("s1", p_detect=P_DETECT)], management=management(score_margin), q=Q_MOTION
        )
    )
    steps = []
    for t in range(LAST_HIT + 1):
        reported = ReportedTrack("a", np.zeros(4), COVARIANCE)
        steps.append(engine.apply(TrackReport("s1", float(t), (reported,))))
    t = LAST_HIT
    while engine.tracks and t < 40:
        t += 1
        steps.append(engine.apply(TrackReport("s1", float(t), ())))
    return engine, steps


def reference() -> tuple[float, list[float], list[float]]:
    """The hit increment, and per miss k = 1..20 the empty-gate probability and gate area."""
    s = 2.0 * 1.0 + 0.25 + Q_MOTION / 3.0  # per axis
    hit = math.log(P_DETECT / (2.0 * math.pi * RHO_FA * s))
    probability, probabilities, areas = 1.0, [], []
    for k in range(1, 21):
        area = math.pi * GATE * (2.0 + 0.25 * k**2 + Q_MOTION * k**3 / 3.0)
        probability *= max(0.0, 1.0 - (RHO_FA + RHO_NT) * area)
        probabilities.append(probability)
        areas.append(area)
    return hit, probabilities, areas


def first_below(values: list[float], bound: float) -> int:
    """1-based index of the first value below ``bound``."""
    return next(k for k, value in enumerate(values, start=1) if value < bound)


def status_of(step: StepResult) -> tuple[TrackStatus, StatusReason, float]:
    (track,) = step.tracks
    assert track.id == "F1"
    return track.status, track.reason, track.score


def test_reference_numbers_order_the_two_terminations() -> None:
    """Worked values: ΔL ≈ 8.57; gate emptiness after 11 misses; score after 9 (margin 0)."""
    hit, probabilities, _ = reference()
    thresholds = management(0.0)
    confirm, delete = thresholds.confirm_threshold, thresholds.delete_threshold
    miss = math.log(1.0 - P_DETECT)
    assert hit == pytest.approx(math.log(0.8 / (2 * math.pi * 1e-5 * (2.25 + 1 / 6))))
    assert hit > confirm  # one hit after the start confirms (L₀ = 0)
    assert first_below(probabilities, 0.5) == 11
    # Margin 0: the score sits at confirm; ⌈(confirm − delete) / |ln 0.2|⌉ = ⌈13.81 / 1.609⌉ = 9.
    assert math.ceil((confirm - delete) / -miss) == 9
    # No margin: 3 hits → 25.7; 11 misses → 25.7 − 17.7 = 8.0, never near delete.
    assert 3 * hit + 11 * miss > delete


@pytest.mark.parametrize(
    ("score_margin", "misses", "reason"),
    [(None, 11, StatusReason.GATE_EMPTINESS), (0.0, 9, StatusReason.SCORE_DELETED)],
)
def test_a_confirmed_track_the_sensor_keeps_missing_coasts_and_is_terminated(
    score_margin: float | None, misses: int, reason: StatusReason
) -> None:
    hit, probabilities, _ = reference()
    thresholds = management(score_margin)
    miss = math.log(1.0 - P_DETECT)
    engine, steps = run_until_gone(score_margin)
    assert engine.tracks == []
    assert len(steps) == LAST_HIT + 1 + misses
    assert status_of(steps[1])[:2] == (TrackStatus.CONFIRMED, StatusReason.SCORE_CONFIRMED)
    ceiling = math.inf if score_margin is None else thresholds.confirm_threshold + score_margin
    score = min(LAST_HIT * hit, ceiling)
    assert status_of(steps[LAST_HIT])[2] == pytest.approx(score, rel=1e-9)
    for k in range(1, misses + 1):
        status, why, value = status_of(steps[LAST_HIT + k])
        assert value == pytest.approx(score + k * miss, rel=1e-9)
        if k < misses and k <= OVERDUE_REVISITS:
            # s1 (revisit 1 s) is not overdue yet: still confirmed (§8.6), the miss counted
            assert (status, why) == (TrackStatus.CONFIRMED, StatusReason.SCORE_CONFIRMED)
        elif k < misses:
            assert (status, why) == (TrackStatus.COASTING, StatusReason.MISSED)
        else:
            assert (status, why) == (TrackStatus.TERMINATED, reason)
    if reason is StatusReason.SCORE_DELETED:
        # The gate was not empty enough yet: the score came first.
        assert probabilities[misses - 1] >= 0.5
        assert score + (misses - 1) * miss > thresholds.delete_threshold
    else:
        assert score + misses * miss > thresholds.delete_threshold


def test_the_empty_gate_probability_follows_the_reference_product() -> None:
    _, probabilities, _ = reference()
    engine = SessionEngine(
        make_config([SensorSpec("s1", p_detect=P_DETECT)], management=management(None), q=Q_MOTION)
    )
    for t in range(LAST_HIT + 1):
        engine.apply(TrackReport("s1", float(t), (ReportedTrack("a", np.zeros(4), COVARIANCE),)))
    assert engine.tracks[0].empty_gate_probability == 1.0
    for k in range(1, 11):
        engine.apply(TrackReport("s1", float(LAST_HIT + k), ()))
        (track,) = engine.tracks
        overdue = k > OVERDUE_REVISITS  # s1's revisit is 1 s
        assert track.status is (TrackStatus.COASTING if overdue else TrackStatus.CONFIRMED)
        assert track.empty_gate_probability == pytest.approx(probabilities[k - 1], rel=1e-9)
