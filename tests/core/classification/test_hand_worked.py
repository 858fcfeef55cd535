"""Hand-worked small cases: behaviour plausibilities, GBT + mapping, discounting order,
total conflict, the Bayesian matrix M of [MTT] §6.1.2."""

from __future__ import annotations

import numpy as np
import pytest

from core.belief import Frame, MassFunction
from core.classification import (
    BayesianClassifier,
    BehaviourModels,
    CredalClassifier,
    class_given_behaviour,
)
from core.errors import ClassificationError
from core.tracking.presets import aircraft, pedestrian

NESTED = BehaviourModels.from_mapping(
    Frame(["b1", "b2", "b3"]),
    ["m1", "m2", "m3"],
    {"b1": ["m1"], "b2": ["m1", "m2"], "b3": ["m1", "m2", "m3"]},
)


def _logs(mu: list[float], likelihood: list[float]) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(divide="ignore"):
        return np.log(np.array([mu])), np.log(np.array([likelihood]))


def test_behaviour_plausibilities_eq_22_with_eq_20() -> None:
    log_mu, log_l = _logs([0.5, 0.3, 0.2], [2.0, 1.0, 0.5])
    # Pl(b1) = 2; Pl(b2) = (0.5·2 + 0.3·1)/0.8 = 1.625; Pl(b3) = 1 + 0.3 + 0.1 = 1.4
    np.testing.assert_allclose(np.exp(NESTED.log_likelihoods(log_mu, log_l)), [[2.0, 1.625, 1.4]])
    np.testing.assert_allclose(NESTED.plausibilities(log_mu, log_l, "max"), [[1.0, 0.8125, 0.7]])
    np.testing.assert_allclose(NESTED.plausibilities(log_mu, log_l, "clip"), [[1.0, 1.0, 1.0]])
    log_mu, log_l = _logs([0.5, 0.3, 0.2], [0.5, 0.2, 0.1])
    np.testing.assert_allclose(NESTED.plausibilities(log_mu, log_l, "clip"), [[0.5, 0.3875, 0.33]])
    np.testing.assert_allclose(NESTED.plausibilities(log_mu, log_l, "max"), [[1.0, 0.775, 0.66]])


def test_behaviour_with_zero_mode_probability_uses_uniform_weights() -> None:
    behaviours = BehaviourModels.from_mapping(
        Frame(["still", "moving"]), ["m1", "m2", "m3"], {"still": ["m1"], "moving": ["m2", "m3"]}
    )
    log_mu, log_l = _logs([1.0, 0.0, 0.0], [0.1, 0.4, 0.2])
    np.testing.assert_allclose(np.exp(behaviours.log_likelihoods(log_mu, log_l)), [[0.1, 0.3]])


def test_plausibilities_survive_underflow() -> None:
    log_mu = np.log(np.array([[0.9, 0.05, 0.05]]))
    log_l = np.array([[-5000.0, -5001.0, -9000.0]])  # every Λ underflows in float64
    pl = NESTED.plausibilities(log_mu, log_l, "max")
    assert pl[0, 0] == 1.0
    assert 0.0 < pl[0, 1] < 1.0


def test_credal_step_gbt_and_mapping() -> None:
    preset = aircraft()
    classifier = CredalClassifier(preset.behaviours, preset.relation)
    # GBT: {b2}: 0.4, {b1,b2}: 0.1, {b2,b3}: 0.4, {b1,b2,b3}: 0.1 → {bomber,fighter}: 0.8, Ω: 0.2
    step = classifier.step_mass(np.array([0.2, 1.0, 0.5]))
    assert step.mass(["bomber", "fighter"]) == pytest.approx(0.8)
    assert step.mass(["liner", "bomber", "fighter"]) == pytest.approx(0.2)
    state = classifier.combine(classifier.initial(), step)
    assert state.pignistic is not None
    np.testing.assert_allclose(state.pignistic, [0.2 / 3, 0.4 + 0.2 / 3, 0.4 + 0.2 / 3])


SECOND_STEP = np.array([0.2, 0.2, 1.0])  # → {fighter}: 0.64, {bomber,fighter}: 0.16, Ω: 0.2


