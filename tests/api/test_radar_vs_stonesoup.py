"""A range-azimuth radar scene tracked by the service and by Stone Soup on the same detections.

One target per Monte Carlo run, 35–50 km from the radar, moving with the
continuous white-noise-acceleration model the session declares (``motion.q``),
seen every second with σ_range 20 m and σ_az 0.2°. The service tracks the
polar detections (converted measurements, :mod:`core.models.measurement`); Stone Soup runs
single-target filters with ``CartesianToBearingRange`` and its extended and
unscented Kalman updaters on the same measurements, each started from the
service's first estimate (mean and covariance) at the same scan. The service's
position RMSE and mean GOSPA (Stone Soup's ``GOSPAMetric``, p = 2, c = 500 m,
α = 2, on x, y, each scan after the start: a missing or extra track costs
c²/2) must be within 5 % of the better Stone Soup filter, and its average
NEES (state x, vx, y, vy) inside the two-sided 95 % χ² interval of that many
scans × runs (the two Stone Soup filters' NEES is printed beside it; on this
scene all three agree to 1 %).
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta
from typing import Any

import httpx
import numpy as np
from scipy.stats import chi2
from stonesoup.measures import Euclidean
from stonesoup.metricgenerator.ospametric import GOSPAMetric
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.angle import Bearing
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.state import GaussianState, State
from stonesoup.updater.kalman import ExtendedKalmanUpdater, UnscentedKalmanUpdater

from .conftest import LiveServer

RUNS = 8
SCANS = 25
Q = 1.0  # m²/s³
SIGMA_RANGE = 20.0
SIGMA_AZIMUTH_DEG = 0.2
EPOCH = datetime(2026, 1, 1, tzinfo=UTC)
GOSPA = GOSPAMetric(p=2, c=500.0, measure=Euclidean(mapping=(0, 2)))  # α = 2 (fixed)


def _gospa(estimates: list[np.ndarray], truth: list[np.ndarray], scans: range) -> list[float]:
    """Stone Soup's GOSPA of each scan: the scan's estimated states against its true one."""
    distances = []
    for scan, estimated, true in zip(scans, estimates, truth, strict=True):
        time = EPOCH + timedelta(seconds=scan)
        metric, _ = GOSPA.compute_gospa_metric(
            [State(StateVector(state), timestamp=time) for state in estimated],
            [State(StateVector(true), timestamp=time)],
        )
        distances.append(float(metric.value["distance"]))
    return distances


def _truth(rng: np.random.Generator) -> np.ndarray:
    """States [x, vx, y, vy] over the scans, 35–50 km out, CV with white-noise acceleration."""
    bearing = rng.uniform(20.0, 70.0)
    start = 48_000.0 * np.array([math.sin(math.radians(bearing)), math.cos(math.radians(bearing))])
    heading = math.radians(bearing + 180.0 + rng.uniform(-40.0, 40.0))
    velocity = 150.0 * np.array([math.sin(heading), math.cos(heading)])
    axis_q = Q * np.array([[1 / 3, 1 / 2], [1 / 2, 1.0]])
    transition = np.array([[1.0, 1.0], [0.0, 1.0]])
    states = np.zeros((SCANS, 4))
    states[0] = [start[0], velocity[0], start[1], velocity[1]]
    for scan in range(1, SCANS):
        for axis in (slice(0, 2), slice(2, 4)):
            noise = rng.multivariate_normal(np.zeros(2), axis_q)
            states[scan, axis] = transition @ states[scan - 1, axis] + noise
    return states


def _measure(states: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Range (m) and azimuth (deg clockwise from north) of each state, with the radar's noise."""
    ranges = np.hypot(states[:, 0], states[:, 2]) + rng.normal(0.0, SIGMA_RANGE, len(states))
    azimuths = np.degrees(np.arctan2(states[:, 0], states[:, 2]))
    return ranges, azimuths + rng.normal(0.0, SIGMA_AZIMUTH_DEG, len(states))


def _service_run(
    client: httpx.Client, ranges: np.ndarray, azimuths: np.ndarray
) -> tuple[list[dict[str, Any] | None], list[list[np.ndarray]]]:
    """The service's track of each scan (None before it has one), and every fused state
    it reports at each scan (for GOSPA: an extra track would cost)."""
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "motion": {"model": "constant_velocity", "q": Q},
        "sensors": [
            {
                "id": "radar",
                "p_detect": 0.99,
                "measurement": {
                    "kind": "polar",
                    "sigma_range": SIGMA_RANGE,
                    "sigma_azimuth_deg": SIGMA_AZIMUTH_DEG,
                },
            }
        ],
        "tracking": {"thresholds": {"min_points": 3}},
    }
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    sid, headers = created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}
    estimates: list[dict[str, Any] | None] = []
    every_track: list[list[np.ndarray]] = []
    for scan, (rho, azimuth) in enumerate(zip(ranges, azimuths, strict=True)):
        body = {
            "sensor": "radar",
            "time": float(scan),
            "detections": [{"range": float(rho), "azimuth_deg": float(azimuth)}],
        }
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        tracks = answer.json()["tracks"]
        every_track.append([np.asarray(track["state"]) for track in tracks])
        assert len(tracks) <= 1, tracks
        estimates.append(tracks[0] if tracks else None)
    return estimates, every_track


