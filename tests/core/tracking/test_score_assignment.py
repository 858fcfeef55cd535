"""The established tracks of several sensors' detections are assigned on the track score
(docs/algorithms.md §8.9, "assigned on the score"): the matching of the most likely single
hypothesis, Σ (ΔL_hit − ΔL_miss) of [MTT] §4.3 eq 16, over GNN's gated pairs that pass the
hit floor — checked against hand-worked scores and a brute-force search over every matching;
one sensor's tracker keeps the papers' GNN on D."""

from __future__ import annotations

import itertools
import math
from types import MappingProxyType

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal

from core.lifecycle import LifeCycleConfig, ScoreModel
from core.tracking.associate import DetectionAssociator
from core.tracking.config import LocalTrackerConfig
from core.tracking.imm import IMMPrediction
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

P_DETECT = 0.9
CLUTTER = 1e-5
GATE = float(chi2.ppf(0.999, 2))
"""GNN's default T (gate probability 0.999, two measured components)."""


def _bank() -> ModelBank:
    return ModelBank(
        (constant_velocity(1.0, 1.0, noise="continuous"),),
        LinearMeasurementModel(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]), np.eye(2)),
        np.ones((1, 1)),
    )


def _associator(sensors: tuple[str, ...]) -> DetectionAssociator:
    config = LocalTrackerConfig(
        bank=_bank(),
        classification=None,
        fields_of_view=MappingProxyType(dict.fromkeys(sensors)),
    )
    return DetectionAssociator(config, _bank(), _score())


def _score() -> ScoreModel:
    return ScoreModel(P_DETECT, CLUTTER, 1e-9, 1e-3, 1e-3)


def _prediction(centres: np.ndarray, spreads: np.ndarray) -> IMMPrediction:
    """One-model predictions of tracks at ``centres`` (T, 2) with innovation covariances
    ``spreads`` (T, 2, 2) (R = I: the position covariance is S − I, the velocity's I)."""
    count = len(centres)
    means = np.zeros((count, 1, 4))
    means[:, 0, [0, 2]] = centres
    covariances = np.tile(np.eye(4), (count, 1, 1, 1))
    position = spreads - np.eye(2)
    for i, j in itertools.product(range(2), range(2)):
        covariances[:, 0, 2 * i, 2 * j] = position[:, i, j]
    return IMMPrediction(
        means,
        covariances,
        np.zeros((count, 1)),
        centres[:, None, :].copy(),
        spreads[:, None, :, :].copy(),
    )


def _hit(point: np.ndarray, centre: np.ndarray, spread: np.ndarray) -> float:
    """ΔL of a hit by scipy: ln P_D − ln β_FT + ln N(z; ẑ, S)."""
    return (
        math.log(P_DETECT)
        - math.log(CLUTTER)
        + float(multivariate_normal.logpdf(point, centre, spread))
    )


def test_a_kept_tracks_narrow_gate_takes_its_detection_from_a_wide_gates_jump() -> None:
    """Track A at the origin, S = 2 I; track B 30 m east, S = 200 I (a young track coasted
    through other sensors' scans); one detection at (4, 0). D: A 16/2 = 8, B 26²/200 =
    3.38 — GNN on D (T − D: 5.82 against 10.44) gives it to B, one sensor's tracker still
    does. The score, by hand: ΔL = ln 0.9 − ln 2π + ln 10⁵ − ½ ln|S| − D/2 = −0.1054 −
    1.8379 + 11.5129 − 0.6931 − 4 = 4.8765 for A, and −0.1054 − 1.8379 + 11.5129 −
    5.2983 − 1.69 = 2.5813 for B: several sensors' tracker gives it to A, scored 4.8765."""
    prediction = _prediction(
        np.array([[0.0, 0.0], [30.0, 0.0]]), np.array([2.0 * np.eye(2), 200.0 * np.eye(2)])
    )
    z = np.array([[4.0, 0.0]])
    first = np.array([True, True])
    several = _associator(("a", "b")).associate(prediction, z, None, first, _score())
    np.testing.assert_array_equal(several.rows, [0])
    np.testing.assert_array_equal(several.cols, [0])
    assert several.hit_gain[0] == pytest.approx(4.8765, abs=1e-4)
    assert several.hit_gain[0] == pytest.approx(_hit(z[0], np.zeros(2), 2.0 * np.eye(2)))
    assert several.hit_gain[1] == 0.0
    one = _associator(("a",)).associate(prediction, z, None, first, _score())
    np.testing.assert_array_equal(one.rows, [1])  # the papers' GNN on D, unchanged
    assert one.hit_gain[1] == pytest.approx(2.5813, abs=1e-4)


