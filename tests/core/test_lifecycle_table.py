"""The shared life cycle (``core.lifecycle``) row by row: [HZ] §5.1 and every transition.

One vectorised call of :func:`advance` over one track per case, each case's
expected status, reason and numbers worked by hand below (α = β = 1e-3:
confirm = ln(0.999/0.001) = 6.9068, delete = −6.9068; P_D = 0.9: a miss adds
ln 0.1 = −2.3026; ρ_FA = ρ_NT = 1e-6; γ = χ²₂(0.999) = −2 ln 0.001 = 13.8155;
A_G = π γ √|S|; phantom lifetime 500 m / 1 m/s = 500 s; time 100 s).
Then :func:`hand_over`, and the tracker and the engine on the same evidence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import ReportedTrack, TrackReport
from core.geometry import PolygonView, Sector, Visibility
from core.lifecycle import (
    REASONS,
    STATUSES,
    Evidence,
    LifeCycleConfig,
    LifeState,
    StatusReason,
    TrackStatus,
    advance,
    hand_over,
    reason_code,
)
from core.tracking import ModelBank
from core.tracking.config import LocalTrackerConfig
from core.tracking.tracker import LocalTracker

T, N, C, P, X = (
    TrackStatus.TENTATIVE,
    TrackStatus.CONFIRMED,
    TrackStatus.COASTING,
    TrackStatus.PHANTOM,
    TrackStatus.TERMINATED,
)
R_ = StatusReason
CONFIG = LifeCycleConfig.paper(2, true_deletion=1e-3, min_points=3)
"""The paper life cycle (ceiling at the confirm threshold, gate emptiness from the first
miss, no start exempt); the defaults' own rules are checked after the table."""
CONFIRM = math.log(0.999 / 0.001)
DELETE = math.log(0.001 / 0.999)
MISS = math.log(0.1)
GAMMA = -2.0 * math.log(0.001)
TIME = 100.0
SMALL_GATE = math.log(100.0)  # √|S| = 10: A_G = 434.03, factor 1 − 2e-6 · 434.03 = 0.999132
LARGE_GATE = math.log(1e8)  # √|S| = 1e4: A_G = 434 025, factor 0.131950
VISIBLE, BLIND, OUT = (
    int(Visibility.VISIBLE),
    int(Visibility.BLIND_ZONE),
    int(Visibility.OUT_OF_RANGE),
)


@dataclass(frozen=True)
class Case:
    name: str
    status: TrackStatus
    reason: StatusReason
    score: float
    expected: tuple[TrackStatus, StatusReason]
    expected_score: float
    hits: int = 1
    empty_gate: float = 1.0
    phantom_since: float = math.nan
    detected: bool = False
    increment: float = 0.0
    seen: bool = False
    gate: float = SMALL_GATE
    where: int = VISIBLE
    occluded: bool = False
    sensors: int = 1
    expected_empty_gate: float | None = None
    expected_since: float | None = None
    misses: int = 0


def factor(log_det: float) -> float:
    return 1.0 - 2e-6 * math.pi * GAMMA * math.exp(0.5 * log_det)