def _stonesoup_run(
    updater_kind: type[ExtendedKalmanUpdater],
    start: int,
    prior: dict[str, Any],
    ranges: np.ndarray,
    azimuths: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Stone Soup's filter from the service's estimate at ``start``: states [x, vx, y, vy]."""
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(Q), ConstantVelocity(Q)])
    measurement = CartesianToBearingRange(
        ndim_state=4,
        mapping=(0, 2),
        noise_covar=np.diag([math.radians(SIGMA_AZIMUTH_DEG) ** 2, SIGMA_RANGE**2]),
    )
    predictor = KalmanPredictor(transition)
    updater = updater_kind(measurement)
    state = GaussianState(
        StateVector(prior["state"]),
        CovarianceMatrix(prior["covariance"]),
        timestamp=EPOCH + timedelta(seconds=start),
    )
    estimates = []
    covariances = []
    for scan in range(start + 1, len(ranges)):
        time = EPOCH + timedelta(seconds=scan)
        # Stone Soup's bearing is counter-clockwise from x: 90° − azimuth
        detection = Detection(
            StateVector([Bearing(math.radians(90.0 - azimuths[scan])), ranges[scan]]),
            timestamp=time,
            measurement_model=measurement,
        )
        prediction = predictor.predict(state, timestamp=time)
        state = updater.update(SingleHypothesis(prediction, detection))
        estimates.append(np.asarray(state.state_vector, dtype=float).ravel())
        covariances.append(np.asarray(state.covar, dtype=float))
    return np.array(estimates), np.array(covariances)


def test_polar_radar_matches_stonesoup_ekf_and_ukf_and_is_consistent(
    live_server: LiveServer,
) -> None:
    rng = np.random.default_rng(17)
    squared: dict[str, list[float]] = {"service": [], "ekf": [], "ukf": []}
    gospa: dict[str, list[float]] = {"service": [], "ekf": [], "ukf": []}
    nees: list[float] = []
    peer_nees: dict[str, list[float]] = {"ekf": [], "ukf": []}
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        for _ in range(RUNS):
            truth = _truth(rng)
            ranges, azimuths = _measure(truth, rng)
            ours, every_track = _service_run(client, ranges, azimuths)
            start = next(scan for scan, estimate in enumerate(ours) if estimate is not None)
            assert start <= 8, start
            after = ours[start + 1 :]
            assert all(estimate is not None for estimate in after)
            states = np.array([estimate["state"] for estimate in after if estimate is not None])
            covariances = [np.asarray(e["covariance"]) for e in after if e is not None]
            errors = states - truth[start + 1 :]
            squared["service"] += (errors[:, 0] ** 2 + errors[:, 2] ** 2).tolist()
            scans = range(start + 1, SCANS)
            gospa["service"] += _gospa(every_track[start + 1 :], list(truth[start + 1 :]), scans)
            nees += [
                float(error @ np.linalg.solve(covariance, error))
                for error, covariance in zip(errors, covariances, strict=True)
            ]
            prior = ours[start]
            assert prior is not None
            for name, kind in (("ekf", ExtendedKalmanUpdater), ("ukf", UnscentedKalmanUpdater)):
                estimated, spread = _stonesoup_run(kind, start, prior, ranges, azimuths)
                theirs = estimated - truth[start + 1 :]
                squared[name] += (theirs[:, 0] ** 2 + theirs[:, 2] ** 2).tolist()
                gospa[name] += _gospa(
                    [[state] for state in estimated], list(truth[start + 1 :]), scans
                )
                peer_nees[name] += [
                    float(error @ np.linalg.solve(covariance, error))
                    for error, covariance in zip(theirs, spread, strict=True)
                ]
    rmse = {name: math.sqrt(float(np.mean(values))) for name, values in squared.items()}
    print(f"position RMSE (m): {rmse}")  # the report's numbers (pytest -s)
    print(f"Stone Soup mean NEES: { {n: float(np.mean(v)) for n, v in peer_nees.items()} }")
    mean_gospa = {name: float(np.mean(values)) for name, values in gospa.items()}
    print(f"mean GOSPA (m): {mean_gospa}")
    assert rmse["service"] <= 1.05 * min(rmse["ekf"], rmse["ukf"]), rmse
    assert mean_gospa["service"] <= 1.05 * min(mean_gospa["ekf"], mean_gospa["ukf"]), mean_gospa
    samples = len(nees)
    low, high = chi2.ppf([0.025, 0.975], 4 * samples) / samples
    mean_nees = float(np.mean(nees))
    print(
        f"mean NEES {mean_nees:.3f} over {samples} estimates, 95 % interval [{low:.3f}, {high:.3f}]"
    )
    assert low <= mean_nees <= high, (mean_nees, low, high)
