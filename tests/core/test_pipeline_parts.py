"""The pipeline parts both layers are assembled from (``core.pipeline``), each against a
computation by hand: explicit inverses and determinants, F P Fᵀ + Q written out for a
1-D constant-velocity model, nearest pairs found by eye, masks set by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.fusion.motion import MotionModel, StateLayout
from core.geometry import Sector
from core.lifecycle import (
    COASTING,
    CONFIRMED,
    TENTATIVE,
    TERMINATED,
    LifeCycleConfig,
    LifeState,
    StatusReason,
    initiated,
    reason_code,
)
from core.pipeline.evidence import coasting_misses, hits, seen_by
from core.pipeline.gate import mahalanobis, pair_positions, position_distances
from core.pipeline.handover import hand_over_pairs
from core.pipeline.predict import predict_estimates
from core.pipeline.rows import TrackRows, ended


def test_mahalanobis_and_log_det_match_an_explicit_inverse() -> None:
    rng = np.random.default_rng(3)
    roots = rng.normal(size=(5, 3, 3))
    covariances = roots @ np.swapaxes(roots, 1, 2) + 0.5 * np.eye(3)
    differences = rng.normal(size=(5, 3))
    distance, log_det = mahalanobis(differences, covariances)
    for k in range(5):
        expected = differences[k] @ np.linalg.inv(covariances[k]) @ differences[k]
        assert distance[k] == pytest.approx(expected, rel=1e-12)
        assert log_det[k] == pytest.approx(math.log(np.linalg.det(covariances[k])), rel=1e-12)


def test_position_distances_read_only_the_position_components_of_the_sum() -> None:
    states = np.array([[1.0, 50.0, 2.0, -40.0]])
    observed = np.array([[4.0, 0.0, 6.0, 0.0]])
    covariance = np.diag([1.0, 100.0, 4.0, 100.0])
    distance, log_det = position_distances(
        states, covariance[None], observed, 2.0 * covariance[None], np.array([0, 2])
    )
    assert distance[0] == pytest.approx(3.0**2 / 3.0 + 4.0**2 / 12.0)
    assert log_det[0] == pytest.approx(math.log(3.0 * 12.0))


def test_pair_positions_find_pairs_in_a_sorted_pair_list() -> None:
    rows, cols = np.array([0, 0, 1, 2, 2]), np.array([1, 3, 0, 2, 3])
    found = pair_positions(rows, cols, 4, np.array([2, 0, 1]), np.array([3, 3, 0]))
    assert found.tolist() == [4, 1, 2]


def test_a_zero_step_is_the_estimate_and_any_other_step_is_f_p_ft_plus_q() -> None:
    motion = MotionModel(StateLayout(2, (0,), (1,)), q=0.3)
    states = np.array([[10.0, 2.0], [10.0, 2.0]])
    covariance = np.array([[4.0, 1.0], [1.0000001, 1.0]])  # a last-bit asymmetry
    predicted, predicted_cov = predict_estimates(
        motion, states, np.stack([covariance, covariance]), np.array([0.0, 2.5])
    )
    assert predicted[0].tolist() == [10.0, 2.0]
    assert predicted_cov[0].tolist() == ((covariance + covariance.T) / 2).tolist()
    dt = 2.5
    f = np.array([[1.0, dt], [0.0, 1.0]])
    q = 0.3 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    expected = f @ covariance @ f.T + q
    assert predicted[1] == pytest.approx([15.0, 2.0])
    assert predicted_cov[1] == pytest.approx((expected + expected.T) / 2, rel=1e-12)


def test_hand_over_pairs_each_newcomer_with_its_nearest_keeper_inside_the_gate() -> None:
    covariance = np.broadcast_to(np.eye(2), (3, 2, 2))
    keepers = np.array([[0.0, 0.0], [100.0, 0.0], [500.0, 500.0]])
    newcomers = np.array([[101.0, 1.0], [0.5, -0.5], [900.0, 0.0]])
    known, incoming = hand_over_pairs((keepers, covariance), (newcomers, covariance), 0.999)
    assert sorted(zip(known.tolist(), incoming.tolist(), strict=True)) == [(0, 1), (1, 0)]


def test_evidence_of_hits_misses_and_sight() -> None:
    detected, increment = hits(4, np.array([3, 1]), np.array([2.5, -1.0]))
    assert detected.tolist() == [False, True, False, True]
    assert increment.tolist() == [0.0, -1.0, 0.0, 2.5]
    status = np.array([CONFIRMED, COASTING, TENTATIVE, CONFIRMED])
    seen = np.array([True, True, True, False])
    assert coasting_misses(status, seen, detected).tolist() == [True, False, False, False]
    view = Sector((0.0, 0.0), 0.0, 45.0, range_min=0.0, range_max=100.0)  # heading 0: +x
    positions = np.array([[50.0, 0.0, 7000.0], [80.0, 1.0, 1.0], [0.0, 60.0, 0.0]])
    visible, hidden = seen_by(view, positions, np.array([CONFIRMED] * 3), 5.0)
    # the second stands behind the first, seen from the origin; the third is outside
    assert visible.tolist() == [True, False, False] and hidden.tolist() == [False, True, False]
    flat, none_hidden = seen_by(view, positions[:, :1], np.array([CONFIRMED] * 3), 5.0)
    assert flat.all() and not none_hidden.any()  # no plane in 1-D: everything seen


def test_rows_start_numbered_and_keep_the_living() -> None:
    rows = TrackRows.empty().started(7, LifeState.new(3, 0.5))
    assert rows.numbers.tolist() == [7, 8, 9]
    after = LifeState(*(getattr(rows.life, name).copy() for name in LifeState.__dataclass_fields__))
    after.status[1] = TERMINATED
    assert ended(rows.life, after).tolist() == [False, True, False]
    assert rows.living(after).alive.tolist() == [0, 2]
    assert rows.select(np.array([2, 0])).numbers.tolist() == [9, 7]


def test_tracks_confirmed_below_start_confirmed_at_the_confirm_threshold() -> None:
    config = LifeCycleConfig(score_ceiling=None)
    plain = initiated(config, 2, -1.0)
    assert plain.status.tolist() == [TENTATIVE] * 2 and plain.score.tolist() == [-1.0] * 2
    below = initiated(config, 2, -1.0, confirmed_below=True)
    assert below.status.tolist() == [CONFIRMED] * 2
    assert below.reason.tolist() == [reason_code(StatusReason.LOCAL_CONFIRMED)] * 2
    assert below.score.tolist() == [math.log((1 - 1e-3) / 1e-3)] * 2
    capped = initiated(LifeCycleConfig(), 1, 0.0, confirmed_below=True)
    assert capped.score[0] == 0.0  # the default ceiling
