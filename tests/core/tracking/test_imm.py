"""The batched IMM against filterpy's IMMEstimator, outliers, coasting, batching."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import IMMEstimator, KalmanFilter

from core.errors import TrackingError
from core.numerics import logsumexp
from core.simulation import aircraft_scenario
from core.tracking import IMMPredictor, IMMState, IMMUpdater, ModelBank, two_point_initiation
from core.tracking.presets import aircraft


def _filterpy_imm(bank: ModelBank, state: IMMState) -> tuple[IMMEstimator, list[KalmanFilter]]:
    """filterpy's IMM on the same bank: B u of each model as a one-column B with u = 1."""
    filters = []
    for j, model in enumerate(bank.models):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x = state.means[0, j].reshape(4, 1).copy()
        kf.P = state.covariances[0, j].copy()
        kf.F = model.transition.copy()
        kf.Q = model.process_noise.copy()
        kf.B = model.input_offset.reshape(4, 1).copy()
        kf.H = bank.measurement.matrix.copy()
        kf.R = bank.measurement.noise_covariance.copy()
        filters.append(kf)
    imm = IMMEstimator(filters, state.mode_probabilities[0].copy(), bank.mode_transition.copy())
    return imm, filters


@pytest.fixture(scope="module")
def target_two() -> np.ndarray:
    steps, measurements = aircraft_scenario(seed=3).detections(2)
    assert len(steps) == 100
    return measurements


def test_matches_filterpy_step_by_step(target_two: np.ndarray) -> None:
    bank = aircraft().bank
    z = target_two
    state = two_point_initiation(bank, z[0:1], z[1:2], 1.0)
    imm, filters = _filterpy_imm(bank, state)
    predictor, updater = IMMPredictor(bank), IMMUpdater(bank)
    manoeuvring = 0
    for k in range(2, len(z)):
        imm.predict(u=np.ones((1, 1)))
        imm.update(z[k].reshape(2, 1))
        update = updater.update(predictor.predict(state), z[k : k + 1])
        state = update.state
        mean, covariance = update.combined()
        np.testing.assert_allclose(mean[0], imm.x[:, 0], rtol=0, atol=1e-8)
        np.testing.assert_allclose(covariance[0], imm.P, rtol=0, atol=1e-8)
        np.testing.assert_allclose(update.mode_probabilities[0], imm.mu, rtol=0, atol=1e-8)
        for j, kf in enumerate(filters):
            np.testing.assert_allclose(state.means[0, j], kf.x[:, 0], rtol=0, atol=1e-8)
            np.testing.assert_allclose(state.covariances[0, j], kf.P, rtol=0, atol=1e-8)
        manoeuvring += int(np.argmax(imm.mu) != 0)
    assert manoeuvring >= 10  # the comparison covered both manoeuvres, not only m1


def test_outlier_freezes_filterpy_but_not_us(target_two: np.ndarray) -> None:
    bank = aircraft().bank
    z = target_two[:30]
    state = two_point_initiation(bank, z[0:1], z[1:2], 1.0)
    imm, _ = _filterpy_imm(bank, state)
    predictor, updater = IMMPredictor(bank), IMMUpdater(bank)
    for k in range(2, len(z)):
        imm.predict(u=np.ones((1, 1)))
        imm.update(z[k].reshape(2, 1))
        state = updater.update(predictor.predict(state), z[k : k + 1]).state
    prediction = predictor.predict(state)
    # 2 km ahead along +x: every model's likelihood underflows, (+4g, 0) = m6 is the closest.
    outlier = prediction.combined_measurement()[0] + np.array([[2000.0, 0.0]])
    imm.predict(u=np.ones((1, 1)))
    filterpy_predicted = imm.cbar.copy()
    imm.update(outlier.reshape(2, 1))
    update = updater.update(prediction, outlier)

    np.testing.assert_allclose(imm.mu, filterpy_predicted, rtol=1e-12)  # frozen at c̄
    assert int(np.argmax(imm.mu)) == 0
    assert np.all(np.isfinite(update.log_likelihoods))
    assert np.all(update.log_likelihoods < -1e6)  # exp() of these is 0 in float64
    assert np.all(
        np.isfinite(update.log_mode_probabilities[np.isfinite(update.log_mode_probabilities)])
    )
    assert not np.any(np.isnan(update.mode_probabilities))
    assert int(np.argmax(update.mode_probabilities[0])) == bank.names.index("m6")
    assert update.mode_probabilities[0, bank.names.index("m6")] > 0.999


