"""Metrics: OSPA and GOSPA against Stone Soup; the rest worked by hand."""

from __future__ import annotations

import datetime

import numpy as np
import pytest
from numpy.testing import assert_allclose
from stonesoup.metricgenerator.ospametric import GOSPAMetric, OSPAMetric
from stonesoup.types.state import State

from core.arrays import FloatArray
from core.errors import InvalidInput
from core.metrics import (
    coverage,
    false_decision_rate,
    false_tracks,
    gospa,
    identity_switches,
    ospa,
    rms_error,
    time_mean_error,
    time_to_decision,
    track_losses,
)

NOW = datetime.datetime(2026, 11, 22)


def stone_soup_states(points: FloatArray) -> list[State]:
    return [State(point.reshape(-1, 1), timestamp=NOW) for point in points]


def random_sets(rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    estimates = rng.uniform(0, 20, (int(rng.integers(0, 7)), 2))
    truths = rng.uniform(0, 20, (int(rng.integers(0, 7)), 2))
    return estimates, truths


@pytest.mark.parametrize("order", [1.0, 2.0])
def test_ospa_matches_stone_soup(order: float) -> None:
    rng = np.random.default_rng(int(order))
    metric = OSPAMetric(c=5.0, p=order)
    for _ in range(60):
        estimates, truths = random_sets(rng)
        if len(estimates) == 0 and len(truths) == 0:
            continue
        expected = metric.compute_OSPA_distance(
            stone_soup_states(estimates), stone_soup_states(truths)
        ).value
        assert ospa(estimates, truths, cutoff=5.0, order=order) == pytest.approx(
            expected, abs=1e-10
        )


@pytest.mark.parametrize("order", [1.0, 2.0])
def test_gospa_matches_stone_soup(order: float) -> None:
    rng = np.random.default_rng(10 + int(order))
    metric = GOSPAMetric(c=5.0, p=order)
    for _ in range(60):
        estimates, truths = random_sets(rng)
        if len(estimates) == 0 and len(truths) == 0:
            continue
        reference, _ = metric.compute_gospa_metric(
            stone_soup_states(estimates), stone_soup_states(truths)
        )
        ours = gospa(estimates, truths, cutoff=5.0, order=order)
        assert ours.distance == pytest.approx(reference.value["distance"], abs=1e-10)
        assert ours.localisation == pytest.approx(reference.value["localisation"], abs=1e-10)
        assert ours.missed == pytest.approx(reference.value["missed"], abs=1e-10)
        assert ours.false == pytest.approx(reference.value["false"], abs=1e-10)


def test_ospa_and_gospa_hand_worked() -> None:
    # One estimate 3 m from its truth, one truth missed; c = 10, p = 1.
    # OSPA = (3 + 10) / 2 = 6.5; GOSPA = 3 + 10/2 = 8 (localisation 3, missed 5, false 0).
    estimates = np.array([[0.0, 3.0]])
    truths = np.array([[0.0, 0.0], [100.0, 0.0]])
    assert ospa(estimates, truths, cutoff=10.0) == pytest.approx(6.5)
    result = gospa(estimates, truths, cutoff=10.0)
    assert (result.distance, result.localisation, result.missed, result.false) == pytest.approx(
        (8, 3, 5, 0)
    )
    assert ospa(np.zeros((0, 2)), np.zeros((0, 2)), cutoff=10.0) == 0.0


def test_rms_and_time_mean_error() -> None:
    truths = np.zeros((2, 3, 2))
    estimates = np.array(
        [[[3.0, 4.0], [0.0, 0.0], [1.0, 0.0]], [[0.0, 0.0], [0.0, 2.0], [1.0, 0.0]]]
    )
    # Step 0: errors² 25 and 0 → sqrt(12.5); step 1: 0 and 4 → sqrt(2); step 2: 1 and 1 → 1.
    rms = rms_error(truths, estimates)
    assert_allclose(rms, [np.sqrt(12.5), np.sqrt(2.0), 1.0])
    assert time_mean_error(rms) == pytest.approx((np.sqrt(12.5) + np.sqrt(2.0) + 1.0) / 3)
    with pytest.raises(InvalidInput, match="share a"):
        rms_error(truths, estimates[:, :2])


def test_false_decision_rate() -> None:
    truth = [{"a": "L1", "b": "L2", "c": None}, {"a": "L1", "b": "L2"}]
    decisions = [
        {"a": "L1", "b": "L1", "c": None},
        {"a": "L1"},
    ]  # b wrong twice (second: declared new)
    assert false_decision_rate(decisions, truth) == pytest.approx(2 / 5)
    assert false_decision_rate([{}], [{}]) == 0.0


def test_identity_switches() -> None:
    steps = [
        {"t1": "F1", "t2": "F2"},
        {"t1": "F2", "t2": None},
        {"t1": "F2", "t2": "F2"},
        {"t1": "F1", "t2": "F2"},
    ]
    # t1: F1 → F2 (1), F2 → F1 (2); t2: F2, lost, F2 again: no switch.
    assert identity_switches(steps) == 2


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: ospa(np.zeros((1, 2)), np.zeros((1, 2)), cutoff=0.0),
            "cutoff must be a positive number",
        ),
        (lambda: gospa(np.zeros((1, 2)), np.zeros((1, 2)), cutoff=1.0, order=0.5), "order must be"),
        (
            lambda: ospa(np.array([[np.nan, 0.0]]), np.zeros((1, 2)), cutoff=1.0),
            "estimates must be finite",
        ),
        (lambda: ospa(np.zeros((1, 2)), np.zeros((1, 3)), cutoff=1.0), "differ in dimension"),
    ],
)
def test_invalid_metric_inputs(call: object, message: str) -> None:
    with pytest.raises(InvalidInput, match=message):
        call()  # type: ignore[operator]


