"""Tracking over any time step: closed-form models at Δt, no ΔT grid, long gaps, jittered scans."""

from __future__ import annotations

from datetime import timedelta

import numpy as np
import pytest
from filterpy.common import Q_continuous_white_noise
from filterpy.kalman import KalmanFilter
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)

from core.errors import ModelConfigError
from core.tracking import (
    IMMPredictor,
    IMMState,
    LinearMeasurementModel,
    ModelBank,
    constant_velocity,
)
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import acceleration_input, mode_transition_matrix, speed_model
from core.tracking.presets import GRAVITY, aircraft, pedestrian
from core.tracking.tracker import LocalTracker

RNG_SEED = 20261201


def _cv_bank(q: float, axes: int) -> ModelBank:
    """One continuous-noise constant-velocity model (the ``motion.q`` model)."""
    model = constant_velocity(1.0, q, axes=axes, noise="continuous")
    return ModelBank((model,), LinearMeasurementModel.position(0.5, 2 * axes), np.ones((1, 1)))


def _random_gaussian(
    rng: np.random.Generator, tracks: int, n: int
) -> tuple[np.ndarray, np.ndarray]:
    mean = rng.normal(0.0, 100.0, (tracks, n))
    root = rng.normal(0.0, 1.0, (tracks, n, n))
    return mean, root @ np.swapaxes(root, 1, 2) + 0.1 * np.eye(n)


# ------------------------------------------------------------ closed forms
@pytest.mark.parametrize("axes", [1, 2, 3])
@pytest.mark.parametrize("k", [2, 7, 1000])
def test_cv_once_by_dt_equals_k_times_by_dt_over_k(axes: int, k: int) -> None:
    rng = np.random.default_rng(RNG_SEED + k)
    bank = _cv_bank(3.7, axes)
    mean, covariance = _random_gaussian(rng, 5, 2 * axes)
    predictor = IMMPredictor(bank)
    dt = 4.3
    once = predictor.predict(IMMState.from_gaussian(mean, covariance, np.ones(1)), dt)
    state = IMMState.from_gaussian(mean, covariance, np.ones(1))
    for _ in range(k):
        state = predictor.predict(state, dt / k).as_state()
    np.testing.assert_allclose(state.means, once.means, rtol=1e-9, atol=0.0)
    np.testing.assert_allclose(state.covariances, once.covariances, rtol=1e-9, atol=1e-9)


def test_cv_prediction_equals_filterpy_and_stone_soup() -> None:
    """F(Δt), Q(Δt) of the continuous CV model against filterpy's predict and Stone Soup's Q."""
    q, dt = 2.5, 0.37
    bank = _cv_bank(q, 2)
    rng = np.random.default_rng(RNG_SEED)
    mean, covariance = _random_gaussian(rng, 1, 4)
    ours = IMMPredictor(bank).predict(IMMState.from_gaussian(mean, covariance, np.ones(1)), dt)

    axis = ConstantVelocity(noise_diff_coeff=q)
    stone_soup = CombinedLinearGaussianTransitionModel([axis, axis])
    np.testing.assert_allclose(
        bank.at(dt).process_noise[0],
        stone_soup.covar(time_interval=timedelta(seconds=dt)),
        rtol=1e-12,
    )
    np.testing.assert_allclose(
        bank.at(dt).transition[0],
        stone_soup.matrix(time_interval=timedelta(seconds=dt)),
        rtol=1e-12,
    )

    kf = KalmanFilter(dim_x=4, dim_z=2)
    kf.x = mean[0].reshape(4, 1).copy()
    kf.P = covariance[0].copy()
    kf.F = np.array([[1, dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, dt], [0, 0, 0, 1]], dtype=float)
    per_axis = Q_continuous_white_noise(dim=2, dt=dt, spectral_density=q)
    kf.Q = np.kron(np.eye(2), per_axis)
    kf.predict()
    np.testing.assert_allclose(ours.means[0, 0], kf.x[:, 0], rtol=1e-12)
    np.testing.assert_allclose(ours.covariances[0, 0], kf.P, rtol=1e-12)


@pytest.mark.parametrize("dt", [0.0, 0.3, 1.0, 2.6, 1e6])
def test_paper_models_closed_form_at_any_dt(dt: float) -> None:
    """[MTT] eq 24 / 26 at Δt, written out by hand: F, B(Δt) u, q B(Δt) B(Δt)ᵀ."""
    u, q = (2 * GRAVITY, -GRAVITY), 0.005
    b = np.array([[dt**2 / 2, 0], [dt, 0], [0, dt**2 / 2], [0, dt]])
    matrices = acceleration_input(1.0, u, q, "m").at(dt)
    np.testing.assert_array_equal(
        matrices.transition, [[1, dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, dt], [0, 0, 0, 1]]
    )
    np.testing.assert_allclose(matrices.input_offset, b @ np.array(u), rtol=1e-15)
    np.testing.assert_allclose(matrices.process_noise, q * b @ b.T, rtol=1e-15)
    walk = speed_model(1.0, (6.0, 2.0), q, "run").at(dt)
    np.testing.assert_array_equal(
        walk.transition, [[1, 6 * dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2 * dt], [0, 0, 0, 1]]
    )