def test_undetected_tracks_coast_on_their_prediction() -> None:
    bank = aircraft().bank
    z0 = np.array([[0.0, 0.0], [100.0, 50.0]])
    z1 = np.array([[200.0, 30.0], [300.0, 60.0]])
    state = two_point_initiation(bank, z0, z1, 1.0)
    prediction = IMMPredictor(bank).predict(state)
    update = IMMUpdater(bank).update(
        prediction, np.array([[400.0, 60.0], [np.nan, np.nan]]), np.array([True, False])
    )
    np.testing.assert_array_equal(update.state.means[1], prediction.means[1])
    np.testing.assert_array_equal(update.state.covariances[1], prediction.covariances[1])
    np.testing.assert_array_equal(
        update.log_mode_probabilities[1], prediction.log_mode_probabilities[1]
    )
    assert np.all(np.isnan(update.log_likelihoods[1]))
    assert np.all(np.isfinite(update.log_likelihoods[0]))
    assert not np.array_equal(update.state.means[0], prediction.means[0])


def test_batch_equals_tracks_one_by_one() -> None:
    bank = aircraft().bank
    rng = np.random.default_rng(7)
    z0 = rng.normal(0, 1000, (5, 2))
    z1 = z0 + rng.normal(0, 200, (5, 2))
    batch = two_point_initiation(bank, z0, z1, 1.0)
    singles = [batch.select([t]) for t in range(5)]
    predictor, updater = IMMPredictor(bank), IMMUpdater(bank)
    for _ in range(4):
        z = batch.combined()[0][:, [0, 2]] + rng.normal(0, 30, (5, 2))
        batch = updater.update(predictor.predict(batch), z).state
        singles = [
            updater.update(predictor.predict(s), z[t : t + 1]).state for t, s in enumerate(singles)
        ]
    for t, single in enumerate(singles):
        np.testing.assert_allclose(batch.means[t], single.means[0], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(
            batch.log_mode_probabilities[t], single.log_mode_probabilities[0], atol=1e-9
        )


def test_combined_measurement_is_the_moment_match() -> None:
    bank = aircraft().bank
    state = two_point_initiation(bank, np.zeros((1, 2)), np.array([[200.0, 10.0]]), 1.0)
    prediction = IMMPredictor(bank).predict(state)
    z_hat, s = prediction.combined_measurement()
    mu = prediction.mode_probabilities[0]
    expected = mu @ prediction.measurement_means[0]
    np.testing.assert_allclose(z_hat[0], expected)
    spread = prediction.measurement_means[0] - expected
    np.testing.assert_allclose(
        s[0],
        np.einsum("r,rij->ij", mu, prediction.innovation_covariances[0]) + (mu * spread.T) @ spread,
        atol=1e-9,
    )


def test_unreachable_modes_stay_finite() -> None:
    bank = ModelBank(aircraft().bank.models[:2], aircraft().bank.measurement, np.eye(2))
    state = two_point_initiation(
        bank,
        np.zeros((1, 2)),
        np.array([[100.0, 0.0]]),
        1.0,
        mode_probabilities=np.array([1.0, 0.0]),
    )
    update = IMMUpdater(bank).update(IMMPredictor(bank).predict(state), np.array([[210.0, 0.0]]))
    assert update.mode_probabilities[0].tolist() == [1.0, 0.0]
    assert np.all(np.isfinite(update.state.means))


def test_shape_errors() -> None:
    bank = aircraft().bank
    state = two_point_initiation(bank, np.zeros((2, 2)), np.ones((2, 2)), 1.0)
    prediction = IMMPredictor(bank).predict(state)
    with pytest.raises(TrackingError):
        IMMUpdater(bank).update(prediction, np.zeros((3, 2)))
    with pytest.raises(TrackingError):
        IMMUpdater(bank).update(prediction, np.array([[np.inf, 0.0], [0.0, 0.0]]))
    with pytest.raises(TrackingError):
        IMMPredictor(bank).predict(
            IMMState(state.means[:, :3], state.covariances, state.log_mode_probabilities)
        )


def test_logsumexp_handles_empty_groups() -> None:
    values = np.array([[-np.inf, -np.inf], [-1e6, -1e6 - np.log(3.0)]])
    result = logsumexp(values, axis=1)
    assert result[0] == -np.inf
    np.testing.assert_allclose(result[1], -1e6 + np.log(4.0 / 3.0))