@pytest.mark.parametrize(
    ("discount", "reliability", "expected"),
    [
        (
            "none",
            None,
            {("fighter",): 0.64, ("bomber", "fighter"): 0.32, ("liner", "bomber", "fighter"): 0.04},
        ),
        # the step masses are discounted: 0.3 × each, 0.7 to Ω, then combined
        (
            "instantaneous",
            0.3,
            {
                ("fighter",): 0.192,
                ("bomber", "fighter"): 0.2304,
                ("liner", "bomber", "fighter"): 0.5776,
            },
        ),
        # the previous cumulative mass is discounted before combining
        (
            "cumulative",
            0.5,
            {("fighter",): 0.64, ("bomber", "fighter"): 0.24, ("liner", "bomber", "fighter"): 0.12},
        ),
    ],
)
def test_discounting_order(
    discount: str, reliability: float | None, expected: dict[tuple[str, ...], float]
) -> None:
    preset = aircraft()
    classifier = CredalClassifier(
        preset.behaviours,
        preset.relation,
        discount=discount,
        reliability=reliability,  # type: ignore[arg-type]
    )
    state = classifier.initial()
    for pl in (np.array([0.2, 1.0, 0.5]), SECOND_STEP):
        state = classifier.combine(state, classifier.step_mass(pl))
    for labels, mass in expected.items():
        assert state.mass.mass(labels) == pytest.approx(mass, abs=1e-12)
    assert sum(expected.values()) == pytest.approx(1.0)


def test_default_reliabilities() -> None:
    preset = pedestrian()
    assert (
        CredalClassifier(preset.behaviours, preset.relation, discount="instantaneous").reliability
        == 0.3
    )
    assert (
        CredalClassifier(preset.behaviours, preset.relation, discount="cumulative").reliability
        == 0.9
    )
    with pytest.raises(ClassificationError):
        CredalClassifier(preset.behaviours, preset.relation, discount="sometimes")  # type: ignore[arg-type]
    with pytest.raises(ClassificationError):
        CredalClassifier(preset.behaviours, preset.relation, reliability=1.5)


RUNNING, STATIC, WALKING = (
    np.array([0.0, 0.0, 1.0]),
    np.array([1.0, 0.0, 0.0]),
    np.array([0.0, 1.0, 0.0]),
)


def test_total_conflict_state_is_absorbing_without_discounting() -> None:
    preset = pedestrian()
    classifier = CredalClassifier(preset.behaviours, preset.relation)
    state = classifier.combine(classifier.initial(), classifier.step_mass(RUNNING))
    assert state.decision() == "sportsman"
    state = classifier.combine(state, classifier.step_mass(STATIC))
    assert state.status == "total_conflict"
    assert state.pignistic is None
    assert state.decision() is None
    assert state.step_conflict == 1.0
    assert state.conflict == 1.0
    state = classifier.combine(state, classifier.step_mass(WALKING))
    assert state.status == "total_conflict"


def test_cumulative_discounting_leaves_total_conflict() -> None:
    preset = pedestrian()
    classifier = CredalClassifier(preset.behaviours, preset.relation, discount="cumulative")
    state = classifier.combine(classifier.initial(), classifier.step_mass(RUNNING))
    state = classifier.combine(state, classifier.step_mass(STATIC))
    assert state.status == "ok"  # the prior was discounted first: 0.1 on Ω survives
    assert state.decision() == "rambler"
    assert state.step_conflict == pytest.approx(0.9)


def test_running_conflict_accumulates() -> None:
    preset = pedestrian()
    classifier = CredalClassifier(preset.behaviours, preset.relation)
    rambler_or_not = np.array([1.0, 0.5, 0.0])  # {rambler}: 0.5, Ω: 0.5
    sportsman_or_not = np.array([0.0, 0.5, 1.0])  # {sportsman}: 0.5, Ω: 0.5
    state = classifier.combine(classifier.initial(), classifier.step_mass(rambler_or_not))
    assert state.step_conflict == 0.0
    state = classifier.combine(state, classifier.step_mass(sportsman_or_not))
    assert state.step_conflict == pytest.approx(0.25)
    # normalised: rambler, sportsman, Ω each 1/3; the next K is 1/3 · 1/2
    state = classifier.combine(state, classifier.step_mass(rambler_or_not))
    assert state.step_conflict == pytest.approx(1 / 6)
    assert state.conflict == pytest.approx(1 - 0.75 * 5 / 6)
    assert state.steps == 3


