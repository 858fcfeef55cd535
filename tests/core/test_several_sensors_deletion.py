"""docs/algorithms.md §8.14: an established track that several sensors look at is deleted
when its run of misses is as rare per second as its slowest sensor's alone."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.lifecycle import (
    COASTING,
    TERMINATED,
    Evidence,
    LifeCycleConfig,
    LifeState,
    advance,
    misses_to_delete,
    several_sensors_shift,
)

BETA = ALPHA = 1e-3
BASE = math.log(BETA / (1.0 - ALPHA))  # −6.9068
MISS = math.log(1.0 - 0.9)  # ln(1 − P_D) at P_D 0.9


def test_the_shift_is_minus_the_log_of_the_slowest_revisit_over_each_sensors() -> None:
    inf = math.inf
    revisits = np.array(
        [
            [4.0, 5.0, 12.0],  # Σ 12/T_i = 3 + 2.4 + 1 = 6.4
            [4.0, inf, inf],  # one sensor: unchanged
            [8.0, 8.0, inf],  # two of one revisit: ln 2
            [inf, inf, inf],  # none
        ]
    )
    np.testing.assert_allclose(
        several_sensors_shift(revisits), [-math.log(6.4), 0.0, -math.log(2.0), 0.0], atol=1e-15
    )
    # three radars of 4, 5 and 12 s at P_D 0.9: 4 misses instead of 3
    drop = -BASE + math.log(6.4)  # 8.763
    assert misses_to_delete(np.array([-BASE, drop]), MISS).tolist() == [3, 4]


def _coasting(scores: list[float], misses: list[int]) -> LifeState:
    state = LifeState.new(len(scores), np.array(scores), hits=10)
    return LifeState(
        np.full(len(scores), COASTING),
        state.reason,
        state.score,
        state.hits,
        state.empty_gate,
        state.phantom_since,
        np.array(misses),
    )


def test_a_third_miss_does_not_end_a_track_three_radars_look_at() -> None:
    """Hand-worked: threshold −6.9068 − ln 6.4 = −8.7631. Rows: (a) 2 misses then a third,
    −6.908, three radars looking: coasts, and its empty gate (A_G·ρ ≥ 1) does not end it
    before a fourth miss; (b) the same alone: deleted (−6.908 ≤ −6.907); (c) a fourth miss,
    −9.210: deleted; (d) the same vouched for by another sensor (§8.9): held at −8.7631."""
    config = LifeCycleConfig()
    shift = -math.log(6.4)
    state = _coasting([2 * MISS, 2 * MISS, 3 * MISS, 3 * MISS], [2, 2, 3, 3])
    evidence = Evidence(
        time=10.0,
        detected=np.zeros(4, dtype=bool),
        hit_increment=np.zeros(4),
        seen=np.ones(4, dtype=bool),
        miss_increment=MISS,
        gate_log_det=np.full(4, 60.0),  # a gate of e^30 m³: empty-gate factor 0
        gate_dim=3,
        visibility=np.zeros(4, dtype=np.int64),
        occluded=np.zeros(4, dtype=bool),
        densities=(1e-9, 1e-9),
        vouched=np.array([False, False, False, True]),
        deletion_shift=np.array([shift, 0.0, shift, shift]),
    )
    after, _ = advance(config, state, evidence)
    assert after.status.tolist() == [COASTING, TERMINATED, TERMINATED, COASTING]
    assert after.score == pytest.approx([3 * MISS, 3 * MISS, 4 * MISS, BASE + shift], abs=1e-12)
    assert after.misses.tolist() == [3, 3, 4, 4]
    assert after.empty_gate[0] == 0.0  # the gate test would have fired at the third miss
    # (a)'s fourth miss ends it: by its score
    again = advance(config, after, evidence)[0]
    assert again.status[0] == TERMINATED


def test_false_deletions_per_second_are_at_most_the_slowest_sensors_alone() -> None:
    """Monte Carlo: radars of 4, 5 and 12 s (offsets 0, 1.3, 2.7 s) at P_D 0.9 see a true
    target for 2·10⁶ s; a run of k misses in a row over their merged scans deletes it.
    With k = 3 (the single sensor's run) it happens ~10⁻³ per merged scan, six times the
    rate β/T_max of the 12 s radar alone; with the §8.14 threshold's k = 4, below it."""
    rng = np.random.default_rng(7)
    span = 2.0e6
    times = np.concatenate(
        [
            np.arange(offset, span, period)
            for period, offset in ((4.0, 0.0), (5.0, 1.3), (12.0, 2.7))
        ]
    )
    missed = rng.random(len(times)) >= 0.9  # the merged order does not matter for iid draws
    missed = missed[np.argsort(times, kind="stable")]

    def deletions(k: int) -> int:
        run = 0
        count = 0
        for m in missed.tolist():
            run = run + 1 if m else 0
            if run == k:
                count += 1
                run = 0  # a new track, a new run
        return count

    k = int(misses_to_delete(np.array(-BASE + math.log(6.4)), MISS))
    assert k == 4
    allowed = BETA / 12.0 * span  # the 12 s radar alone: β per scan
    assert deletions(3) > 3.0 * allowed
    assert deletions(4) < allowed


def test_the_shift_stays_finite_when_the_revisits_ratio_overflows() -> None:
    """A slow sensor's revisit of 1e300 s and a fast one's of 1e-10 s (finite scan times the
    tracker takes): Σ T_max/T_i = 1e310 + 1 overflows a float, but its log does not:
    −ln(1e300/1e-10 + 1) = −310 ln 10 (to 1e-310 relative), worked with math.log of each
    factor. The threshold, and the misses it tolerates, are finite (no ∞ cast to an int)."""
    revisits = np.array([[1e-10, 1e300]])
    expected = -(math.log(1e300) - math.log(1e-10))  # ln(1 + 1e-310) is 0 in float
    shift = several_sensors_shift(revisits)
    assert np.all(np.isfinite(shift))
    assert shift[0] == pytest.approx(expected, rel=1e-12)
    drop = -BASE - shift  # 6.9068 + 713.8
    assert misses_to_delete(drop, MISS).tolist() == [math.ceil((-BASE - expected) / -MISS)]
