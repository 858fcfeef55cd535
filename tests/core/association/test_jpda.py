"""JPDA by exact enumeration (:mod:`core.association.jpda`) against two independent oracles:
a brute-force enumeration of every partial matching written from the definitions, and
Stone Soup's own ``JPDA`` with ``PDAHypothesiser`` (stonesoup/dataassociator/probability.py).
It is the method added through the registry alone (its module, one registry line): the
local tracker runs it unchanged."""

from __future__ import annotations

import datetime
import math

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal

from core.association import associate_measurements
from core.errors import OptionError
from core.simulation import aircraft_scenario
from core.tracking.config import LocalTrackerConfig
from tests.core.association.brute_force import partial_matchings
from tests.core.tracking.tracking_runs import run_tracker

P_DETECT, CLUTTER, P_GATE = 0.8, 2e-3, 0.99


def brute_force(zhat, s, z, p_detect, clutter, p_gate):
    """β_tj and the MAP event from every partial matching of the gated pairs (definitions)."""
    n, m = len(zhat), len(z)
    gate = chi2.ppf(p_gate, z.shape[1])
    ratio = np.zeros((n, m))
    gated = np.zeros((n, m), dtype=bool)
    for t in range(n):
        for j in range(m):
            nu = z[j] - zhat[t]
            gated[t, j] = nu @ np.linalg.inv(s[t]) @ nu <= gate
            ratio[t, j] = p_detect * multivariate_normal(zhat[t], s[t]).pdf(z[j]) / clutter
    events, weights = [], []
    for event in partial_matchings(n, m):
        if all(gated[t, j] for t, j in event):
            weight = math.prod(ratio[t, j] for t, j in event)
            weight *= (1.0 - p_detect * p_gate) ** (n - len(event))
            events.append(event)
            weights.append(weight)
    total = sum(weights)
    beta = np.zeros((n, m))
    for event, weight in zip(events, weights, strict=True):
        for t, j in event:
            beta[t, j] += weight / total
    best = events[int(np.argmax(weights))]
    return beta, set(best)


def a_scene(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Three tracks close together, four detections among them, and a far pair."""
    rng = np.random.default_rng(seed)
    zhat = np.vstack([rng.uniform(0.0, 4.0, size=(3, 2)), [[100.0, 100.0]]])
    s = np.array([np.diag(rng.uniform(0.5, 2.0, size=2)) for _ in range(4)])
    z = np.vstack([rng.uniform(-1.0, 5.0, size=(4, 2)), [[100.5, 99.5]], [[-60.0, 0.0]]])
    return zhat, s, z


@pytest.mark.parametrize("seed", range(6))
def test_jpda_is_the_brute_force_enumeration(seed: int) -> None:
    zhat, s, z = a_scene(seed)
    options = {"p_detect": P_DETECT, "clutter_density": CLUTTER, "gate_probability": P_GATE}
    result = associate_measurements(zhat, s, z, "jpda", options)
    beta, best = brute_force(zhat, s, z, P_DETECT, CLUTTER, P_GATE)
    np.testing.assert_allclose(result.scores.dense(), beta, rtol=1e-10, atol=1e-15)
    assert set(result.assignment().items()) == best
    np.testing.assert_allclose(result.scores.new, 1.0 - beta.sum(axis=0), atol=1e-12)


def test_jpda_is_stone_soups() -> None:
    """Two tracks sharing three detections (one outside both gates): Stone Soup's JPDA
    marginals, from its own Kalman prediction, PDAHypothesiser and joint enumeration."""
    from stonesoup.dataassociator.probability import JPDA
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import (
        CombinedLinearGaussianTransitionModel,
        ConstantVelocity,
    )
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.types.detection import Detection
    from stonesoup.types.state import GaussianState
    from stonesoup.types.track import Track
    from stonesoup.updater.kalman import KalmanUpdater

    start = datetime.datetime(2026, 1, 1)
    now = start + datetime.timedelta(seconds=1)
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
    predictor = KalmanPredictor(
        CombinedLinearGaussianTransitionModel([ConstantVelocity(0.05), ConstantVelocity(0.05)])
    )
    updater = KalmanUpdater(measurement)
    starts = [np.array([0.0, 1.0, 0.0, -0.5]), np.array([2.0, 0.5, 0.5, 0.0])]
    covariance = np.diag([1.0, 0.3, 1.5, 0.2])
    tracks = [Track([GaussianState(x[:, None], covariance, timestamp=start)]) for x in starts]
    z = np.array([[1.2, -0.1], [2.1, 0.3], [1.8, -0.8], [30.0, 30.0]])
    detections = [
        Detection(row[:, None], timestamp=now, measurement_model=measurement) for row in z
    ]
    hypothesiser = PDAHypothesiser(
        predictor=predictor,
        updater=updater,
        clutter_spatial_density=CLUTTER,
        prob_detect=P_DETECT,
        prob_gate=P_GATE,
    )
    answer = JPDA(hypothesiser=hypothesiser).associate(set(tracks), set(detections), now)
    predicted = [
        updater.predict_measurement(predictor.predict(track.state, timestamp=now))
        for track in tracks
    ]
    zhat = np.array([np.asarray(p.state_vector, dtype=float).ravel() for p in predicted])
    s = np.array([np.asarray(p.covar, dtype=float) for p in predicted])
    options = {"p_detect": P_DETECT, "clutter_density": CLUTTER, "gate_probability": P_GATE}
    ours = associate_measurements(zhat, s, z, "jpda", options).scores.dense()
    theirs = np.zeros((2, 4))
    for t, track in enumerate(tracks):
        for hypothesis in answer[track]:
            if hypothesis:
                j = next(k for k, d in enumerate(detections) if d is hypothesis.measurement)
                theirs[t, j] = float(hypothesis.probability)
    assert np.count_nonzero(theirs[:, :3]) >= 4  # the tracks compete for the detections
    np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-14)


def test_a_cluster_too_large_to_enumerate_is_refused_by_name() -> None:
    zhat = np.zeros((6, 2))
    s = np.tile(np.eye(2), (6, 1, 1))
    with pytest.raises(OptionError, match="max_events"):
        associate_measurements(zhat, s, np.zeros((6, 2)), "jpda", {"max_events": 1000})


def test_the_local_tracker_runs_jpda_unchanged() -> None:
    """Every aircraft keeps one confirmed track (as the cheap JPDA baseline does)."""
    scenario = aircraft_scenario(seed=0)
    config = LocalTrackerConfig.paper(association_method="jpda")
    run = run_tracker(scenario, config)
    for target in (1, 3, 4):
        track = run.track_of(target)
        assert run.owners[track] == {target: len(run.assigned[target]) - 1}  # the seed has no track
        assert run.status[track][scenario.n_steps - 1][0] == "confirmed"