def test_clip_scaling_keeps_the_conflict_of_weak_evidence() -> None:
    preset = pedestrian()
    classifier = CredalClassifier(preset.behaviours, preset.relation, likelihood_scale="clip")
    log_mu = np.log(np.full((1, 7), 1 / 7))
    log_l = np.full((1, 7), np.log(0.5))  # every Pl({b}) = 0.5
    (state,) = classifier.update([classifier.initial()], log_mu, log_l)
    assert state.step_conflict == pytest.approx(0.125)  # m(∅) = Π(1 − 0.5)


def test_coasting_tracks_keep_their_mass() -> None:
    preset = pedestrian()
    classifier = CredalClassifier(preset.behaviours, preset.relation)
    before = [classifier.combine(classifier.initial(), classifier.step_mass(RUNNING))] * 2
    log_mu = np.log(np.full((2, 7), 1 / 7))
    log_l = np.array([[0.0, -50, -50, -50, -50, -50, -50]] * 2)
    after = classifier.update(before, log_mu, log_l, np.array([True, False]))
    assert after[1] is before[1]
    assert after[0].status == "total_conflict"


def test_accumulation_frame_reading() -> None:
    preset = pedestrian()
    on_classes = CredalClassifier(preset.behaviours, preset.relation)
    on_behaviours = CredalClassifier(preset.behaviours, preset.relation, accumulation="behaviours")
    results = []
    for classifier in (on_classes, on_behaviours):
        state = classifier.initial()
        for pl in (np.array([0.0, 1.0, 1e-3]), np.array([0.0, 1e-3, 1.0])):  # walk, then run
            state = classifier.combine(state, classifier.step_mass(pl))
        results.append(state)
    assert results[0].decision() == "sportsman"
    assert results[0].step_conflict == 0.0
    # contours multiply: only {walking} (1e-3) or {running} (1e-3) survive, K = (1 − 1e-3)²
    assert results[1].step_conflict == pytest.approx((1 - 1e-3) ** 2, abs=1e-12)
    assert isinstance(results[1].class_mass, MassFunction)
    assert results[1].class_mass.frame == preset.classes


def test_bayesian_matrix_is_mtt_6_1_2() -> None:
    expected = np.array([[1 / 3, 0, 0], [1 / 3, 1 / 2, 0], [1 / 3, 1 / 2, 1]])
    np.testing.assert_allclose(class_given_behaviour(aircraft().relation), expected)
    np.testing.assert_allclose(
        class_given_behaviour(pedestrian().relation), [[1.0, 0.5, 0.0], [0.0, 0.5, 1.0]]
    )


def test_bayesian_step_eq_9_then_eq_21() -> None:
    preset = aircraft()
    classifier = BayesianClassifier(preset.behaviours, preset.relation)
    log_mu = np.log(np.full((2, 13), 1 / 13))
    log_l = np.zeros((2, 13))
    log_l[:, 1:5] = np.log(0.5)  # b2 = (1 + 4·0.5)/5 = 0.6
    log_l[:, 5:] = np.log(0.25)  # b3 = (1 + 2 + 8·0.25)/13 = 5/13
    state = classifier.update(classifier.initial(2), log_mu, log_l, np.array([True, False]))
    posterior = np.array([1.0, 0.6, 5 / 13]) / (1.6 + 5 / 13)
    np.testing.assert_allclose(state.behaviour_probabilities[0], posterior)
    np.testing.assert_allclose(state.behaviour_probabilities[1], 1 / 3)
    np.testing.assert_allclose(
        classifier.class_probabilities(state)[0], class_given_behaviour(preset.relation) @ posterior
    )
