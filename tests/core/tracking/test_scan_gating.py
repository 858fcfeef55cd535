"""ScanGating: a pass's part of the scan's one gating is what gating its tracks and
detections alone gives, pair for pair and number for number (docs/algorithms.md §4)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from core.distance import ModifiedScale, steady_state_covariance
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
