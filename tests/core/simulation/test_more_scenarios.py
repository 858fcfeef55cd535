"""close-pair, crossing, accelerating, overtaking: geometry, windows, clutter, coverage."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import ScenarioError
from core.simulation import (
    CLUTTER,
    SCENARIOS,
    accelerating_scenario,
    close_pair_scenario,
    crossing_scenario,
    overtaking_scenario,
)
from core.simulation.scenario import inside
from core.tracking.presets import GRAVITY


def test_every_evaluation_scenario_is_registered_and_seeded() -> None:
    assert set(SCENARIOS) >= {
        "aircraft",
        "pedestrian",
        "close-pair",
        "crossing",
        "accelerating",
        "overtaking",
    }
    for name, build in SCENARIOS.items():
        first, again = build(4), build(4)
        assert first.name == name
        assert first.seed == 4
        assert len(first.scans) == len(again.scans)
        for a, b in zip(first.scans, again.scans, strict=True):
            np.testing.assert_array_equal(a.measurements, b.measurements)


@pytest.mark.parametrize("ratio", [0.0, 0.5, 2.0])
@pytest.mark.parametrize("reading", ["variance", "std"])
def test_close_pair_noise_is_a_fraction_of_the_separation(ratio: float, reading: str) -> None:
    # [MTT] §6.2.1: "variance" (the letter) σ² = r·d m²; "std" σ = r·d
    scenario = close_pair_scenario(
        seed=2, noise_ratio=ratio, separation=10.0, n_steps=200, noise_reading=reading
    )
    gap = scenario.truth(2).states[:, 2] - scenario.truth(1).states[:, 2]
    np.testing.assert_allclose(gap, 10.0)
    steps, measurements = scenario.detections(1)
    assert len(steps) == 200
    errors = measurements - scenario.truth(1).states[:, [0, 2]]
    sigma = np.sqrt(ratio * 10.0) if reading == "variance" else ratio * 10.0
    assert np.sqrt(np.mean(errors**2)) == pytest.approx(sigma, rel=0.15, abs=1e-12)
    with pytest.raises(ScenarioError):
        close_pair_scenario(noise_ratio=-1.0)
    with pytest.raises(ScenarioError):
        close_pair_scenario(noise_reading="sigma")  # type: ignore[arg-type]


def test_crossing_targets_pass_then_fly_close() -> None:
    scenario = crossing_scenario(seed=0)
    ahead = scenario.truth(1).states[:, [0, 2]] - scenario.truth(2).states[:, [0, 2]]
    assert np.all(ahead[:36] < 0)  # target 1 behind until it overtakes
    np.testing.assert_allclose(ahead[36:], 5.0, atol=1e-9)
    windows = [(m.target_id, m.first_step, m.last_step, m.value) for m in scenario.manoeuvres]
    assert windows == [
        (1, 23, 24, (4 * GRAVITY, 4 * GRAVITY)),
        (1, 35, 36, (-4 * GRAVITY, -4 * GRAVITY)),
    ]
    velocity = scenario.truth(1).states[:, 1]
    np.testing.assert_allclose(velocity[[0, 22, 36, 59]], 40.0)
    np.testing.assert_allclose(velocity[24], 40.0 + 2 * 4 * GRAVITY)


def test_accelerating_vehicle_and_clutter() -> None:
    scenario = accelerating_scenario(seed=1, n_steps=80)
    forward = scenario.truth(2).states[:, 3]
    np.testing.assert_allclose(forward[:40], 0.5, atol=0.2)  # process noise
    np.testing.assert_allclose(forward[79], 0.5 + 40 * 0.1 * 6.0, atol=0.3)
    clutter = [int(np.sum(scan.target_ids == CLUTTER)) for scan in scenario.scans]
    assert 2.5 < np.mean(clutter) < 3.5  # Poisson mean 3 per frame ([HZ] §6)
    region = scenario.sensor_regions["front"]
    for scan in scenario.scans:
        assert all(inside(region, z) for z in scan.measurements)


def test_overtaking_vehicle_crosses_the_blind_zone() -> None:
    scenario = overtaking_scenario(seed=3)
    assert {scan.sensor for scan in scenario.scans} == {"rear", "front"}
    assert len(scenario.scans) == 2 * scenario.n_steps
    truth = scenario.truth(1).states
    hidden = np.flatnonzero(np.abs(truth[:, 2]) < 5.0)
    assert len(hidden) >= 20  # 2.5 s at 4 m/s, ΔT = 0.1 s
    steps, _ = scenario.detections(1)
    assert not set(hidden.tolist()) & set(steps.tolist())
    by_sensor = {
        sensor: {
            scan.step
            for scan in scenario.scans
            if scan.sensor == sensor and np.any(scan.target_ids == 1)
        }
        for sensor in ("rear", "front")
    }
    assert max(by_sensor["rear"]) < hidden.min() < hidden.max() < min(by_sensor["front"])
    front_steps, _ = scenario.detections(2)
    assert len(front_steps) == scenario.n_steps  # the car ahead is always in the front sensor