CASES = [
    Case(
        "hit confirms by score",
        T,
        R_.INITIATED,
        0.0,
        (N, R_.SCORE_CONFIRMED),
        CONFIRM,
        detected=True,
        increment=7.0,
        seen=True,
    ),
    Case(
        "hit below the threshold",
        T,
        R_.INITIATED,
        0.0,
        (T, R_.INITIATED),
        3.0,
        detected=True,
        increment=3.0,
        seen=True,
    ),
    Case(
        "min_points hits confirm",
        T,
        R_.INITIATED,
        0.0,
        (N, R_.MIN_POINTS),
        1.0,
        hits=2,
        detected=True,
        increment=1.0,
        seen=True,
    ),
    Case(
        "min_points hits, score below 0: still tentative (more likely false)",
        T,
        R_.INITIATED,
        -3.0,
        (T, R_.INITIATED),
        -2.0,
        hits=2,
        detected=True,
        increment=1.0,
        seen=True,
    ),
    Case("a second sensor confirms", T, R_.INITIATED, 0.0, (N, R_.SECOND_SENSOR), 0.0, sensors=2),
    Case(
        "unseen: nothing happens", N, R_.SCORE_CONFIRMED, CONFIRM, (N, R_.SCORE_CONFIRMED), CONFIRM
    ),
    Case(
        "confirmed miss coasts",
        N,
        R_.SCORE_CONFIRMED,
        CONFIRM,
        (C, R_.MISSED),
        CONFIRM + MISS,
        seen=True,
        expected_empty_gate=factor(SMALL_GATE),
    ),
    Case(
        "coasting hit reacquires",
        C,
        R_.MISSED,
        2.0,
        (N, R_.REACQUIRED),
        4.0,
        empty_gate=0.7,
        detected=True,
        increment=2.0,
        seen=True,
        expected_empty_gate=1.0,
    ),
    Case(
        "gate emptiness",
        C,
        R_.MISSED,
        4.6,
        (X, R_.GATE_EMPTINESS),
        4.6 + MISS,
        empty_gate=0.6,
        seen=True,
        gate=LARGE_GATE,
        expected_empty_gate=0.6 * factor(LARGE_GATE),
    ),
    Case(
        "score deletion",
        C,
        R_.MISSED,
        -5.0,
        (X, R_.SCORE_DELETED),
        -5.0 + MISS,
        seen=True,
        expected_empty_gate=factor(SMALL_GATE),
    ),
    Case("out of range", N, R_.SCORE_CONFIRMED, CONFIRM, (X, R_.OUT_OF_RANGE), CONFIRM, where=OUT),
    Case(
        "out of range before expiry",
        P,
        R_.BLIND_ZONE,
        1.0,
        (X, R_.OUT_OF_RANGE),
        1.0,
        phantom_since=-1000.0,
        where=OUT,
    ),
    Case(
        "phantom expires",
        P,
        R_.BLIND_ZONE,
        1.0,
        (X, R_.PHANTOM_EXPIRED),
        1.0,
        phantom_since=TIME - 501.0,
    ),
    Case(
        "phantom stays, never missed",
        P,
        R_.BLIND_ZONE,
        1.0,
        (P, R_.BLIND_ZONE),
        1.0,
        phantom_since=50.0,
        seen=True,
        where=BLIND,
        expected_since=50.0,
    ),
    Case(
        "blind zone: phantom",
        N,
        R_.SCORE_CONFIRMED,
        CONFIRM,
        (P, R_.BLIND_ZONE),
        CONFIRM,
        where=BLIND,
        expected_since=TIME,
    ),
    Case("blind zone: tentative ends", T, R_.INITIATED, 0.0, (X, R_.BLIND_ZONE), 0.0, where=BLIND),
    Case(
        "blind zone but detected",
        N,
        R_.SCORE_CONFIRMED,
        CONFIRM,
        (N, R_.SCORE_CONFIRMED),
        CONFIRM,
        detected=True,
        increment=1.0,
        seen=True,
        where=BLIND,
    ),
    Case(
        "occluded: phantom",
        C,
        R_.MISSED,
        3.0,
        (P, R_.OCCLUDED),
        3.0,
        occluded=True,
        expected_since=TIME,
    ),
    Case("occluded: tentative ends", T, R_.INITIATED, 0.0, (X, R_.OCCLUDED), 0.0, occluded=True),
]


def evidence_of(cases: list[Case]) -> Evidence:
    return Evidence(
        time=TIME,
        detected=np.array([c.detected for c in cases]),
        hit_increment=np.array([c.increment for c in cases]),
        seen=np.array([c.seen for c in cases]),
        miss_increment=MISS,
        gate_log_det=np.array([c.gate for c in cases]),
        gate_dim=2,
        visibility=np.array([c.where for c in cases], dtype=np.int64),
        occluded=np.array([c.occluded for c in cases]),
        sensors=np.array([c.sensors for c in cases], dtype=np.int64),
    )


def state_of(cases: list[Case]) -> LifeState:
    return LifeState(
        status=np.array([STATUSES.index(c.status) for c in cases], dtype=np.int64),
        reason=np.array([REASONS.index(c.reason) for c in cases], dtype=np.int64),
        score=np.array([c.score for c in cases]),
        hits=np.array([c.hits for c in cases], dtype=np.int64),
        empty_gate=np.array([c.empty_gate for c in cases]),
        phantom_since=np.array([c.phantom_since for c in cases]),
        misses=np.array([c.misses for c in cases], dtype=np.int64),
    )


