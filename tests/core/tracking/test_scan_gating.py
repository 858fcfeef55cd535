"""ScanGating: a pass's part of the scan's one gating is what gating its tracks and
detections alone gives, pair for pair and number for number (docs/algorithms.md §4)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal

from core.distance import ModifiedScale, steady_state_covariance
from core.lifecycle import ScoreModel
from core.tracking import IMMPredictor
from core.tracking.config import ImmDistance
from core.tracking.gating import ScanGating, gate_pairs
from core.tracking.imm import IMMPrediction, IMMState
from core.tracking.presets import preset


def _prediction(tracks: int, rng: np.random.Generator) -> IMMPrediction:
    bank = preset("aircraft", time_interval=1.0).bank
    means = np.zeros((tracks, bank.state_dim))
    means[:, [0, 2]] = rng.uniform(-2000.0, 2000.0, (tracks, 2))
    means[:, [1, 3]] = rng.normal(0.0, 150.0, (tracks, 2))
    covariances = np.tile(np.diag([400.0, 900.0, 400.0, 900.0]), (tracks, 1, 1))
    modes = rng.dirichlet(np.ones(bank.n_models), tracks)
    return IMMPredictor(bank).predict(IMMState.from_gaussian(means, covariances, modes))


@pytest.mark.parametrize("imm_distance", ["closest_model", "combined", "gated_combined"])
@pytest.mark.parametrize("own_noise", [False, True])
@pytest.mark.parametrize("modified", [False, True])
def test_a_pass_reads_what_gating_its_part_alone_gives(
    imm_distance: ImmDistance, own_noise: bool, modified: bool
) -> None:
    rng = np.random.default_rng(13)
    bank = preset("aircraft", time_interval=1.0).bank
    noise = bank.measurement.noise_covariance
    prediction = _prediction(24, rng)
    centres = prediction.measurement_means[:, 0]
    # detections near most tracks, a few of them between two, and clutter
    z = np.concatenate(
        [centres[::2] + rng.normal(0.0, 10.0, (12, 2)), rng.uniform(-2000.0, 2000.0, (10, 2))]
    )
    covariances = None
    if own_noise:
        covariances = rng.uniform(0.5, 2.0, len(z))[:, None, None] * noise
    scale = None
    if modified:
        first = bank.models[0]
        steady = steady_state_covariance(
            first.transition, first.process_noise, bank.measurement.matrix, noise
        )
        scale = ModifiedScale.of(steady.innovation if not own_noise else steady.innovation - noise)
    gate = float(chi2.ppf(0.999, 2))
    gating = ScanGating(prediction, z, covariances, noise, imm_distance, scale)
    tracks = np.flatnonzero(rng.random(len(centres)) < 0.6)
    detections = np.flatnonzero(rng.random(len(z)) < 0.7)
    part = gating.pairs(gate, tracks, detections)
    alone = gate_pairs(
        IMMPrediction(
            prediction.means[tracks],
            prediction.covariances[tracks],
            prediction.log_mode_probabilities[tracks],
            prediction.measurement_means[tracks],
            prediction.innovation_covariances[tracks],
        ),
        z[detections],
        None if covariances is None else covariances[detections],
        noise,
        gate,
        imm_distance,
        scale,
    )
    assert len(alone.pairs) >= 4  # the part has pairs to compare
    assert len(gating.pairs(gate, np.arange(len(centres)), np.arange(len(z))).pairs) > len(
        alone.pairs
    )
    for mine, reference in (
        (part.pairs.rows, alone.pairs.rows),
        (part.pairs.cols, alone.pairs.cols),
        (part.pairs.distance, alone.pairs.distance),
        (part.pairs.log_det, alone.pairs.log_det),
        (part.plain_distance, alone.plain_distance),
        (part.models, alone.models),
    ):
        np.testing.assert_array_equal(mine, reference)
    assert (part.pairs.n_known, part.pairs.n_incoming) == (len(tracks), len(detections))


def _two_model_prediction(weight: float) -> IMMPrediction:
    """One track of two models in 2-D: a straight one at the origin and a manoeuvre (prior
    ``weight``) 200 m east, both σ = 10 m per axis (the states are not read by the gate)."""
    centres = np.array([[[0.0, 0.0], [200.0, 0.0]]])
    spreads = np.tile(100.0 * np.eye(2), (1, 2, 1, 1))
    log_mu = np.log(np.array([[1.0 - weight, weight]]))
    return IMMPrediction(np.zeros((1, 2, 4)), np.zeros((1, 2, 4, 4)), log_mu, centres, spreads)


@pytest.mark.parametrize("clutter", [1e-8, 1e-6])
def test_outside_the_mixtures_gate_a_detection_stays_only_if_the_bank_explains_it(
    clutter: float,
) -> None:
    """docs/algorithms.md §4: a detection in the manoeuvre model's gate but outside the
    moment-matched mixture's gate is kept when P_D Λ(z) / ((1 − P_D) β_FT) ≥ (1 − β) / α,
    Λ the two-model mixture density (scipy's multivariate normal), else dropped; one
    inside the mixture's gate is kept whatever the clutter."""
    weight, p_detect, alpha, beta = 0.01, 0.9, 1e-3, 1e-3
    prediction = _two_model_prediction(weight)
    z = np.array([[5.0, 3.0], [200.0, 4.0]])
    gate = float(chi2.ppf(0.999, 2))
    score = ScoreModel(p_detect, clutter, 1e-9, alpha, beta)
    found = gate_pairs(
        prediction, z, None, np.eye(2), gate, "gated_combined", None, score.manoeuvre_floor
    )
    # the oracle: the mixture by hand and by scipy
    mean = (1 - weight) * np.zeros(2) + weight * np.array([200.0, 0.0])
    spread = np.array([[200.0, 0.0]]) - mean
    combined = (
        100.0 * np.eye(2) + (1 - weight) * np.outer(mean, mean) + weight * np.outer(spread, spread)
    )
    expected = []
    for col, point in enumerate(z):
        d_combined = (point - mean) @ np.linalg.solve(combined, point - mean)
        mixture = (1 - weight) * multivariate_normal.pdf(
            point, [0.0, 0.0], 100.0 * np.eye(2)
        ) + weight * multivariate_normal.pdf(point, [200.0, 0.0], 100.0 * np.eye(2))
        ratio = p_detect * mixture / ((1 - p_detect) * clutter)
        if d_combined <= gate or ratio >= (1 - beta) / alpha:
            expected.append(col)
    assert 0 in expected  # the straight model's detection: inside the mixture's gate
    assert (1 in expected) == (clutter == 1e-8)  # the manoeuvre: by its evidence
    np.testing.assert_array_equal(found.pairs.cols, expected)
    np.testing.assert_array_equal(found.pairs.rows, np.zeros(len(expected)))
    # without the floor both stay (the closest model gates them)
    unfloored = gate_pairs(prediction, z, None, np.eye(2), gate, "gated_combined", None)
    np.testing.assert_array_equal(unfloored.pairs.cols, [0, 1])
