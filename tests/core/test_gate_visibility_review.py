"""Review of §8.16 (the probability that a sensor sees a track) joined to §8.14 (the
several-sensor deletion shift): each test is worked by hand, or against Monte Carlo over the
geometry's own ``contains``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.geometry import Coverage, PolygonView, Sector
from core.lifecycle import COASTING, Evidence, LifeCycleConfig, LifeState, advance
from core.pipeline.evidence import look
from core.pipeline.visibility import inside_probability

BASE = math.log(1e-3 / (1.0 - 1e-3))  # the default delete threshold, −6.9068
MISS = math.log(1.0 - 0.9)  # a full miss at P_D 0.9, −2.3026
SHIFT = -math.log(2.0)  # two sensors of one revisit (§8.14)


def _coasting(count: int, score: float, misses: int) -> LifeState:
    state = LifeState.new(count, score, hits=10)
    return LifeState(
        np.full(count, COASTING),
        state.reason,
        state.score,
        state.hits,
        state.empty_gate,
        state.phantom_since,
        np.full(count, misses),
    )


@pytest.mark.parametrize("other", [-math.inf, math.log(0.05 * (1.0 - 0.9))])
def test_the_gate_test_waits_in_full_misses_whatever_another_row_scores(other: float) -> None:
    """Hand-worked (§8.14): two radars of one revisit lower the threshold by ln 2 to −7.600;
    from the ceiling 0 that is ⌈7.600 / 2.3026⌉ = 4 full misses instead of ⌈6.907 / 2.3026⌉
    = 3, so a coasting track (row 0) missed a third time, its gate empty, is not ended by
    gate emptiness before its fourth miss. Row 1 is another track the step's sensor does not
    see: out of the region (p_region 0, ΔL ln 0 = −inf, as ``look`` scores it) or at its
    edge (p = p_region = 0.05: ln(0.05 · 0.1) = −5.30). Its ΔL is never added to any score,
    and it must not change row 0's wait."""
    assert math.ceil((-BASE - SHIFT) / -MISS) - math.ceil(-BASE / -MISS) == 1
    state = _coasting(2, 2 * MISS, 2)
    evidence = Evidence(
        time=10.0,
        detected=np.zeros(2, dtype=bool),
        hit_increment=np.zeros(2),
        seen=np.array([True, False]),
        miss_increment=np.array([MISS, other]),
        gate_log_det=np.full(2, 60.0),  # a gate of e^30 m³: empty-gate factor 0
        gate_dim=3,
        visibility=np.zeros(2, dtype=np.int64),
        occluded=np.zeros(2, dtype=bool),
        densities=(1e-9, 1e-9),
        deletion_shift=np.array([SHIFT, SHIFT]),
        full_miss_increment=MISS,
    )
    after, _ = advance(LifeCycleConfig(), state, evidence)
    assert after.empty_gate[0] == 0.0  # the gate test would fire at this miss
    assert after.misses[0] == 3
    assert after.status[0] == COASTING
    assert after.score[0] == pytest.approx(3 * MISS, abs=1e-12)  # −6.908 > −7.600


def test_look_scores_a_row_out_of_the_region_minus_infinity_unseen() -> None:
    """What makes row 1 above: a track far outside the explicit region (50 σ) is not seen and
    its p_region is 0, its ΔL ln(0 − 0) = −inf."""
    square = PolygonView(((0.0, 0.0), (1000.0, 0.0), (1000.0, 1000.0), (0.0, 1000.0)))
    coverage = Coverage((square,), region=square)
    positions = np.array([[500.0, 500.0], [3500.0, 500.0]])
    covariances = np.repeat((50.0**2 * np.eye(2))[None], 2, axis=0)
    sight = look(
        coverage, square, None, positions, covariances, np.full(2, COASTING), 0.0, 0.9, 13.8
    )
    assert sight.seen.tolist() == [True, False]
    assert sight.miss_increment[0] == pytest.approx(MISS, abs=1e-9)
    assert sight.miss_increment[1] == -math.inf
