"""A 3-D radar's range-rate, used by the service and by Stone Soup's EKF on the same detections.

One target per Monte Carlo run, 30–45 km out at 6–10 km altitude, 200 m/s
on a random heading, moving with the session's white-noise acceleration
(``motion.q``); the radar measures range (σ 20 m), azimuth and elevation (σ
0.2°) and range-rate (σ 0.5 m/s) every second. The service runs the same
scan twice, with ``sigma_range_rate`` (the range-rate update of
:mod:`core.tracking.range_rate`) and without (the range-rate ignored); Stone
Soup runs its extended Kalman updater with ``CartesianToElevationBearingRangeRate``
(and, for the run without, ``CartesianToElevationBearingRange``), each started
from the service's estimate at the same scan. With the range-rate the
service's velocity RMSE, whole and radial (along the line of sight), must be
within 5 % of Stone Soup's EKF with it, its radial velocity RMSE under 0.3 × its
own without it, and its mean NEES inside the 95 % χ² interval. The range-rate
tells the radial velocity (3.3 → 0.5 m/s here, as for Stone Soup); the
whole velocity error (≈ 32 m/s) is the cross-range one, which it barely sees
(∂ṙ/∂p is the tangential velocity over the range).
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta
from typing import Any

import httpx
import numpy as np
from scipy.stats import chi2
from stonesoup.models.measurement.nonlinear import (
    CartesianToElevationBearingRange,
    CartesianToElevationBearingRangeRate,
)
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.angle import Bearing, Elevation
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import ExtendedKalmanUpdater

from .conftest import LiveServer

RUNS = 6
SCANS = 20
Q = 1.0  # m²/s³
SIGMA_RANGE = 20.0
SIGMA_ANGLE_DEG = 0.2
SIGMA_RANGE_RATE = 0.5
EPOCH = datetime(2026, 1, 1, tzinfo=UTC)
POSITIONS, VELOCITIES = [0, 2, 4], [1, 3, 5]


def _truth(rng: np.random.Generator) -> np.ndarray:
    """States [x, vx, y, vy, z, vz] over the scans, CV with white-noise acceleration."""
    bearing = math.radians(rng.uniform(0.0, 360.0))
    heading = math.radians(rng.uniform(0.0, 360.0))
    distance = rng.uniform(30_000.0, 45_000.0)
    states = np.zeros((SCANS, 6))
    states[0, POSITIONS] = [
        distance * math.sin(bearing),
        distance * math.cos(bearing),
        rng.uniform(6_000.0, 10_000.0),
    ]
    states[0, VELOCITIES] = [200.0 * math.sin(heading), 200.0 * math.cos(heading), 0.0]
    axis_q = Q * np.array([[1 / 3, 1 / 2], [1 / 2, 1.0]])
    transition = np.array([[1.0, 1.0], [0.0, 1.0]])
    for scan in range(1, SCANS):
        for axis in (slice(0, 2), slice(2, 4), slice(4, 6)):
            noise = rng.multivariate_normal(np.zeros(2), axis_q)
            states[scan, axis] = transition @ states[scan - 1, axis] + noise
    return states


def _measure(states: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Rows (range m, azimuth deg clockwise from north, elevation deg, range-rate m/s)."""
    position, velocity = states[:, POSITIONS], states[:, VELOCITIES]
    distance = np.linalg.norm(position, axis=1)
    azimuth = np.degrees(np.arctan2(position[:, 0], position[:, 1]))
    elevation = np.degrees(np.arcsin(position[:, 2] / distance))
    rate = np.sum(position * velocity, axis=1) / distance
    count = len(states)
    return np.stack(
        [
            distance + rng.normal(0.0, SIGMA_RANGE, count),
            azimuth + rng.normal(0.0, SIGMA_ANGLE_DEG, count),
            elevation + rng.normal(0.0, SIGMA_ANGLE_DEG, count),
            rate + rng.normal(0.0, SIGMA_RANGE_RATE, count),
        ],
        axis=1,
    )


def _service_run(
    client: httpx.Client, measured: np.ndarray, with_rate: bool
) -> list[dict[str, Any] | None]:
    measurement: dict[str, Any] = {
        "kind": "polar",
        "sigma_range": SIGMA_RANGE,
        "sigma_azimuth_deg": SIGMA_ANGLE_DEG,
        "sigma_elevation_deg": SIGMA_ANGLE_DEG,
    }
    if with_rate:
        measurement["sigma_range_rate"] = SIGMA_RANGE_RATE
    config = {
        "state": {"dim": 6, "position": POSITIONS, "velocity": VELOCITIES},
        "motion": {"model": "constant_velocity", "q": Q},
        "sensors": [{"id": "radar", "p_detect": 0.99, "measurement": measurement}],
        "tracking": {"thresholds": {"min_points": 3}},
    }
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
    estimates: list[dict[str, Any] | None] = []
    for scan, (rho, azimuth, elevation, rate) in enumerate(measured.tolist()):
        detection = {
            "range": rho,
            "azimuth_deg": azimuth,
            "elevation_deg": elevation,
            "range_rate": rate,  # sent to both sessions: unused without sigma_range_rate
        }
        body = {"sensor": "radar", "time": float(scan), "detections": [detection]}
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        tracks = answer.json()["tracks"]
        assert len(tracks) <= 1, tracks
        estimates.append(tracks[0] if tracks else None)
    return estimates


