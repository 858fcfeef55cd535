"""The range-rate update against filterpy's EKF with a numerically differentiated Jacobian."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter
from scipy.stats import norm

from core.errors import InvalidInput, ModelConfigError, TrackingError
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.motion import MotionModel, StateLayout
from core.models.measurement import Polar
from core.tracking.config import LocalTrackerConfig
from core.tracking.imm import IMMState, IMMUpdate
from core.tracking.range_rate import range_rate_update
from core.tracking.tracker import LocalTracker

SITE = (1_000.0, -2_000.0, 30.0)
SIGMA = 0.7


def _range_rate(x: np.ndarray) -> float:
    offset = x[[0, 2, 4]] - np.array(SITE)
    return float(offset @ x[[1, 3, 5]] / np.linalg.norm(offset))


def _numerical_jacobian(x: np.ndarray) -> np.ndarray:
    step = 1e-4
    columns = []
    for i in range(len(x)):
        up, down = x.copy(), x.copy()
        up[i] += step
        down[i] -= step
        columns.append((_range_rate(up) - _range_rate(down)) / (2 * step))
    return np.array([columns])


def _posterior(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    mean = np.array([20_000.0, -150.0, 12_000.0, 80.0, 8_000.0, 5.0])
    mean += rng.normal(0.0, 100.0, 6)
    root = rng.normal(size=(6, 6))
    covariance = root @ root.T + np.diag([400.0, 100.0, 900.0, 400.0, 100.0, 25.0])
    return mean, covariance


def test_each_model_of_each_track_is_filterpy_s_ekf_update() -> None:
    rng = np.random.default_rng(11)
    tracks, models = 3, 2
    means = np.zeros((tracks, models, 6))
    covariances = np.zeros((tracks, models, 6, 6))
    for t in range(tracks):
        for j in range(models):
            means[t, j], covariances[t, j] = _posterior(rng)
    log_mu = np.log(np.array([[0.3, 0.7], [0.5, 0.5], [0.9, 0.1]]))
    position_log_likelihoods = rng.normal(-10.0, 1.0, (tracks, models))
    update = IMMUpdate(
        state=IMMState(means, covariances, log_mu),
        detected=np.ones(tracks, dtype=bool),
        innovations=np.zeros((tracks, models, 3)),
        innovation_covariances=np.tile(np.eye(3), (tracks, models, 1, 1)),
        log_likelihoods=position_log_likelihoods,
    )
    rows = np.array([0, 2])
    measured = np.array([-95.0, 40.0])
    result = range_rate_update(
        update, rows, measured, Polar.of_axes(SITE, (1.0, 1.0, 1.0, SIGMA**2)), axes=3
    )
    for k, t in enumerate(rows.tolist()):
        expected_log_mu = log_mu[t].copy()
        for j in range(models):
            ekf = ExtendedKalmanFilter(dim_x=6, dim_z=1)
            ekf.x, ekf.P, ekf.R = means[t, j].copy(), covariances[t, j].copy(), np.eye(1) * SIGMA**2
            predicted = _range_rate(means[t, j])
            jacobian = _numerical_jacobian(means[t, j])
            ekf.update(
                np.array([measured[k]]),
                lambda _x, h=jacobian: h,
                lambda _x, value=predicted: np.array([value]),
            )
            np.testing.assert_allclose(result.state.means[t, j], ekf.x, rtol=1e-7, atol=1e-6)
            np.testing.assert_allclose(result.state.covariances[t, j], ekf.P, rtol=1e-6, atol=1e-6)
            spread = float((jacobian @ covariances[t, j] @ jacobian.T)[0, 0]) + SIGMA**2
            factor = norm(predicted, math.sqrt(spread)).logpdf(measured[k])
            expected_log_mu[j] += factor
            assert result.log_likelihoods[t, j] == pytest.approx(
                position_log_likelihoods[t, j] + factor, rel=1e-7
            )
        expected = np.exp(expected_log_mu) / np.exp(expected_log_mu).sum()
        np.testing.assert_allclose(result.state.mode_probabilities[t], expected, rtol=1e-6)
    # the track without a range-rate is untouched
    np.testing.assert_array_equal(result.state.means[1], means[1])
    np.testing.assert_array_equal(result.state.covariances[1], covariances[1])


def test_range_rates_need_their_model_velocities_and_one_per_detection() -> None:
    """A scan's range-rates are measured by the scan's model (the report's): without a
    polar model with a range-rate there is no site or σ for them."""
    tracker = LocalTracker(LocalTrackerConfig())
    with pytest.raises(TrackingError, match="polar measurement model with a range-rate"):
        tracker.step(0.0, np.zeros((1, 2)), range_rates=[1.0])
    without_rate = Polar.of_axes((0.0, 0.0), (1.0, 1.0))
    with pytest.raises(TrackingError, match="polar measurement model with a range-rate"):
        tracker.step(0.0, np.zeros((1, 2)), range_rates=[1.0], model=without_rate)
    model = Polar.of_axes((0.0, 0.0), (1.0, 1.0, 1.0))
    pedestrian = LocalTracker(LocalTrackerConfig(preset="pedestrian"))
    with pytest.raises(TrackingError, match="headings"):
        pedestrian.step(0.0, np.zeros((1, 2)), range_rates=[1.0], model=model)
    with pytest.raises(TrackingError, match="range_rates"):
        tracker.step(0.0, np.zeros((2, 2)), range_rates=[1.0], model=model)
    with pytest.raises(TrackingError, match="range_rates"):
        tracker.step(0.0, np.zeros((1, 2)), range_rates=[math.inf], model=model)
    assert pedestrian.time is None
    assert tracker.time is None  # refused scans change nothing
    with pytest.raises(ModelConfigError, match="polar noise"):
        Polar.of_axes((0.0, 0.0), (1.0, 1.0, 0.0))


def test_a_range_rate_on_headings_is_refused_with_one_reason_by_session_and_tracker() -> None:
    """One fact, one check (core.tracking.range_rate.require_velocities): a session whose
    radar measures range-rates under the pedestrian preset (headings, [MTT] eq 26) is refused
    when it is configured, and a tracker given such a scan refuses it, for the same reason."""
    reason = (
        "a range-rate needs velocities in the state, not the headings of the 'pedestrian' preset"
    )
    model = Polar.of_axes((0.0, 0.0), (1.0, 1.0, 1.0))
    config = LocalTrackerConfig(preset="pedestrian")
    layout = StateLayout(dim=4, position=(0, 2), velocity=(1, 3))
    with pytest.raises(InvalidInput) as refused:
        FusionConfig(
            motion=MotionModel(layout, q=1.0),
            sensors=(SensorSpec("walker", tracker=config, model=model),),
        )
    assert str(refused.value) == f"sensor 'walker': {reason}"
    with pytest.raises(TrackingError) as scan:
        LocalTracker(config).step(0.0, np.zeros((1, 2)), range_rates=[1.0], model=model)
    assert str(scan.value) == reason
    # the aircraft preset's velocities take it
    FusionConfig(
        motion=MotionModel(layout, q=1.0),
        sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(), model=model),),
    )
