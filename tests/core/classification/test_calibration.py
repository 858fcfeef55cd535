"""The noise calibration of the mode likelihoods (§8.5, core/classification/calibration.py)."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from core.classification.calibration import (
    noise_calibrated_log_likelihoods,
    resolved_accelerations,
    sharp_predictions,
)
from core.lifecycle import LifeCycleConfig
from core.simulation.nearby import crossing_scenario
from core.tracking.config import ClassificationOptions, LocalTrackerConfig
from core.tracking.tracker import LocalTracker
from evaluation.tracking import track_scenario


def gaussian_log_likelihood(nu: np.ndarray, s: np.ndarray) -> float:
    return float(
        -0.5
        * (nu @ np.linalg.solve(s, nu) + np.linalg.slogdet(s)[1] + len(nu) * math.log(2 * math.pi))
    )


def test_a_model_within_the_noise_band_of_the_best_is_as_plausible_and_one_outside_keeps_its_excess() -> (
    None
):
    """Worked by hand, κ = 3, S = I (q = 2): model 0 fits exactly (ν = 0).
    Model 1 is 1 σ away: d = 1, τ = 3 − 0.5 = 2.5 > its deficit 0.5 → tied with model 0.
    Model 2 is 3 σ away: d = 3, τ = 9 − 4.5 = 4.5, deficit 4.5 → tied, just.
    Model 3 is 8 σ away: d = 8, τ = max(0, 24 − 32) = 0: its deficit 32 stays."""
    s = np.eye(2)
    nus = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 3.0], [8.0, 0.0]])
    raw = np.array([[gaussian_log_likelihood(nu, s) for nu in nus]])
    calibrated = noise_calibrated_log_likelihoods(
        raw, nus[None], np.broadcast_to(s, (1, 4, 2, 2)), significance=3.0
    )
    best = raw[0, 0]
    np.testing.assert_allclose(calibrated[0], [best, best, best, best - 32.0], atol=1e-12)
    # a row without a detection (NaN) is left as it is
    nan_row = noise_calibrated_log_likelihoods(
        np.full((1, 4), np.nan), np.full((1, 4, 2), np.nan), np.broadcast_to(s, (1, 4, 2, 2))
    )
    assert np.all(np.isnan(nan_row))


def straight_airliner_betp(options: ClassificationOptions, seed: int = 3) -> np.ndarray:
    """A 230 m/s straight-and-level aircraft seen every 4 s for 6 minutes by a radar 80 km
    away across its path: converted noise 350 m cross-range (0.25°), 40 m in range, 420 m
    in height (0.3°); BetP of its track at every scan from the 4th on."""
    rng = np.random.default_rng(seed)
    r = np.diag([350.0**2, 40.0**2, 420.0**2])
    tracker = LocalTracker(
        LocalTrackerConfig(
            axes=3,
            time_interval=4.0,
            measurement_noise=tuple(tuple(row) for row in r.tolist()),
            life_cycle=LifeCycleConfig(termination_probability=0.0),
            classification=options,
        )
    )
    betps = []
    for k in range(90):
        t = 4.0 * k
        truth = np.array([230.0 * t, 0.0, 9000.0])
        step = tracker.step(t, (truth + rng.multivariate_normal(np.zeros(3), r))[None])
        confirmed = [track for track in step.tracks if track.status.value == "confirmed"]
        if k >= 3 and confirmed:
            assert confirmed[0].pignistic is not None
            betps.append(confirmed[0].pignistic)
    return np.array(betps)


def test_an_airliner_under_radar_noise_is_not_called_a_fighter() -> None:
    calibrated = straight_airliner_betp(ClassificationOptions())
    assert len(calibrated) > 40
    # every scan leaves the three classes tied: undecided, never fighter or bomber
    np.testing.assert_allclose(calibrated, 1.0 / 3.0, atol=1e-9)
    # control: [MTT]'s raw likelihoods read the same noise as manoeuvres
    raw = straight_airliner_betp(ClassificationOptions(significance=None))
    assert raw[-1][2] > raw[-1][0] + 0.05


def test_the_papers_fighter_is_still_recognised_with_the_calibration() -> None:
    """[MTT] Fig 17–18's crossing scene (0.2 m², 1 s) with the default (calibrated)
    classification: the fighter is decided fighter, the unknown aircraft stays in doubt."""
    variance = 0.2
    scenario = crossing_scenario(seed=0, measurement_variance=variance)
    config = LocalTrackerConfig(
        measurement_noise=((variance, 0.0), (0.0, variance)), fields_of_view={"radar": None}
    )
    run = track_scenario(scenario, config)
    fighter, other = run.track_of(1, 40, 59), run.track_of(2, 40, 59)
    assert fighter is not None and other is not None and fighter != other
    assert run.pignistic_of(fighter, scenario.n_steps, 3)[-1][2] > 0.99
    np.testing.assert_allclose(run.pignistic_of(other, scenario.n_steps, 3)[-1], 1 / 3, atol=1e-9)


def test_a_step_is_evidence_only_where_the_best_model_predicted_sharply() -> None:
    """Worked by hand, q = 3, sharpness 2: R = I; the best model (the larger likelihood)
    predicted with H P Hᵀ = 3.9 I (σ just under twice the detection's: kept) in the first row and 9 I
    (three times: dropped) in the second; the other model's spread does not matter; a row
    without a detection is dropped."""
    eye = np.eye(3)
    predicted = np.array([[3.9 * eye, 100 * eye], [100 * eye, 9 * eye], [eye, eye]])
    innovation = predicted + eye
    log_likelihoods = np.array([[0.0, -1.0], [-1.0, 0.0], [np.nan, np.nan]])
    kept = sharp_predictions(log_likelihoods, innovation, predicted, sharpness=2.0)
    np.testing.assert_array_equal(kept, [True, False, False])


# ------------------------------------------------ accelerations shown by the detections
def _three(times: list[float], positions: np.ndarray, variance: float) -> bool:
    q = positions.shape[-1]
    return bool(
        resolved_accelerations(
            np.array([times]),
            positions[None],
            np.broadcast_to(variance * np.eye(q), (1, 3, q, q)),
        )[0]
    )


def test_the_detections_show_an_acceleration_only_beyond_their_noise() -> None:
    """Equal steps Δ, R = σ² I, q = 2: â = (z₁ − 2z₂ + z₃)/Δ², Var = 6σ²/Δ⁴ per axis, and
    χ²₂'s survival is exp(−x/2), so the threshold of Φ(−κ) is x = −2 ln Φ(−κ): a quadratic
    track at |a| just above √(x · 6σ²/Δ⁴) is resolved, just below is not."""
    kappa, sigma2, dt = 4.5, 0.2, 1.0
    threshold = -2.0 * math.log(0.5 * math.erfc(kappa / math.sqrt(2.0)))
    edge = math.sqrt(threshold * 6.0 * sigma2 / dt**4)
    times = [0.0, dt, 2 * dt]
    direction = np.array([0.6, 0.8])

    def quadratic(a: float) -> np.ndarray:  # x = v t + a t²/2 along a direction
        return np.array([(30.0 * t + 0.5 * a * t**2) * direction for t in times])

    assert _three(times, quadratic(1.01 * edge), sigma2)
    assert not _three(times, quadratic(0.99 * edge), sigma2)
    # the papers' 4g turn at 1 s, 0.2 m²: far beyond (edge ≈ 5.2 m/s²)
    assert _three(times, quadratic(4 * 9.81), sigma2)


def test_a_straight_flyer_at_a_long_revisit_shows_no_acceleration_and_a_turn_beyond_noise_does() -> (
    None
):
    """Unequal steps (4 s, 12 s): a constant velocity is exactly on the line (â = 0);
    â of a quadratic is its acceleration whatever the steps, σ_â = σ √(Σ c_k²) with
    c = 2/(4·16), −2/(4·12), 2/(12·16) (√Σc² = 0.0531): a 2g turn at 50 m noise is
    19.6 against 2.7 (χ²₃ 54, beyond the threshold 28), a 0.3g one at 300 m 2.9
    against 15.9 (not shown)."""
    times = [0.0, 4.0, 16.0]
    straight = np.array([[230.0 * t, -40.0 * t, 9000.0] for t in times])
    assert not _three(times, straight, 1.0)
    for g, sigma, shown in ((2.0, 50.0, True), (0.3, 300.0, False)):
        turn = np.array([[230.0 * t + 0.5 * g * 9.81 * t**2, -40.0 * t, 9000.0] for t in times])
        assert _three(times, turn, sigma**2) is shown


def test_tracks_without_three_detections_show_nothing() -> None:
    positions = np.zeros((2, 3, 2))
    positions[:, 2] = [500.0, 0.0]  # a jump that would be resolved
    times = np.array([[np.nan, 0.0, 1.0], [0.0, 1.0, 2.0]])
    noises = np.broadcast_to(np.eye(2), (2, 3, 2, 2))
    np.testing.assert_array_equal(resolved_accelerations(times, positions, noises), [False, True])


_VELOCITY = np.array([230.0, -90.0])


def _straight_flyer_put_off(
    config: LocalTrackerConfig, sigma: float, dt: float, velocity: np.ndarray
) -> list[Any]:
    """Twenty scans of a straight flyer, its track's velocity then put 235 m/s off per
    axis in every model (as a start or a re-acquisition left it on the real-traffic
    scene), and twenty scans more: the last step's tracks."""
    rng = np.random.default_rng(0)

    def scan(k: int) -> np.ndarray:
        return (np.array([5000.0, 2000.0]) + velocity * dt * k + rng.normal(0, sigma, 2))[None]

    tracker = LocalTracker(config)
    for k in range(20):
        tracker.step(dt * k, scan(k))
    saved = json.loads(json.dumps(tracker.export()))
    (entry,) = saved["tracks"]
    means = np.array(entry["means"]).reshape(13, 4)
    means[:, [1, 3]] += 235.0
    entry["means"] = means.tolist()
    tracker = LocalTracker.restore(config, saved)
    for k in range(20, 40):
        step = tracker.step(dt * k, scan(k))
    return list(step.tracks)


def test_a_straight_flyer_in_the_banks_cycle_at_a_12_s_revisit_stays_undecided() -> None:
    """The aircraft bank at 12 s with σ = 300 m: a straight 230 m/s track whose velocity is
    put 235 m/s off per axis (u Δt / 2 of the diagonal 4g models, as a start or a
    re-acquisition left it on the real-traffic scene) stays in a cycle of opposite 4g
    models — its velocity is still hundreds of m/s off 20 scans later, each step's best
    model far better than constant velocity — but its three detections are on a line
    within their noise at every step, so the class stays vacuous (BetP 1/3 each).

    The cycle is set up without the hit test of a long step (docs/algorithms.md §8.1, "A
    detection after a long gap"), which breaks it at its first far detection (see the
    next test): what is tested here is the classification inside the cycle."""
    sigma, dt = 300.0, 12.0
    config = LocalTrackerConfig(
        measurement_noise=((sigma**2, 0.0), (0.0, sigma**2)),
        life_cycle=LifeCycleConfig(hit_evidence=False),
    )
    (track,) = _straight_flyer_put_off(config, sigma, dt, _VELOCITY)
    assert track.status.value == "confirmed"
    assert np.linalg.norm(track.state[[1, 3]] - _VELOCITY) > 150.0  # still in the cycle
    assert track.pignistic is not None
    np.testing.assert_allclose(track.pignistic, 1.0 / 3.0, atol=1e-9)


def test_the_hit_test_breaks_the_banks_cycle_at_a_12_s_revisit() -> None:
    """The same straight flyer put 235 m/s off per axis, with the defaults: the hit test
    refuses the detection that only a held 4g input reaches, the track coasts once and
    takes the next detections, and its velocity comes back to the truth (within 60 m/s,
    against the 332 m/s it starts off and the hundreds it keeps in the cycle)."""
    sigma, dt = 300.0, 12.0
    config = LocalTrackerConfig(measurement_noise=((sigma**2, 0.0), (0.0, sigma**2)))
    (track,) = _straight_flyer_put_off(config, sigma, dt, _VELOCITY)
    assert track.id == "L1" and track.status.value == "confirmed"
    assert np.linalg.norm(track.state[[1, 3]] - _VELOCITY) < 60.0
