"""Replay one target's own detections through the IMM and the classifiers.

This is the single-target chain of [MTT] §6.1.3 and §6.3.3 (each target
updated with its own measurements, no association): two-point initiation on
the first two detections, then one IMM cycle per step to the end of the
scenario. Steps without a detection (after the target disappears) are
coasting: prediction only, no classification evidence.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.classification import (
    BayesianClassifier,
    CredalClassification,
    CredalClassifier,
)
from core.classification.behaviours import MODE_PROBABILITY_READINGS, ModeProbabilities
from core.errors import ScenarioError
from core.simulation.scenario import Scenario
from core.tracking.imm import IMMPredictor, IMMUpdater
from core.tracking.initiator import two_point_initiation
from core.tracking.presets import TrackingPreset


@dataclass(frozen=True)
class SingleTargetReplay:
    """Per-step outputs of a replay (one row per step from ``steps[0]``).

    Attributes
    ----------
    steps : ndarray of int64, shape (k,)
    detected : ndarray of bool, shape (k,)
    means : ndarray, shape (k, n)
        Combined IMM estimates.
    mode_probabilities : ndarray, shape (k, r)
        Updated μ.
    behaviour_plausibilities : ndarray, shape (k, |B|)
        Scaled Pl({b}) of the step (NaN rows when not detected).
    credal : tuple of CredalClassification
    bayesian : ndarray, shape (k, |C|)
        Class probabilities of the Bayesian baseline.
    """

    steps: IntArray
    detected: BoolArray
    means: FloatArray
    mode_probabilities: FloatArray
    behaviour_plausibilities: FloatArray
    credal: tuple[CredalClassification, ...]
    bayesian: FloatArray

    def index(self, step: int) -> int:
        """Row of ``step``."""
        rows = np.flatnonzero(self.steps == step)
        if rows.size == 0:
            raise ScenarioError(f"step {step} is not in the replay")
        return int(rows[0])

    def pignistic(self) -> FloatArray:
        """Credal BetP per step, shape (k, |C|); NaN rows where undefined (total conflict)."""
        width = len(self.credal[0].class_mass.frame)
        return np.array(
            [
                c.pignistic if c.pignistic is not None else np.full(width, np.nan)
                for c in self.credal
            ]
        )

    def step_conflicts(self) -> FloatArray:
        """K of each step's combination, shape (k,)."""
        return np.array([c.step_conflict for c in self.credal])


def replay_single_target(
    scenario: Scenario,
    target_id: int,
    preset: TrackingPreset,
    credal_options: Mapping[str, Any] | None = None,
    mode_probabilities: ModeProbabilities = "updated",
) -> SingleTargetReplay:
    """Track and classify one target of ``scenario`` on its own detections.

    ``mode_probabilities`` is the μ both classifiers weight the behaviours with
    ([MTT] eq 19/22; the Reading in :mod:`core.classification.behaviours`).
    """
    if mode_probabilities not in MODE_PROBABILITY_READINGS:
        raise ScenarioError(f"mode_probabilities must be one of {MODE_PROBABILITY_READINGS}")
    det_steps, measurements = scenario.detections(target_id)
    if len(det_steps) < 2:
        raise ScenarioError(f"target {target_id} has fewer than two detections")
    by_step = {int(s): z for s, z in zip(det_steps, measurements, strict=True)}
    bank = preset.bank
    state = two_point_initiation(
        bank,
        measurements[0:1],
        measurements[1:2],
        scenario.time_interval * float(det_steps[1] - det_steps[0]),
        velocity=preset.velocity_convention,
    )
    predictor, updater = IMMPredictor(bank), IMMUpdater(bank)
    credal = CredalClassifier(preset.behaviours, preset.relation, **dict(credal_options or {}))
    bayesian = BayesianClassifier(preset.behaviours, preset.relation)
    credal_state = [credal.initial()]
    bayes_state = bayesian.initial(1)

    steps = np.arange(int(det_steps[1]) + 1, scenario.n_steps, dtype=np.int64)
    detected = np.array([int(k) in by_step for k in steps])
    means, mus, plaus, classes, bayes = [], [], [], [], []
    for k, hit in zip(steps, detected, strict=True):
        prediction = predictor.predict(state)
        z = by_step.get(int(k), np.zeros(2))[None, :]
        update = updater.update(prediction, z, np.array([hit]))
        state = update.state
        log_mu = (
            prediction.log_mode_probabilities
            if mode_probabilities == "predicted"
            else update.log_mode_probabilities
        )
        credal_state = credal.update(credal_state, log_mu, update.log_likelihoods, update.detected)
        bayes_state = bayesian.update(bayes_state, log_mu, update.log_likelihoods, update.detected)
        means.append(update.combined()[0][0])
        mus.append(update.mode_probabilities[0])
        plaus.append(
            preset.behaviours.plausibilities(
                log_mu,
                update.log_likelihoods,
                credal.likelihood_scale,
            )[0]
            if hit
            else np.full(len(preset.behaviours.frame), np.nan)
        )
        classes.append(credal_state[0])
        bayes.append(bayesian.class_probabilities(bayes_state)[0])
    return SingleTargetReplay(
        steps=steps,
        detected=detected,
        means=np.array(means),
        mode_probabilities=np.array(mus),
        behaviour_plausibilities=np.array(plaus),
        credal=tuple(classes),
        bayesian=np.array(bayes),
    )
