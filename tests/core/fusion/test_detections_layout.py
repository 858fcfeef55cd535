"""Local tracks on the session's layout: any order, 3-D, headings turned into velocities."""

from __future__ import annotations

import numpy as np
import pytest

from core.distance.estimates import check_covariances
from core.errors import InvalidInput
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.detections import check_layout_for_detections, heading_to_velocity, local_order
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import DetectionReport
from core.simulation import aircraft_scenario
from core.tracking.config import LocalTrackerConfig
from core.tracking.presets import pedestrian


def test_heading_tracks_along_one_axis_get_a_positive_definite_velocity() -> None:
    """Under the (2, 0) walking model alone the y velocity is 0 exactly: J P Jᵀ is singular,
    and the per-scan position noise q ΔT²/4 of the model (module Reading) is its variance."""
    bank = pedestrian().bank  # q = 0.001, ΔT = 1 s
    mu = np.zeros(bank.n_models)
    mu[1] = 1.0  # m2 = (2, 0)
    state = np.array([3.0, 1.0, 50.0, 1.0])
    covariance = np.diag([0.04, 0.01, 0.04, 0.01])
    covariance[0, 1] = covariance[1, 0] = 0.005
    mean, velocity_covariance = heading_to_velocity(bank, mu, state, covariance)
    jacobian = np.diag([1.0, 2.0, 1.0, 0.0])
    expected = jacobian @ covariance @ jacobian.T + np.diag([0.0, 0.001 / 4, 0.0, 0.001 / 4])
    np.testing.assert_allclose(mean, [3.0, 2.0, 50.0, 0.0], rtol=1e-15)
    np.testing.assert_allclose(velocity_covariance, expected, rtol=1e-13, atol=1e-18)
    check_covariances(velocity_covariance[None], "tracks")


def test_heading_velocity_adds_the_spread_between_models() -> None:
    """Two models with weight ½: mean ŝ h, and the spread (s_j h − ŝ h)² / 4 on the velocity."""
    bank = pedestrian().bank
    mu = np.zeros(bank.n_models)
    mu[0] = mu[1] = 0.5  # (0, 0) and (2, 0)
    state = np.array([0.0, 1.0, 0.0, 1.0])
    covariance = 0.01 * np.eye(4)
    mean, combined = heading_to_velocity(bank, mu, state, covariance)
    np.testing.assert_allclose(mean, [0.0, 1.0, 0.0, 0.0], atol=1e-15)
    # x velocity: ½ (0 + 0.001/4) + ½ (4 · 0.01 + 0.001/4) + spread ½·1 + ½·1
    np.testing.assert_allclose(combined[1, 1], 0.02 + 0.001 / 4 + 1.0, rtol=1e-13)
    np.testing.assert_allclose(combined[3, 3], 0.001 / 4, rtol=1e-13)


def test_layout_order_and_refusals() -> None:
    assert local_order(StateLayout(4, (0, 1), (2, 3))) == (0, 2, 1, 3)
    assert local_order(StateLayout(6, (0, 2, 4), (1, 3, 5))) == (0, 1, 2, 3, 4, 5)
    assert local_order(StateLayout(6, (3, 4, 5), (0, 1, 2))) == (3, 0, 4, 1, 5, 2)
    for refused in (StateLayout(5, (0, 2), (1, 3)), StateLayout(4, (0, 2))):
        with pytest.raises(InvalidInput, match="dim = 2 × positions"):
            check_layout_for_detections(refused)


def test_detections_on_a_position_first_layout() -> None:
    """``[x, y, vx, vy]``: the fused states hold the positions at 0, 1 and velocities at 2, 3."""
    layout = StateLayout(4, (0, 1), (2, 3))
    engine = SessionEngine(
        FusionConfig(
            motion=MotionModel(layout, q=100.0),
            sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(classification=None)),),
        )
    )
    scenario = aircraft_scenario(seed=0)
    for scan in scenario.scans[:12]:
        step = engine.apply_detections(DetectionReport(scan.sensor, scan.time, scan.measurements))
    truth = scenario.truth(1).state_at(11)
    nearest = min(step.tracks, key=lambda t: float(np.hypot(*(t.state[:2] - truth[[0, 2]]))))
    np.testing.assert_allclose(nearest.state[:2], truth[[0, 2]], atol=3.0)
    np.testing.assert_allclose(nearest.state[2:], truth[[1, 3]], atol=10.0)