def _brute_force(
    centres: np.ndarray, spreads: np.ndarray, z: np.ndarray
) -> tuple[float, set[tuple[int, int]]]:
    """The best matching over every partial one-to-one matching of the pairs allowed
    (D ≤ T, and P_D N(z; ẑ, S) ≥ (1 − P_D) β_FT), by enumeration: its Σ (ΔL_hit −
    ln(1 − P_D)) and its pairs."""
    miss = math.log(1.0 - P_DETECT)
    floor = math.log((1.0 - P_DETECT) * CLUTTER / P_DETECT)
    allowed: dict[tuple[int, int], float] = {}
    for t, d in itertools.product(range(len(centres)), range(len(z))):
        nu = z[d] - centres[t]
        distance = float(nu @ np.linalg.solve(spreads[t], nu))
        likelihood = float(multivariate_normal.logpdf(z[d], centres[t], spreads[t]))
        if distance <= GATE and likelihood >= floor:
            allowed[(t, d)] = _hit(z[d], centres[t], spreads[t]) - miss
    best, chosen = 0.0, set()
    tracks = range(len(centres))
    for targets in itertools.product([None, *range(len(z))], repeat=len(centres)):
        used = [d for d in targets if d is not None]
        if len(used) != len(set(used)):
            continue
        pairs = {(t, d) for t, d in zip(tracks, targets, strict=True) if d is not None}
        if not pairs <= set(allowed):
            continue
        total = sum(allowed[pair] for pair in pairs)
        if total > best:
            best, chosen = total, pairs
    return best, chosen


@pytest.mark.parametrize("seed", range(12))
def test_the_assignment_is_the_best_of_every_matching_by_brute_force(seed: int) -> None:
    """Four tracks, four detections in a 12 m square, gates from σ 1 m to 15 m (seed 7:
    GNN on D, one sensor's, chooses another matching): the pairs
    are the matching of the largest summed score found by enumerating every one-to-one
    partial matching (scipy's Gaussian for each ΔL), and each hit scores its own ΔL."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0.0, 12.0, (4, 2))
    spreads = np.empty((4, 2, 2))
    for t in range(4):
        root = rng.uniform(1.0, 15.0) * rng.normal(size=(2, 2)) / 2.0
        spreads[t] = root @ root.T + np.eye(2)
    z = rng.uniform(0.0, 12.0, (4, 2))
    best, chosen = _brute_force(centres, spreads, z)
    found = _associator(("a", "b")).associate(
        _prediction(centres, spreads), z, None, np.ones(4, dtype=bool), _score()
    )
    pairs = set(zip(found.rows.tolist(), found.cols.tolist(), strict=True))
    assert pairs == chosen
    miss = math.log(1.0 - P_DETECT)
    assert sum(found.hit_gain[t] - miss for t, _ in pairs) == pytest.approx(best)
    for t, d in pairs:
        assert found.hit_gain[t] == pytest.approx(_hit(z[d], centres[t], spreads[t]))


def test_some_matchings_of_the_brute_force_seeds_differ_from_gnn_on_d() -> None:
    """The brute-force test is not GNN's answer in disguise: on its seed 7, one sensor's
    GNN on D chooses another matching than the best on the score."""
    rng = np.random.default_rng(7)
    centres = rng.uniform(0.0, 12.0, (4, 2))
    spreads = np.empty((4, 2, 2))
    for t in range(4):
        root = rng.uniform(1.0, 15.0) * rng.normal(size=(2, 2)) / 2.0
        spreads[t] = root @ root.T + np.eye(2)
    z = rng.uniform(0.0, 12.0, (4, 2))
    _, chosen = _brute_force(centres, spreads, z)
    one = _associator(("a",)).associate(
        _prediction(centres, spreads), z, None, np.ones(4, dtype=bool), _score()
    )
    assert set(zip(one.rows.tolist(), one.cols.tolist(), strict=True)) != chosen


def _young_track_beside_a_kept_one(sensors: tuple[str, ...]) -> tuple[str | None, ...]:
    """The reduced scene of bench/multisensor.py's ~50 ``sectors`` switch (§8.9): target A at
    rest at the origin, detected (σ 1 m) at every scan of ``sensors`` in turn, every 1/2 s
    for 10 s; two false alarms at 8 s (40, 0) and 8.5 s (35, 0) make a young track B
    coasting toward A at 10 m/s; at 10 s the only detection is A's, 4 m east of it (B is
    predicted at (20, 0), its gate widened by two misses and its two-point velocity).
    Returns which track took that detection."""
    bank = ModelBank(
        (constant_velocity(1.0, 0.05, noise="continuous"),),
        LinearMeasurementModel(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]), np.eye(2)),
        np.ones((1, 1)),
    )
    tracker = LocalTracker(
        LocalTrackerConfig(
            bank=bank,
            classification=None,
            life_cycle=LifeCycleConfig(false_target_density=3e-5, new_target_density=1e-5),
            fields_of_view=MappingProxyType(dict.fromkeys(sensors)),
        )
    )
    rng = np.random.default_rng(0)
    false_alarms = {8.0: [40.0, 0.0], 8.5: [35.0, 0.0]}
    for scan in range(20):
        time = 0.5 * scan
        z = [
            rng.normal(0.0, 1.0, 2).tolist(),
            *([false_alarms[time]] if time in false_alarms else []),
        ]
        tracker.step(time, np.array(z), sensor=sensors[scan % len(sensors)])
    step = tracker.step(10.0, np.array([[4.0, 0.0]]), sensor=sensors[-1])
    living = {track.id for track in step.tracks if track.status.value != "terminated"}
    assert {"L1", "L3"} <= living  # A's track, and B alive
    return step.assignment


def test_a_young_tracks_wide_gate_does_not_take_a_kept_tracks_detection() -> None:
    """Several sensors: A's detection goes to A's track (L1, the truth: B is two false
    alarms); one sensor's GNN on D gives it to B (L3), whose gate makes D the smaller."""
    assert _young_track_beside_a_kept_one(("a", "b")) == ("L1",)
    assert _young_track_beside_a_kept_one(("a",)) == ("L3",)
