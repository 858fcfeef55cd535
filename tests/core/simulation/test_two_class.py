"""The t2t-two-class scenario against its description ([T2T] §4 scenario 2)."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import ScenarioError
from core.simulation import ClassifiedTrackListScenario, t2t_two_class
from core.simulation.two_class import CLASSES


def test_counts_times_and_geometry() -> None:
    scenario = t2t_two_class(seed=1, n_steps=30, separation=2.0)
    assert isinstance(scenario, ClassifiedTrackListScenario)
    assert scenario.name == "t2t-two-class"
    assert scenario.seed == 1
    assert len(scenario.reports) == len(scenario.class_masses) == 60
    assert [r.sensor for r in scenario.reports] == ["s1", "s2"] * 30
    assert [r.step for r in scenario.reports] == [k // 2 for k in range(60)]
    times = np.array([r.time for r in scenario.reports])
    np.testing.assert_allclose(times[0::2], np.arange(30.0))
    np.testing.assert_allclose(times[1::2] - times[0::2], 1e-3)
    for report, masses in zip(scenario.reports, scenario.class_masses, strict=True):
        assert report.track_ids == (f"{report.sensor}-0", f"{report.sensor}-1")
        np.testing.assert_array_equal(report.target_ids, [0, 1])
        assert len(masses) == 2
    gap = scenario.truths[1].states[:, 2] - scenario.truths[0].states[:, 2]
    np.testing.assert_allclose(gap, 2.0)
    np.testing.assert_allclose(scenario.truths[0].states[:, 1], 10.0)
    assert scenario.true_classes == ("c1", "c2")


def test_errors_follow_the_reported_covariance() -> None:
    scenario = t2t_two_class(seed=2, n_steps=400, position_sigma=0.5)
    errors = []
    for report in scenario.reports:
        truth = np.array([t.state_at(report.step) for t in scenario.truths])
        lag = report.time - report.step
        truth[:, 0] += truth[:, 1] * lag
        errors.append(report.states - truth)
    rms = np.sqrt(np.mean(np.concatenate(errors) ** 2, axis=0))
    np.testing.assert_allclose(rms, [0.5, 0.25, 0.5, 0.25], rtol=0.06)
    np.testing.assert_allclose(scenario.reports[0].covariances[0], np.diag([0.25, 0.0625] * 2))


def test_class_masses_point_at_the_true_class_up_to_the_error_rate() -> None:
    scenario = t2t_two_class(seed=3, n_steps=500, class_confidence=0.8, class_error=0.1)
    right = wrong = 0
    for masses in scenario.class_masses:
        for target, mass in enumerate(masses):
            assert mass.frame == CLASSES
            singleton = [labels for labels, _ in mass.focal_sets() if len(labels) == 1]
            assert len(singleton) == 1
            support = mass.mass(singleton[0])
            assert 0.4 - 1e-12 <= support <= 0.8 + 1e-12
            assert mass.mass(CLASSES.labels) == pytest.approx(1.0 - support)
            if singleton[0] == (scenario.true_classes[target],):
                right += 1
            else:
                wrong += 1
    assert wrong / (right + wrong) == pytest.approx(0.1, abs=0.02)
    perfect = t2t_two_class(seed=3, n_steps=50, class_error=0.0)
    for masses in perfect.class_masses:
        assert [m.singleton_belief().argmax() for m in masses] == [0, 1]


def test_seeded() -> None:
    first, again, other = t2t_two_class(seed=4), t2t_two_class(seed=4), t2t_two_class(seed=5)
    for a, b in zip(first.reports, again.reports, strict=True):
        np.testing.assert_array_equal(a.states, b.states)
    assert [m.masses.tolist() for ms in first.class_masses for m in ms] == [
        m.masses.tolist() for ms in again.class_masses for m in ms
    ]
    assert not np.array_equal(first.reports[0].states, other.reports[0].states)


@pytest.mark.parametrize(
    "bad",
    [
        {"position_sigma": 0.0},
        {"separation": -1.0},
        {"n_steps": 0},
        {"class_confidence": 1.5},
        {"class_error": -0.1},
    ],
)
def test_rejects_impossible_scenes(bad: dict[str, float]) -> None:
    with pytest.raises(ScenarioError):
        t2t_two_class(**bad)
