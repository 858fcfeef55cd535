"""Prediction to the step's time, over array state (docs/algorithms.md §4, §6.2, §7.1).

Both layers predict every row in one closed-form step over whatever time
has passed (F(Δt), Q(Δt); a gap costs what one step costs). A zero step is
the estimate itself: a second sensor's scan at the same time, or a report's
own estimates at its own time.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core.arrays import FloatArray, IntArray
from core.models import MappedMotion
from core.tracking.imm import IMMPrediction, IMMPredictor, IMMState
from core.tracking.models import ModelBank


def predict_bank(predictor: IMMPredictor, state: IMMState, elapsed: float) -> IMMPrediction:
    """The IMM prediction of every track over ``elapsed`` ≥ 0 s ([MTT] §3; §7.1).

    ``elapsed == 0``: the posterior as it is, with its measurement-space
    moments ẑ = H x, S = H P Hᵀ + R (no mixing, no process noise).
    """
    if elapsed == 0.0:
        bank = predictor.bank
        h = bank.measurement.matrix
        h_t = h.T
        return IMMPrediction(
            means=state.means,
            covariances=state.covariances,
            log_mode_probabilities=state.log_mode_probabilities,
            measurement_means=state.means @ h_t,
            innovation_covariances=h @ state.covariances @ h_t + bank.measurement.noise_covariance,
        )
    return predictor.predict(state, elapsed)


def predict_estimates(
    motion: MappedMotion, states: FloatArray, covariances: FloatArray, dt: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Estimates (n, d), (n, d, d) predicted by their own Δt (n,) ([T2T] Fig 2; §6.4, §7.1).

    Δt = 0: the estimate as it is, its covariance symmetrised (P + Pᵀ)/2; a
    negative Δt predicts backwards (a late report, ``MappedMotion.predict``).
    """
    predicted, predicted_cov = states.copy(), covariances.copy()
    now = dt == 0.0
    if now.any():
        own = covariances[now]
        predicted_cov[now] = (own + own.swapaxes(-1, -2)) / 2.0
    later = ~now
    if later.any():
        predicted[later], predicted_cov[later] = motion.predict(
            states[later], covariances[later], dt[later]
        )
    return predicted, predicted_cov


def without_inputs(
    prediction: IMMPrediction, bank: ModelBank, rows: IntArray, elapsed: float
) -> IMMPrediction:
    """``prediction`` with the models of ``rows`` predicted without their input ``B(Δt) u``.

    For single-point starts (docs/algorithms.md §8.3): two detections give a
    velocity and nothing about an acceleration, and the start's velocity prior
    is wide, so a held-input model "explains" the displacement of the second
    detection by a manoeuvre — at a 12 s revisit a 4g model moves the start
    2.8 km per axis, more than the prior's velocity — and leaves the start
    with a velocity wrong by about ``u Δt``. With every model predicted as
    constant velocity the second detection sets the two-point velocity in
    every model (the models' states and likelihoods are then equal, the mode
    probabilities unchanged), as a two-point initiation does ([MTT] §4.2).
    """
    if len(rows) == 0 or elapsed == 0.0:
        return prediction
    offsets = bank.at(elapsed).input_offset  # (r, n)
    if not np.any(offsets):
        return prediction
    means = prediction.means.copy()
    means[rows] -= offsets[None, :, :]
    measurement_means = prediction.measurement_means.copy()
    measurement_means[rows] -= (offsets @ bank.measurement.matrix.T)[None, :, :]
    return replace(prediction, means=means, measurement_means=measurement_means)