def test_every_row_of_the_table_at_once() -> None:
    before = state_of(CASES)
    after, confirmed = advance(CONFIG, before, evidence_of(CASES))
    assert CONFIG.confirm_threshold == pytest.approx(CONFIRM)
    assert CONFIG.delete_threshold == pytest.approx(DELETE)
    for k, case in enumerate(CASES):
        got = (STATUSES[after.status[k]], REASONS[after.reason[k]])
        assert got == case.expected, case.name
        assert after.score[k] == pytest.approx(case.expected_score, abs=1e-12), case.name
        assert after.hits[k] == case.hits + int(case.detected), case.name
        if case.expected_empty_gate is not None:
            assert after.empty_gate[k] == pytest.approx(case.expected_empty_gate, rel=1e-12)
        if case.expected_since is None:
            assert math.isnan(after.phantom_since[k]) or case.status is P, case.name
        else:
            assert after.phantom_since[k] == case.expected_since, case.name
        was_tentative = case.status is T
        assert confirmed[k] == (was_tentative and case.expected[0] is N), case.name
    # The input state is never changed in place.
    assert before.status.tolist() == [STATUSES.index(c.status) for c in CASES]
    # Every status and every reason the life cycle can give was reached once.
    reached = {(STATUSES[s], REASONS[r]) for s, r in zip(after.status, after.reason, strict=True)}
    assert {reason for _, reason in reached} | {
        R_.MERGED_INTO_PHANTOM,
        R_.DUPLICATE,
        R_.LOCAL_CONFIRMED,
    } == set(StatusReason)


def test_with_phantoms_off_a_hidden_track_is_not_a_phantom() -> None:
    cases = [c for c in CASES if c.name in ("blind zone: phantom", "occluded: phantom")]
    after, _ = advance(
        LifeCycleConfig.paper(2, true_deletion=1e-3, phantoms=False),
        state_of(cases),
        evidence_of(cases),
    )
    assert after.statuses() == [N, C]
    assert after.reasons() == [R_.SCORE_CONFIRMED, R_.MISSED]


def test_termination_probability_zero_turns_gate_emptiness_off() -> None:
    (case,) = [c for c in CASES if c.name == "gate emptiness"]
    off = LifeCycleConfig.paper(2, true_deletion=1e-3, termination_probability=0.0)
    after, _ = advance(off, state_of([case]), evidence_of([case]))
    assert (after.statuses(), after.reasons()) == ([C], [R_.MISSED])
    assert after.empty_gate[0] == pytest.approx(0.6 * factor(LARGE_GATE))


def test_the_defaults_keep_a_start_until_its_third_hit_and_a_track_through_two_misses() -> None:
    """Defaults (§8.1, §8.3): a tentative track hit with ≤ 3 hits is not deleted by its score
    (its next detection tests it), one with 4 is; a coasting track whose gate is all but
    sure to hold clutter survives its 1st and 2nd miss in a row and ends at its 3rd."""
    config = LifeCycleConfig().for_dimension(2)
    start = dict(status=T, reason=R_.INITIATED, detected=True, seen=True, increment=-2.0)
    lost = dict(status=C, reason=R_.MISSED, score=0.0, seen=True, gate=LARGE_GATE)
    cases = [
        Case(
            "start, 2nd hit, weak",
            score=-6.0,
            hits=1,
            expected=(T, R_.INITIATED),
            expected_score=-8.0,
            **start,
        ),
        Case(
            "start, 3rd hit, weak",
            score=-6.0,
            hits=2,
            expected=(T, R_.INITIATED),
            expected_score=-8.0,
            **start,
        ),
        Case(
            "tentative, 4th hit, weak",
            score=-6.0,
            hits=3,
            expected=(X, R_.SCORE_DELETED),
            expected_score=-8.0,
            **start,
        ),
        Case(
            "1st miss, large gate",
            expected=(C, R_.MISSED),
            expected_score=MISS,
            misses=0,
            empty_gate=1.0,
            **lost,
        ),
        Case(
            "2nd miss, large gate",
            expected=(C, R_.MISSED),
            expected_score=MISS,
            misses=1,
            empty_gate=0.13,
            **lost,
        ),
        Case(
            "3rd miss, large gate",
            expected=(X, R_.GATE_EMPTINESS),
            expected_score=MISS,
            misses=2,
            empty_gate=0.13,
            **lost,
        ),
    ]
    after, _ = advance(config, state_of(cases), evidence_of(cases))
    for k, case in enumerate(cases):
        assert (STATUSES[after.status[k]], REASONS[after.reason[k]]) == case.expected, case.name
        assert after.score[k] == pytest.approx(case.expected_score), case.name
    assert after.misses.tolist() == [0, 0, 0, 1, 2, 3]
    # the 1st miss's empty-gate probability is already under 0.5: [HZ] alone would end it
    assert after.empty_gate[3] == pytest.approx(factor(LARGE_GATE)) and factor(LARGE_GATE) < 0.5


