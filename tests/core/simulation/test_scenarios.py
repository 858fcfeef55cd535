"""Scenario generators: counts, appearance / disappearance, manoeuvre windows, seeding."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import ScenarioError
from core.simulation import CLUTTER, aircraft_scenario, pedestrian_scenario
from core.tracking.presets import GRAVITY


def _speed(scenario_states: np.ndarray) -> np.ndarray:
    return np.diff(scenario_states[:, [0, 2]], axis=0)


def test_aircraft_counts_and_lifetimes() -> None:
    scenario = aircraft_scenario(seed=1)
    assert scenario.n_steps == 121
    assert [t.target_id for t in scenario.truths] == [1, 2, 3, 4]
    spans = {t.target_id: (t.first_step, t.last_step) for t in scenario.truths}
    assert spans == {1: (0, 120), 2: (0, 99), 3: (30, 120), 4: (70, 120)}
    counts = [len(scan.measurements) for scan in scenario.scans]
    assert counts[:30] == [2] * 30
    assert counts[30:70] == [3] * 40
    assert counts[70:100] == [4] * 30
    assert counts[100:] == [3] * 21
    steps, measurements = scenario.detections(2)
    np.testing.assert_array_equal(steps, np.arange(100))
    assert np.all(np.concatenate([s.target_ids for s in scenario.scans]) != CLUTTER)
    truth = scenario.truth(2).states[:, [0, 2]]
    assert np.sqrt(np.mean((measurements - truth) ** 2)) == pytest.approx(np.sqrt(0.2), rel=0.2)


def test_aircraft_target_two_manoeuvres() -> None:
    scenario = aircraft_scenario(seed=1)
    windows = {(m.first_step, m.last_step): m.value for m in scenario.manoeuvres}
    assert windows == {(50, 54): (2 * GRAVITY, 0.0), (70, 75): (-4 * GRAVITY, 0.0)}
    velocity = scenario.truth(2).states[:, 1]
    acceleration = np.diff(velocity)  # acceleration[k - 1] drives step k
    steps = np.arange(1, 100)
    in_first = (steps >= 50) & (steps <= 54)
    in_second = (steps >= 70) & (steps <= 75)
    noise = 5 * np.sqrt(0.005)  # process noise: |w| < 5σ
    np.testing.assert_allclose(acceleration[in_first], 2 * GRAVITY, atol=noise)
    np.testing.assert_allclose(acceleration[in_second], -4 * GRAVITY, atol=noise)
    assert np.all(np.abs(acceleration[~in_first & ~in_second]) < noise)
    for other in (1, 3, 4):
        assert np.all(np.abs(np.diff(scenario.truth(other).states[:, [1, 3]], axis=0)) < noise)


def test_aircraft_is_seeded() -> None:
    first, again, other = (
        aircraft_scenario(seed=5),
        aircraft_scenario(seed=5),
        aircraft_scenario(seed=6),
    )
    np.testing.assert_array_equal(first.scans[40].measurements, again.scans[40].measurements)
    assert not np.array_equal(first.scans[40].measurements, other.scans[40].measurements)


def test_pedestrian_phases() -> None:
    scenario = pedestrian_scenario(seed=0, stop_at=60, n_steps=140)
    assert scenario.n_steps == 140
    displacement = _speed(scenario.truth(1).states)  # row k - 1 is the move into step k
    np.testing.assert_allclose(displacement[0:39], 2.0)  # steps 1..39 walk
    np.testing.assert_allclose(displacement[39:59], 6.0)  # steps 40..59 run
    np.testing.assert_allclose(displacement[59:], 0.0)  # steps 60..139 stop
    np.testing.assert_allclose(_speed(scenario.truth(2).states), np.tile([2.0, 0.0], (139, 1)))
    labels = [(m.target_id, m.label, m.first_step, m.last_step) for m in scenario.manoeuvres]
    assert (1, "run", 40, 59) in labels
    assert (1, "stop", 60, 139) in labels
    assert all(len(scan.measurements) == 2 for scan in scenario.scans)


def test_pedestrian_default_is_the_papers_timing() -> None:
    # [MTT] §6.3.3: the class change at step 120; as long stopped as moving by default.
    scenario = pedestrian_scenario(seed=0)
    assert scenario.n_steps == 240
    displacement = _speed(scenario.truth(1).states)
    np.testing.assert_allclose(displacement[39:119], 6.0)  # steps 40..119 run
    np.testing.assert_allclose(displacement[119:], 0.0)  # steps 120..239 stop
    with pytest.raises(ScenarioError):
        pedestrian_scenario(stop_at=30)


def test_pedestrian_walks_again() -> None:
    scenario = pedestrian_scenario(seed=0, stop_at=60, walk_again_at=240)
    assert scenario.n_steps == 300
    displacement = _speed(scenario.truth(1).states)
    np.testing.assert_allclose(displacement[59:239], 0.0)
    np.testing.assert_allclose(displacement[239:], 2.0)
    with pytest.raises(ScenarioError):
        pedestrian_scenario(walk_again_at=30)
