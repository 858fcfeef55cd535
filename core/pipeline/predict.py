"""Prediction to the step's time, over array state (docs/algorithms.md §4, §6.2, §7.1).

Both layers predict every row in one closed-form step over whatever time
has passed (F(Δt), Q(Δt); a gap costs what one step costs). A zero step is
the estimate itself: a second sensor's scan at the same time, or a report's
own estimates at its own time.
"""

from __future__ import annotations

from core.arrays import FloatArray
from core.fusion.motion import MotionModel
from core.tracking.imm import IMMPrediction, IMMPredictor, IMMState


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
    motion: MotionModel, states: FloatArray, covariances: FloatArray, dt: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Estimates (n, d), (n, d, d) predicted by their own Δt (n,) ([T2T] Fig 2; §6.4, §7.1).

    Δt = 0: the estimate as it is, its covariance symmetrised (P + Pᵀ)/2; a
    negative Δt predicts backwards (a late report, ``MotionModel.predict``).
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