def test_presets_reproduce_the_paper_at_the_nominal_step() -> None:
    b = np.array([[0.5, 0], [1, 0], [0, 0.5], [0, 1]])
    bank = aircraft().bank
    at = bank.at(1.0)
    np.testing.assert_array_equal(at.process_noise, bank.process_noises)
    np.testing.assert_allclose(at.process_noise[0], 0.005 * b @ b.T, rtol=1e-15)
    np.testing.assert_array_equal(bank.mode_transition_at(1.0), mode_transition_matrix(13, 0.95))


def test_mean_and_input_compose_over_split_steps_for_every_paper_model() -> None:
    """F(a + b) = F(b) F(a) and the input term composes; the discrete Q does not (module docstring)."""
    for bank in (aircraft().bank, pedestrian().bank):
        a, b = 0.4, 1.9
        first, second, whole = bank.at(a), bank.at(b), bank.at(a + b)
        np.testing.assert_allclose(
            second.transition @ first.transition, whole.transition, rtol=1e-12
        )
        composed = (
            np.einsum("rij,rj->ri", second.transition, first.input_offset) + second.input_offset
        )
        np.testing.assert_allclose(composed, whole.input_offset, rtol=1e-12, atol=1e-12)
    bank = aircraft().bank
    first, second, whole = bank.at(0.5), bank.at(0.5), bank.at(1.0)
    split = second.transition @ first.process_noise @ np.swapaxes(second.transition, 1, 2)
    assert not np.allclose(split + second.process_noise, whole.process_noise)


def test_mode_transition_is_a_power_per_nominal_scan() -> None:
    bank = aircraft(stay=0.9).bank
    pi = bank.mode_transition
    np.testing.assert_allclose(bank.mode_transition_at(3.0), pi @ pi @ pi, rtol=1e-10, atol=1e-15)
    half = bank.mode_transition_at(0.5)
    np.testing.assert_allclose(half @ half, pi, rtol=1e-10, atol=1e-15)
    # the stay family's closed form: Π^p = λ^p I + (1 − λ^p) 11ᵀ / r
    r, lam, p = 13, 0.9 - 0.1 / 12, 2.37
    expected = lam**p * np.eye(r) + (1 - lam**p) / r
    np.testing.assert_allclose(bank.mode_transition_at(p), expected, rtol=1e-10, atol=1e-15)
    np.testing.assert_array_equal(bank.mode_transition_at(0.0), np.eye(r))
    np.testing.assert_allclose(bank.mode_transition_at(1e6), np.full((r, r), 1 / r), rtol=1e-9)
    with pytest.raises(ModelConfigError, match="negative eigenvalue"):
        ModelBank.from_config(
            {
                "models": [{"kind": "constant_velocity"}, {"kind": "speed", "name": "s"}],
                "mode_transition": [[0.0, 1.0], [1.0, 0.0]],
            }
        )