def test_new_tracks_are_tentative_and_initiated() -> None:
    fresh = LifeState.new(2, score=0.5, hits=2)
    assert fresh.statuses() == [T, T] and fresh.reasons() == [R_.INITIATED] * 2
    assert fresh.score.tolist() == [0.5, 0.5] and fresh.hits.tolist() == [2, 2]


def test_hand_over_to_a_phantom_and_a_duplicate_merge() -> None:
    """Keepers 0 (phantom) and 1 (confirmed); newcomers 2 and 3 (just confirmed, tentative)."""
    state = LifeState(
        status=np.array([STATUSES.index(s) for s in (P, N, N, T)], dtype=np.int64),
        reason=np.array(
            [reason_code(r) for r in (R_.BLIND_ZONE, R_.MISSED, R_.SCORE_CONFIRMED, R_.INITIATED)],
            dtype=np.int64,
        ),
        score=np.array([1.0, 5.0, 6.0, 2.0]),
        hits=np.array([10, 20, 3, 1], dtype=np.int64),
        empty_gate=np.array([0.8, 0.9, 1.0, 1.0]),
        phantom_since=np.array([40.0, np.nan, np.nan, np.nan]),
        misses=np.array([0, 2, 0, 0], dtype=np.int64),
    )
    phantom = hand_over(state, np.array([0]), np.array([2]), R_.MERGED_INTO_PHANTOM)
    assert phantom.statuses()[:3] == [N, N, X]
    assert phantom.reasons()[:3] == [R_.REACQUIRED, R_.MISSED, R_.MERGED_INTO_PHANTOM]
    assert phantom.score[0] == 6.0 and phantom.hits[0] == 13
    assert phantom.empty_gate[0] == 1.0 and math.isnan(phantom.phantom_since[0])
    assert phantom.misses[0] == 0
    duplicate = hand_over(state, np.array([1]), np.array([3]), R_.DUPLICATE)
    assert duplicate.statuses()[1::2] == [N, X]
    assert duplicate.reasons()[1::2] == [R_.MISSED, R_.DUPLICATE]  # a confirmed keeper stays as is
    assert duplicate.score[1] == 5.0 and duplicate.hits[1] == 21
    assert duplicate.misses[1] == 0  # the keeper was just reported
    assert state.statuses() == [P, N, N, T]  # not changed in place


# ----------------------------------------------- tracker and engine, same evidence
FOV = PolygonView(((-100.0, -100.0), (100.0, -100.0), (100.0, 100.0), (-100.0, 100.0)))
REGION = PolygonView(((-100.0, -100.0), (400.0, -100.0), (400.0, 100.0), (-100.0, 100.0)))
LIFE = LifeCycleConfig.paper(2, phantom_max_distance=50.0, phantom_min_speed=10.0)  # 5 s phantoms
BANK = ModelBank.from_config(
    {
        "time_interval": 1.0,
        "measurement": {"variance": 1.0},
        "models": [{"kind": "constant_velocity", "name": "cv", "noise_intensity": 0.01}],
    }
)


def positions(start: float, speed: float, scans: int) -> list[tuple[float, float]]:
    return [(start + speed * t, 0.0) for t in range(scans)]


def detected_at(point: tuple[float, float], t: int, missed: range) -> bool:
    return -100.0 < point[0] < 100.0 and t not in missed


def tracker_statuses(
    truth: list[tuple[float, float]], missed: range
) -> list[tuple[TrackStatus, StatusReason] | None]:
    tracker = LocalTracker(
        LocalTrackerConfig.paper(
            bank=BANK, fields_of_view={"radar": FOV}, region=REGION, life_cycle=LIFE
        )
    )
    out: list[tuple[TrackStatus, StatusReason] | None] = []
    for t, point in enumerate(truth):
        z = [point] if detected_at(point, t, missed) else np.zeros((0, 2))
        step = tracker.step(float(t), z)
        tracks = [track for track in step.tracks if track.id == "L1"]
        out.append((tracks[0].status, tracks[0].reason) if tracks else None)
    return out


def engine_statuses(
    truth: list[tuple[float, float]], speed: float, missed: range
) -> list[tuple[TrackStatus, StatusReason] | None]:
    engine = SessionEngine(
        FusionConfig(
            motion=MotionModel(StateLayout(4, (0, 2), (1, 3)), q=0.01),
            sensors=(SensorSpec("radar", p_detect=0.9, fov=FOV),),
            region=REGION,
            management=LIFE,
        )
    )
    covariance = np.diag([1.0, 1.0, 1.0, 1.0])
    out: list[tuple[TrackStatus, StatusReason] | None] = []
    for t, point in enumerate(truth):
        tracks = (
            (ReportedTrack("r1", np.array([point[0], speed, point[1], 0.0]), covariance),)
            if detected_at(point, t, missed)
            else ()
        )
        step = engine.apply(TrackReport("radar", float(t), tracks))
        found = [track for track in step.tracks if track.id == "F1"]
        out.append((found[0].status, found[0].reason) if found else None)
    return out


