"""The behaviour of [MTT] Fig 15 (aircraft) and Fig 20–22 (pedestrian), on seeded scenarios.

Each target is tracked by the IMM on its own detections (no association).
"""

from __future__ import annotations

import numpy as np
import pytest

from core.simulation import aircraft_scenario, pedestrian_scenario
from core.simulation.replay import SingleTargetReplay, replay_single_target
from core.tracking.presets import aircraft, pedestrian

LINER, BOMBER, FIGHTER = 0, 1, 2
RAMBLER, SPORTSMAN = 0, 1


@pytest.fixture(scope="module")
def aircraft_two() -> SingleTargetReplay:
    return replay_single_target(aircraft_scenario(seed=0), 2, aircraft())


def _rows(replay: SingleTargetReplay, first: int, last: int) -> np.ndarray:
    return (replay.steps >= first) & (replay.steps <= last)


def test_fig_15_before_the_first_manoeuvre(aircraft_two: SingleTargetReplay) -> None:
    betp = aircraft_two.pignistic()[_rows(aircraft_two, 0, 49)]
    assert len(betp) == 48
    assert np.all(np.abs(betp - 1 / 3) <= 0.1)


def test_fig_15_between_the_manoeuvres(aircraft_two: SingleTargetReplay) -> None:
    betp = aircraft_two.pignistic()[_rows(aircraft_two, 55, 69)]
    assert np.all(betp[:, LINER] <= 0.1)
    assert np.all(betp[:, BOMBER] >= 0.35)
    assert np.all(betp[:, FIGHTER] >= 0.35)


def test_fig_15_after_the_sharp_manoeuvre_and_after_disappearing(
    aircraft_two: SingleTargetReplay,
) -> None:
    betp = aircraft_two.pignistic()
    after = _rows(aircraft_two, 76, 120)
    assert np.all(betp[after, FIGHTER] >= 0.9)
    gone = _rows(aircraft_two, 100, 120)
    assert gone.sum() == 21
    assert not aircraft_two.detected[gone].any()
    # Coasting predictions are not evidence: the class mass is the one of step 99.
    last_seen = aircraft_two.credal[aircraft_two.index(99)]
    for row in np.flatnonzero(gone):
        assert aircraft_two.credal[row] is last_seen


def test_fig_14_bayesian_baseline_fails_in_doubt(aircraft_two: SingleTargetReplay) -> None:
    between = _rows(aircraft_two, 55, 69)
    bayes = aircraft_two.bayesian[between]
    betp = aircraft_two.pignistic()[between]
    assert np.all(np.abs(bayes[:, BOMBER] - bayes[:, FIGHTER]) > 0.2)
    assert np.all(np.abs(betp[:, BOMBER] - betp[:, FIGHTER]) <= 0.1)


@pytest.fixture(scope="module")
def walk_run_stop() -> dict[str, SingleTargetReplay]:
    scenario = pedestrian_scenario(seed=0, stop_at=60, n_steps=140)
    preset = pedestrian()
    return {
        discount: replay_single_target(scenario, 1, preset, {"discount": discount})
        for discount in ("none", "instantaneous", "cumulative")
    }


def test_fig_20_standard_algorithm_cannot_follow_the_stop(
    walk_run_stop: dict[str, SingleTargetReplay],
) -> None:
    replay = walk_run_stop["none"]
    assert replay.step_conflicts()[replay.index(60)] > 1 - 1e-6
    betp = replay.pignistic()[_rows(replay, 45, 139)]
    assert not np.any(np.isnan(betp))
    assert np.all(betp[:, SPORTSMAN] > 0.5)


def test_fig_21_instantaneous_discounting_follows_both_changes(
    walk_run_stop: dict[str, SingleTargetReplay],
) -> None:
    replay = walk_run_stop["instantaneous"]
    betp = replay.pignistic()
    assert np.any(betp[_rows(replay, 40, 44), SPORTSMAN] > 0.5)
    assert np.all(betp[_rows(replay, 60 + 45, 139), RAMBLER] > 0.5)


def test_fig_22_cumulative_discounting_forgets_within_a_few_steps(
    walk_run_stop: dict[str, SingleTargetReplay],
) -> None:
    replay = walk_run_stop["cumulative"]
    assert replay.credal[0].class_mass.frame.labels == ("rambler", "sportsman")
    betp = replay.pignistic()
    assert np.any(betp[_rows(replay, 60, 64), RAMBLER] > 0.5)


def test_fig_20_literal_total_conflict_on_another_noise_realisation() -> None:
    # With seed 13 the stop's evidence against running becomes total (1 − K < 1e-12) at
    # step 62: as in the paper, BetP cannot be computed any more, to the end.
    replay = replay_single_target(
        pedestrian_scenario(seed=13, stop_at=60, n_steps=140), 1, pedestrian()
    )
    statuses = [c.status for c in replay.credal]
    first = statuses.index("total_conflict")
    assert int(replay.steps[first]) == 62
    assert all(status == "total_conflict" for status in statuses[first:])
    assert all(c.pignistic is None for c in replay.credal[first:])
    assert replay.credal[first - 1].decision() == "sportsman"


def test_fig_22_23_walking_again_after_the_stop() -> None:
    # λ = 0.9 both ways. Walking is a shared behaviour: cumulative discounting forgets the
    # rambler evidence and drifts back to doubt (Fig 22); instantaneous keeps it (Fig 23).
    scenario = pedestrian_scenario(seed=0, stop_at=60, walk_again_at=240)
    preset = pedestrian()
    cumulative, instantaneous = (
        replay_single_target(scenario, 1, preset, {"discount": discount, "reliability": 0.9})
        for discount in ("cumulative", "instantaneous")
    )
    assert cumulative.pignistic()[cumulative.index(239), RAMBLER] > 0.99  # still stopped
    assert abs(cumulative.pignistic()[cumulative.index(299), RAMBLER] - 0.5) < 0.05
    assert instantaneous.pignistic()[instantaneous.index(299), RAMBLER] > 0.99
