"""The batched credal classifier against the reference :class:`CredalClassifier`.

Same inputs, every option: cumulative masses, class masses, step and running
conflicts, BetP, ``total_conflict`` states and step counts agree within 1e-12,
on random IMM outputs (with zero and one plausibilities and total conflicts
forced in) and on the aircraft / pedestrian replays of [MTT] §6.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from core.belief import Frame, Relation
from core.classification import BehaviourModels, CredalClassification, CredalClassifier
from core.classification.batched import (
    BatchedCredalClassifier,
    CredalBatch,
    dense_to_mass,
    mass_to_dense,
)
from core.errors import ClassificationError
from core.simulation import aircraft_scenario, pedestrian_scenario
from core.simulation.scenario import Scenario
from core.tracking.imm import IMMPredictor, IMMUpdater
from core.tracking.initiator import two_point_initiation
from core.tracking.presets import TrackingPreset, aircraft, pedestrian

TOLERANCE = 1e-12
OPTIONS = list(
    itertools.product(
        ("max", "clip"), ("none", "instantaneous", "cumulative"), ("classes", "behaviours")
    )
)


def _pair(
    preset: TrackingPreset, scale: str, discount: str, accumulation: str
) -> tuple[CredalClassifier, BatchedCredalClassifier]:
    options = {"likelihood_scale": scale, "discount": discount, "accumulation": accumulation}
    return (
        CredalClassifier(preset.behaviours, preset.relation, **options),  # type: ignore[arg-type]
        BatchedCredalClassifier(preset.behaviours, preset.relation, **options),  # type: ignore[arg-type]
    )


def assert_same(
    reference: list[CredalClassification], batch: CredalBatch, batched: BatchedCredalClassifier
) -> None:
    """Every track of ``batch`` equals the reference state within :data:`TOLERANCE`."""
    assert batch.n_tracks == len(reference)
    for row, expected in enumerate(reference):
        np.testing.assert_allclose(
            batch.masses[row], mass_to_dense(expected.mass), rtol=0, atol=TOLERANCE
        )
        np.testing.assert_allclose(
            batch.class_masses[row], mass_to_dense(expected.class_mass), rtol=0, atol=TOLERANCE
        )
        assert batch.status(row) == expected.status
        if expected.pignistic is None:
            assert not batch.defined[row]
        else:
            np.testing.assert_allclose(
                batch.pignistic[row], expected.pignistic, rtol=0, atol=TOLERANCE
            )
        assert batch.step_conflicts[row] == pytest.approx(expected.step_conflict, abs=TOLERANCE)
        if np.isinf(expected.log_normaliser):
            assert batch.log_normalisers[row] == expected.log_normaliser
        else:
            assert batch.log_normalisers[row] == pytest.approx(
                expected.log_normaliser, abs=TOLERANCE
            )
        assert batch.conflicts[row] == pytest.approx(expected.conflict, abs=TOLERANCE)
        assert int(batch.steps[row]) == expected.steps
        # The reference view of the row is the reference state itself.
        back = batched.classification(batch, row)
        assert back.mass.masks.tolist() == expected.mass.masks.tolist()
        assert back.status == expected.status


def _random_imm_output(
    rng: np.random.Generator, tracks: int, models: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    log_mu = np.log(rng.dirichlet(np.full(models, 0.5), tracks))
    log_lambda = rng.normal(0.0, 3.0, (tracks, models))
    # Some tracks whose likelihoods all underflow, some models with Λ = 0 or μ = 0.
    log_lambda[rng.random(tracks) < 0.1] -= 1e4
    log_lambda[rng.random((tracks, models)) < 0.05] = -np.inf
    log_mu[rng.random((tracks, models)) < 0.05] = -np.inf
    log_lambda[rng.random(tracks) < 0.03] = -np.inf  # no model fits at all: m(∅) = 1
    detected = rng.random(tracks) < 0.8
    return log_mu, log_lambda, detected


@pytest.mark.parametrize("name", ["aircraft", "pedestrian"])
@pytest.mark.parametrize(("scale", "discount", "accumulation"), OPTIONS)
def test_random_inputs_match_the_reference(
    name: str, scale: str, discount: str, accumulation: str
) -> None:
    preset = aircraft() if name == "aircraft" else pedestrian()
    reference, batched = _pair(preset, scale, discount, accumulation)
    rng = np.random.default_rng(sum(map(ord, name + scale + discount + accumulation)))
    tracks, models = 40, len(preset.behaviours.model_names)
    states = [reference.initial()] * tracks
    batch = batched.initial(tracks)
    assert_same(states, batch, batched)
    for _ in range(25):
        log_mu, log_lambda, detected = _random_imm_output(rng, tracks, models)
        states = reference.update(states, log_mu, log_lambda, detected)
        batch = batched.update(batch, log_mu, log_lambda, detected)
        assert_same(states, batch, batched)
    if discount == "none":
        assert not batch.defined.all()  # total conflicts did happen (and stayed)


@pytest.mark.parametrize(("scale", "discount", "accumulation"), OPTIONS)
def test_step_masses_and_combine_match_the_reference(
    scale: str, discount: str, accumulation: str
) -> None:
    """GBT + Γ with plausibilities 0 and 1, and :meth:`combine` with arbitrary step masses
    (the phantom hand-over combines two cumulative masses)."""
    preset = pedestrian()
    reference, batched = _pair(preset, scale, discount, accumulation)
    rng = np.random.default_rng(7)
    p = rng.random((60, 3))
    p[rng.random(p.shape) < 0.2] = 0.0
    p[rng.random(p.shape) < 0.2] = 1.0
    dense = batched.step_masses(p)
    for row, pl in enumerate(p):
        np.testing.assert_allclose(
            dense[row], mass_to_dense(reference.step_mass(pl)), rtol=0, atol=TOLERANCE
        )
    states = reference.update(
        [reference.initial()] * 60, np.zeros((60, 7)), rng.normal(0, 2, (60, 7))
    )
    batch = batched.from_classifications(states)
    assert_same(states, batch, batched)
    others = rng.dirichlet(np.ones(dense.shape[1]), 60)
    others[::5] = 0.0
    others[::5, 0] = 1.0  # a total-conflict "step"
    merged = batched.combine(batch, others)
    expected = [
        reference.combine(state, dense_to_mass(batched.frame, other))
        for state, other in zip(states, others, strict=True)
    ]
    assert_same(expected, merged, batched)


def _replay_both(
    scenario: Scenario,
    target: int,
    preset: TrackingPreset,
    reference: CredalClassifier,
    batched: BatchedCredalClassifier,
) -> int:
    """The single-target IMM chain of :func:`core.simulation.replay.replay_single_target`,
    feeding both classifiers; returns the number of steps compared."""
    det_steps, measurements = scenario.detections(target)
    by_step = {int(s): z for s, z in zip(det_steps, measurements, strict=True)}
    state = two_point_initiation(
        preset.bank,
        measurements[0:1],
        measurements[1:2],
        scenario.time_interval * float(det_steps[1] - det_steps[0]),
        velocity=preset.velocity_convention,
    )
    predictor, updater = IMMPredictor(preset.bank), IMMUpdater(preset.bank)
    states = [reference.initial()]
    batch = batched.initial(1)
    compared = 0
    for k in range(int(det_steps[1]) + 1, scenario.n_steps):
        hit = np.array([k in by_step])
        update = updater.update(predictor.predict(state), by_step.get(k, np.zeros(2))[None, :], hit)
        state = update.state
        states = reference.update(
            states, update.log_mode_probabilities, update.log_likelihoods, hit
        )
        batch = batched.update(batch, update.log_mode_probabilities, update.log_likelihoods, hit)
        assert_same(states, batch, batched)
        compared += 1
    return compared


@pytest.mark.parametrize(("scale", "discount", "accumulation"), OPTIONS)
def test_aircraft_replay_matches_the_reference(
    scale: str, discount: str, accumulation: str
) -> None:
    preset = aircraft()
    reference, batched = _pair(preset, scale, discount, accumulation)
    assert _replay_both(aircraft_scenario(seed=0), 2, preset, reference, batched) == 119


@pytest.mark.parametrize(("scale", "discount", "accumulation"), OPTIONS)
def test_pedestrian_replay_matches_the_reference(
    scale: str, discount: str, accumulation: str
) -> None:
    """Includes the near-total conflict at the stop ([MTT] Fig 20, K > 1 − 1e-6)."""
    preset = pedestrian()
    reference, batched = _pair(preset, scale, discount, accumulation)
    assert (
        _replay_both(
            pedestrian_scenario(seed=0, stop_at=60, n_steps=140), 1, preset, reference, batched
        )
        > 130
    )


def test_batch_rows_are_independent_of_the_batch() -> None:
    """select / replace / concatenate move rows without changing them."""
    preset = aircraft()
    _, batched = _pair(preset, "max", "instantaneous", "classes")
    rng = np.random.default_rng(3)
    log_mu, log_lambda, _ = _random_imm_output(rng, 30, 13)
    batch = batched.update(batched.initial(30), log_mu, log_lambda)
    rows = np.array([5, 2, 29])
    alone = batched.update(batched.initial(3), log_mu[rows], log_lambda[rows])
    np.testing.assert_array_equal(batch.select(rows).masses, alone.masses)
    np.testing.assert_array_equal(batch.select(rows).pignistic, alone.pignistic)
    joined = batched.initial(2).concatenate(alone)
    assert joined.n_tracks == 5 and joined.steps.tolist() == [0, 0, 1, 1, 1]
    replaced = batched.initial(30).replace(rows, alone)
    np.testing.assert_array_equal(replaced.masses[rows], alone.masses)
    assert replaced.steps.sum() == 3
    with pytest.raises(ValueError, match="read-only"):
        batch.masses[0, 0] = 1.0


def test_validation() -> None:
    preset = aircraft()
    with pytest.raises(ClassificationError):
        BatchedCredalClassifier(preset.behaviours, preset.relation, discount="sometimes")  # type: ignore[arg-type]
    _, batched = _pair(preset, "max", "none", "classes")
    with pytest.raises(ClassificationError):
        batched.step_masses(np.array([[0.5, 1.5, 0.2]]))
    with pytest.raises(ClassificationError):
        batched.update(batched.initial(2), np.zeros((3, 13)), np.zeros((3, 13)))
    with pytest.raises(ClassificationError):
        batched.combine(batched.initial(2), np.zeros((2, 4)))
    labels = [f"b{i}" for i in range(11)]
    frame = Frame(labels)
    big = BehaviourModels.from_mapping(frame, labels, {b: [b] for b in labels})
    classes = Frame(["c"])
    with pytest.raises(ClassificationError, match="at most"):
        BatchedCredalClassifier(
            big, Relation.from_mapping(frame, classes, {b: ["c"] for b in labels})
        )