def _stonesoup_run(
    with_rate: bool, start: int, prior: dict[str, Any], measured: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Stone Soup's EKF from the service's estimate at ``start``: states, covariances."""
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(Q)] * 3)
    angle = math.radians(SIGMA_ANGLE_DEG) ** 2
    if with_rate:
        model: Any = CartesianToElevationBearingRangeRate(
            ndim_state=6,
            mapping=(0, 2, 4),
            velocity_mapping=(1, 3, 5),
            noise_covar=np.diag([angle, angle, SIGMA_RANGE**2, SIGMA_RANGE_RATE**2]),
        )
    else:
        model = CartesianToElevationBearingRange(
            ndim_state=6, mapping=(0, 2, 4), noise_covar=np.diag([angle, angle, SIGMA_RANGE**2])
        )
    predictor, updater = KalmanPredictor(transition), ExtendedKalmanUpdater(model)
    state = GaussianState(
        StateVector(prior["state"]),
        CovarianceMatrix(prior["covariance"]),
        timestamp=EPOCH + timedelta(seconds=start),
    )
    estimates, covariances = [], []
    for scan in range(start + 1, len(measured)):
        rho, azimuth, elevation, rate = measured[scan]
        time = EPOCH + timedelta(seconds=scan)
        # Stone Soup's bearing is counter-clockwise from x: 90° − azimuth
        values: list[Any] = [
            Elevation(math.radians(elevation)),
            Bearing(math.radians(90.0 - azimuth)),
            rho,
        ]
        if with_rate:
            values.append(rate)
        detection = Detection(StateVector(values), timestamp=time, measurement_model=model)
        prediction = predictor.predict(state, timestamp=time)
        state = updater.update(SingleHypothesis(prediction, detection))
        estimates.append(np.asarray(state.state_vector, dtype=float).ravel())
        covariances.append(np.asarray(state.covar, dtype=float))
    return np.array(estimates), np.array(covariances)


def _velocity_squared(errors: np.ndarray, truth: np.ndarray) -> tuple[list[float], list[float]]:
    """Squared velocity errors: the whole vector, and its radial part (along the line of sight)."""
    line = truth[:, POSITIONS] / np.linalg.norm(truth[:, POSITIONS], axis=1)[:, None]
    velocity = errors[:, VELOCITIES]
    radial = np.sum(velocity * line, axis=1)
    return np.sum(velocity**2, axis=1).tolist(), (radial**2).tolist()


def _nees(errors: np.ndarray, covariances: list[np.ndarray] | np.ndarray) -> list[float]:
    return [
        float(error @ np.linalg.solve(covariance, error))
        for error, covariance in zip(errors, covariances, strict=True)
    ]


def test_range_rate_improves_velocity_as_stonesoup_ekf_does(live_server: LiveServer) -> None:
    rng = np.random.default_rng(29)
    names = ("service", "service_without", "ekf", "ekf_without")
    squared: dict[str, list[float]] = {name: [] for name in names}
    radial: dict[str, list[float]] = {name: [] for name in names}
    nees: dict[str, list[float]] = {"service": [], "ekf": []}
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        for _ in range(RUNS):
            truth = _truth(rng)
            measured = _measure(truth, rng)
            runs = {
                name: _service_run(client, measured, name == "service")
                for name in ("service", "service_without")
            }
            starts = {
                name: next(scan for scan, e in enumerate(run) if e is not None)
                for name, run in runs.items()
            }
            common = max(starts.values())
            assert common <= 8, starts
            for name, run in runs.items():
                after = run[common + 1 :]
                assert all(estimate is not None for estimate in after)
                states = np.array([e["state"] for e in after if e is not None])
                errors = states - truth[common + 1 :]
                whole, along = _velocity_squared(errors, truth[common + 1 :])
                squared[name] += whole
                radial[name] += along
                if name == "service":
                    covariances = [np.asarray(e["covariance"]) for e in after if e is not None]
                    nees["service"] += _nees(errors, covariances)
                start = starts[name]
                prior = run[start]
                assert prior is not None
                with_rate = name == "service"
                estimated, spread = _stonesoup_run(with_rate, start, prior, measured)
                theirs = (estimated - truth[start + 1 :])[common - start :]
                whole, along = _velocity_squared(theirs, truth[common + 1 :])
                squared["ekf" if with_rate else "ekf_without"] += whole
                radial["ekf" if with_rate else "ekf_without"] += along
                if with_rate:
                    nees["ekf"] += _nees(theirs, spread[common - start :])
    rmse = {name: math.sqrt(float(np.mean(values))) for name, values in squared.items()}
    radial_rmse = {name: math.sqrt(float(np.mean(values))) for name, values in radial.items()}
    mean_nees = {name: float(np.mean(values)) for name, values in nees.items()}
    print(f"velocity RMSE (m/s): {rmse}")  # the report's numbers (pytest -s)
    print(f"radial velocity RMSE (m/s): {radial_rmse}")
    samples = len(nees["service"])
    low, high = chi2.ppf([0.025, 0.975], 6 * samples) / samples
    print(f"mean NEES {mean_nees} over {samples} estimates, 95 % interval [{low:.3f}, {high:.3f}]")
    assert rmse["service"] <= 1.05 * rmse["ekf"], rmse
    assert radial_rmse["service"] <= 1.05 * radial_rmse["ekf"], radial_rmse
    assert radial_rmse["service"] <= 0.3 * radial_rmse["service_without"], radial_rmse
    assert low <= mean_nees["service"] <= high, (mean_nees, low, high)