@pytest.mark.parametrize(
    ("start", "missed", "ending"),
    [
        (-95.0, range(0), (X, R_.PHANTOM_EXPIRED)),  # leaves the field of view at 20 s
        (-95.0, range(6, 30), (X, R_.SCORE_DELETED)),  # undetected from 6 s, inside the view
    ],
)
def test_the_tracker_and_the_engine_reach_the_same_statuses_on_the_same_evidence(
    start: float, missed: range, ending: tuple[TrackStatus, StatusReason]
) -> None:
    """One target at 10 m/s, exact positions; the tracker gets detections, the engine the
    same positions as a sensor's track list. From the scan where the tracker confirms (its
    two-point initiation needs one scan more), both give every scan the same status and
    reason — but for the fused track's status while its only source is not overdue
    (docs/algorithms.md §8.6: 2.5 revisits, so it stays confirmed at 6, 7 and 8 s where
    the tracker coasts) — and end at the same scan for the same reason."""
    truth = positions(start, 10.0, 30)
    local = tracker_statuses(truth, missed)
    fused = engine_statuses(truth, 10.0, missed)
    first = local.index((N, R_.SCORE_CONFIRMED))
    assert first == 2 and fused[1] == (N, R_.SCORE_CONFIRMED)
    expected = list(local)
    for t in (t for t in missed if t - (missed.start - 1) <= 2.5):
        assert local[t] == (C, R_.MISSED)
        expected[t] = (N, R_.SCORE_CONFIRMED)
    assert fused[first:] == expected[first:]
    end = local.index(ending)
    assert end == fused.index(ending)
    assert set(local[end + 1 :]) == {None}
    if ending[1] is R_.PHANTOM_EXPIRED:  # phantom from 20 s (x = 105 m) until 26 s (> 5 s)
        assert local[19] == (N, R_.SCORE_CONFIRMED) and local[20] == (P, R_.BLIND_ZONE)
        assert end == 26
    else:  # coasting from 6 s; ⌈(confirm − delete) / ln 10⌉ = 6 misses: deleted at 11 s
        assert local[6] == (C, R_.MISSED) and end == 11


def test_the_tracker_and_the_engine_both_make_an_occluded_track_a_phantom() -> None:
    """Two still targets on a sector's axis, at 50 m and 100 m; from 3 s only the near one is
    detected. With occlusion radius 2 m the near one hides the far one ([HZ] §2.1): both
    layers make it a phantom (``occluded``) at 3 s and end it at 9 s (phantom lifetime 5 s),
    scan by scan alike once the tracker has confirmed it (2 s)."""
    view = Sector((0.0, 0.0), heading_deg=90.0, half_angle_deg=30.0, range_min=0.0, range_max=500.0)
    life = LifeCycleConfig.paper(
        2, occlusion_radius=2.0, phantom_max_distance=50.0, phantom_min_speed=10.0
    )
    near, far = (0.0, 50.0), (0.0, 100.0)
    seen_far = range(3)
    tracker = LocalTracker(
        LocalTrackerConfig.paper(bank=BANK, fields_of_view={"radar": view}, life_cycle=life)
    )
    engine = SessionEngine(
        FusionConfig(
            motion=MotionModel(StateLayout(4, (0, 2), (1, 3)), q=0.01),
            sensors=(SensorSpec("radar", p_detect=0.9, fov=view),),
            management=life,
        )
    )
    local, fused = [], []
    for t in range(12):
        points = [near, far] if t in seen_far else [near]
        step = tracker.step(float(t), points)
        local.append(next(((k.status, k.reason) for k in step.tracks if k.id == "L2"), None))
        report = TrackReport(
            "radar",
            float(t),
            tuple(
                ReportedTrack(f"r{k}", np.array([x, 0.0, y, 0.0]), np.eye(4))
                for k, (x, y) in enumerate(points)
            ),
        )
        result = engine.apply(report)
        fused.append(next(((k.status, k.reason) for k in result.tracks if k.id == "F2"), None))
    assert local[2] == fused[2] == (N, R_.SCORE_CONFIRMED)
    assert local[2:] == fused[2:]
    assert local[3] == (P, R_.OCCLUDED) and local.index((X, R_.PHANTOM_EXPIRED)) == 9