# ------------------------------------------- coverage, losses, false tracks, decisions
def test_coverage_hand_worked() -> None:
    # Truth a at 0, b at 10; tracks T1 at 1 (covers a), T2 at 10.5 (covers b), T3 at 30 (none).
    truths = {"a": [0.0, 0.0], "b": [10.0, 0.0]}
    tracks = {"T1": [1.0, 0.0], "T2": [10.5, 0.0], "T3": [30.0, 0.0]}
    assert coverage(truths, tracks, cutoff=2.0) == {"a": "T1", "b": "T2"}
    # T1 is the nearest track of both truths; the total-distance pairing gives b to T2.
    truths = {"a": [0.0, 0.0], "b": [1.5, 0.0]}
    tracks = {"T1": [1.0, 0.0], "T2": [2.0, 0.0]}
    assert coverage(truths, tracks, cutoff=2.0) == {"a": "T1", "b": "T2"}
    # Beyond the cut-off nothing covers; no tracks at all: every truth uncovered.
    assert coverage({"a": [0.0, 0.0]}, {"T1": [5.0, 0.0]}, cutoff=2.0) == {"a": None}
    assert coverage({"a": [0.0, 0.0]}, {}, cutoff=2.0) == {"a": None}
    with pytest.raises(InvalidInput):
        coverage({"a": [0.0]}, {"T": [0.0]}, cutoff=0.0)


def test_track_losses_and_false_tracks_hand_worked() -> None:
    steps: list[dict[str, str | None]] = [
        {"a": None, "b": "T2"},  # a not yet covered: not a loss
        {"a": "T1", "b": "T2"},
        {"a": None, "b": "T2"},  # a lost (1)
        {"a": "T3", "b": None},  # b lost (2); a found again under another id
        {"a": None},  # a lost (3); b gone from the scene: not a loss
        {"a": None, "b": None},  # b back without a track: was not covered before
    ]
    assert track_losses(steps) == 3
    assert track_losses([]) == 0
    assert false_tracks({"T1", "T2", "T3", "T4", "T5"}, steps) == 2  # T4, T5 never cover
    assert false_tracks(set(), steps) == 0


def test_time_to_decision_hand_worked() -> None:
    fighter = 2
    nan = np.nan
    run = np.array(
        [
            [1 / 3, 1 / 3, 1 / 3],  # 0
            [0.0, 0.5, 0.5],  # 1
            [0.0, 0.2, 0.8],  # 2: decided …
            [0.0, 0.6, 0.4],  # 3: … but not for good
            [nan, nan, nan],  # 4: no BetP (total conflict): undecided
            [0.0, 0.1, 0.9],  # 5: decided from here to the end
            [0.0, 0.0, 1.0],  # 6
        ]
    )
    assert time_to_decision(run, fighter) == 5.0
    assert time_to_decision(run, fighter, start=2) == 3.0
    assert time_to_decision(run, fighter, level=0.95) == 6.0
    assert np.isnan(time_to_decision(run, 0))  # liner never
    assert time_to_decision(run, fighter, start=5) == 0.0
    # Batched over runs: the same run twice and one decided at once.
    stacked = np.stack([run, run, np.tile([0.0, 0.0, 1.0], (7, 1))])
    assert_allclose(time_to_decision(stacked, fighter), [5.0, 5.0, 0.0])
    with pytest.raises(InvalidInput):
        time_to_decision(run, fighter, start=7)
    with pytest.raises(InvalidInput):
        time_to_decision(run[0], fighter)