# ------------------------------------------------------------- the tracker
def _straight_targets(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts on a 3 km grid and 200 m/s velocities in every direction."""
    side = int(np.ceil(np.sqrt(count)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)
    start = 3000.0 * grid[:count].astype(np.float64)
    heading = np.linspace(0.0, 2 * np.pi, count, endpoint=False)
    return start, 200.0 * np.stack([np.cos(heading), np.sin(heading)], axis=1)


def _position_rms(times: np.ndarray, noise: np.ndarray, warm: int) -> float:
    """Position RMS of the confirmed tracks' estimates against the truth, scans after ``warm``."""
    start, velocity = _straight_targets(noise.shape[1])
    tracker = LocalTracker(LocalTrackerConfig.paper(classification=None))
    errors = []
    for k, t in enumerate(times):
        truth = start + t * velocity
        step = tracker.step(float(t), truth + noise[k])
        if k < warm:
            continue
        tracks = {track.id: track for track in step.tracks if track.status.value == "confirmed"}
        for target, track_id in enumerate(step.assignment):
            if track_id in tracks:  # a 1-in-1000 gate miss leaves a target out of one scan
                errors.append(tracks[track_id].state[[0, 2]] - truth[target])
    assert len(errors) >= 0.99 * (len(times) - warm) * noise.shape[1]
    return float(np.sqrt(np.mean(np.square(errors))))


def test_jittered_scans_track_as_well_as_the_grid() -> None:
    rng = np.random.default_rng(RNG_SEED)
    scans, targets = 60, 16
    noise = rng.normal(0.0, np.sqrt(0.2), (scans, targets, 2))
    regular = np.arange(scans, dtype=np.float64)
    jittered = regular + rng.uniform(-0.12, 0.12, scans)
    jittered[0] = 0.0
    assert np.all(np.diff(jittered) > 0) and not np.allclose(np.diff(jittered), 1.0)
    grid_rms = _position_rms(regular, noise, warm=8)
    jitter_rms = _position_rms(jittered, noise, warm=8)
    assert grid_rms < 0.6  # the estimates are good to begin with (R = 0.2 I)
    assert abs(jitter_rms / grid_rms - 1.0) <= 0.05


def test_a_long_gap_is_one_prediction(monkeypatch: pytest.MonkeyPatch) -> None:
    """A scan 1e6 s after the last is accepted and predicted in one step; no detection can keep
    tracks that uncertain (their best hit increment is below the delete threshold), so they are
    not associated: they miss, their gates empty ([HZ] §4.2), and the targets start anew."""
    start, velocity = _straight_targets(4)
    tracker = LocalTracker(LocalTrackerConfig.paper())
    for k in range(6):
        tracker.step(float(k), start + k * velocity)
    calls: list[float | None] = []
    original = IMMPredictor.predict

    def counting(self: IMMPredictor, state: IMMState, dt: float | None = None) -> object:
        calls.append(dt)
        return original(self, state, dt)

    monkeypatch.setattr(IMMPredictor, "predict", counting)
    later = 5.0 + 1e6
    step = tracker.step(later, start + later * velocity)
    assert calls == [1e6]
    assert step.assignment == (None,) * 4
    assert [(t.status.value, t.reason.value) for t in step.tracks] == [
        ("terminated", "gate_emptiness")
    ] * 4
    for k in (1, 2):
        step = tracker.step(later + k, start + (later + k) * velocity)
    assert [t.status.value for t in step.tracks] == ["confirmed"] * 4
    assert all(track_id is not None for track_id in step.assignment)


def test_a_moderate_gap_keeps_the_tracks() -> None:
    """After 20 s without scans the tracks are still associated and keep their ids."""
    start, velocity = _straight_targets(4)
    tracker = LocalTracker(LocalTrackerConfig.paper())
    for k in range(6):
        step = tracker.step(float(k), start + k * velocity)
    ids = step.assignment
    later = 25.0
    step = tracker.step(later, start + later * velocity)
    assert step.assignment == ids


@pytest.mark.parametrize("factory", [aircraft, pedestrian])
def test_3d_presets_add_a_vertical_constant_velocity_axis(factory: object) -> None:
    """Horizontal blocks as in 2-D; z: F = [[1, Δt], [0, 1]], no input, q B Bᵀ; H picks x, y, z."""
    flat, spatial = factory(), factory(axes=3)  # type: ignore[operator]
    dt = 1.7
    planar, full = flat.bank.at(dt), spatial.bank.at(dt)
    np.testing.assert_array_equal(full.transition[:, :4, :4], planar.transition)
    np.testing.assert_array_equal(full.process_noise[:, :4, :4], planar.process_noise)
    np.testing.assert_array_equal(full.input_offset[:, :4], planar.input_offset)
    q = spatial.bank.models[0].noise_intensity
    b = np.array([dt**2 / 2, dt])
    for j in range(spatial.bank.n_models):
        np.testing.assert_array_equal(full.transition[j, 4:, 4:], [[1, dt], [0, 1]])
        np.testing.assert_array_equal(full.input_offset[j, 4:], [0.0, 0.0])
        np.testing.assert_allclose(full.process_noise[j, 4:, 4:], q * np.outer(b, b), rtol=1e-15)
        assert not np.any(full.process_noise[j, :4, 4:])
    np.testing.assert_array_equal(
        spatial.bank.measurement.matrix,
        [[1, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 0, 0, 0, 1, 0]],
    )
    assert spatial.conventions[2] == "velocity"
    assert spatial.behaviours.model_names == flat.behaviours.model_names
    assert spatial.classes == flat.classes


def test_a_3d_tracker_follows_a_climbing_target() -> None:
    rng = np.random.default_rng(RNG_SEED)
    config = LocalTrackerConfig.paper(
        axes=3, measurement_noise=((0.2, 0, 0), (0, 0.2, 0), (0, 0, 0.2))
    )
    tracker = LocalTracker(config)
    start, velocity = np.array([0.0, 0.0, 1000.0]), np.array([150.0, -40.0, 12.0])
    times = np.cumsum(rng.uniform(0.8, 1.2, 20))
    for t in times:
        step = tracker.step(float(t), (start + t * velocity + rng.normal(0, 0.45, 3))[None])
    (track,) = step.tracks
    assert track.status.value == "confirmed"
    np.testing.assert_allclose(track.state[[0, 2, 4]], start + times[-1] * velocity, atol=2.0)
    np.testing.assert_allclose(track.state[[1, 3, 5]], velocity, atol=2.0)
