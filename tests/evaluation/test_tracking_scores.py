"""OSPA, GOSPA and identity switches of a tracked run, against values worked by hand."""

from __future__ import annotations

import numpy as np
import pytest

from core.simulation.scenario import Scenario, TargetTruth
from evaluation.tracking import TrackedRun, tracking_scores


def _truth(target_id: int, x: float, y: float, steps: int) -> TargetTruth:
    states = np.tile([x, 0.0, y, 0.0], (steps, 1))
    return TargetTruth(target_id, 0, states)


def _state(x: float, y: float) -> list[float]:
    return [x, 0.0, y, 0.0]


def test_scores_worked_by_hand() -> None:
    # Truth 1 at (0, 0), truth 2 at (100, 0); c = 10, order 1.
    scenario = Scenario(
        name="hand",
        seed=0,
        time_interval=1.0,
        n_steps=4,
        truths=(_truth(1, 0.0, 0.0, 4), _truth(2, 100.0, 0.0, 4)),
        manoeuvres=(),
        scans=(),
        measurement_noise=np.eye(2),
    )
    empty = np.zeros(0, dtype=np.int64)
    run = TrackedRun(
        steps=np.array([0, 1, 2, 3]),
        track_ids=((), ("a",), ("a", "b", "t"), ("b", "z")),
        statuses=((), ("tentative",), ("confirmed", "coasting", "tentative"), ("confirmed",) * 2),
        reasons=((), ("",), ("", "", ""), ("", "")),
        states=(
            np.zeros((0, 4)),
            np.array([_state(0.0, 0.0)]),
            # step 2: a is 0.5 m from truth 1, b on truth 2; the tentative t is ignored.
            np.array([_state(0.3, 0.4), _state(100.0, 0.0), _state(50.0, 0.0)]),
            # step 3: b moves onto truth 1 (a switch), z is far from truth 2.
            np.array([_state(0.0, 0.0), _state(200.0, 0.0)]),
        ),
        pignistic=(np.zeros((0, 3)),) * 4,
        detection_steps=empty,
        detection_targets=empty,
        detection_tracks=(),
        measurements=np.zeros((0, 2)),
    )
    scores = tracking_scores(scenario, run, cutoff=10.0, first_step=2)
    # OSPA: step 2 (0.5 + 0) / 2 = 0.25; step 3 b on truth 1, z 100 m from truth 2,
    # cut at c: (0 + 10) / 2 = 5.
    assert scores.ospa == pytest.approx((0.25 + 5.0) / 2)
    # GOSPA (α = 2): step 2 0.5; step 3 0 + a miss and a false track at c / 2 each = 10.
    assert scores.gospa == pytest.approx((0.5 + 10.0) / 2)
    # Truth 1: a at step 2, b at step 3 → one switch; truth 2 loses b (no switch).
    assert scores.identity_switches == 1
