"""A 3 g coordinated turn between straight legs: Singer against constant velocity.

One aircraft flies 60 s straight at 250 m/s, turns 180° at 3 g (a coordinated
turn at constant speed, ω = 3g / 250 m/s = 0.118 rad/s, 26.7 s), and flies 60 s
straight back. A sensor measures its position every 1 s with σ = 25 m per
axis. Each filter is a Kalman filter that predicts with the session's motion
model as the fused layer does (:class:`core.models.MappedMotion` on the
session's state layout, defaults of the API) and updates with the position:

- ``constant_velocity q=1`` — the default ``motion.q`` of a session of track
  lists without a preset;
- ``constant_velocity q=342`` — the default ``motion.q`` derived from the
  aircraft preset (the bank's largest velocity change at 3σ);
- ``singer (defaults)`` — ``motion.model: "singer"`` with nothing else given
  (τ = 20 s, σ_m = 18.9 m/s², :mod:`core.models.singer`);
- ``stone soup singer`` — Stone Soup's ``KalmanPredictor`` / ``KalmanUpdater``
  with ``Singer(damping_coeff=1/τ, noise_diff_coeff=2σ_m²/τ)`` per axis on the
  same measurements: its RMSE must equal ours (the same model, independently
  written); the largest difference of the position estimates is printed.

Every filter starts at the first measurement with the true velocity and the
covariance diag(σ², 30², σ_m²) per axis (no start-up transient: the legs are
the same for all). Position RMSE against the truth over N_RUNS seeded runs,
over the whole flight after a 5 s settle, and over the turn and the 15 s
after it (where a model lags). Also the time per predict+update step of ours
and Stone Soup's, in the same run.

Run: ``.venv/bin/python bench/manoeuvre.py`` (or ``make bench``).
"""

from __future__ import annotations

import datetime
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel
from stonesoup.models.transition.linear import Singer as StoneSoupSinger
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import KalmanUpdater

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import describe_machine

from core.models import MappedMotion, StateLayout
from core.models.singer import GRAVITY, Singer
from core.models.transition import ConstantVelocity, TransitionModel

SEED = 20261203
N_RUNS = 50
SPEED = 250.0  # m/s
TURN_ACCELERATION = 3.0 * GRAVITY  # m/s²
LEG = 60.0  # s, each straight leg
STEP = 1.0  # s between measurements
SIGMA = 25.0  # m, position noise per axis
SETTLE = 5  # measurements before the RMSE counts
AFTER_TURN = 15.0  # s after the turn still counted in the turn window
CV_LAYOUT = StateLayout(4, position=(0, 2), velocity=(1, 3))
SINGER_LAYOUT = StateLayout(6, position=(0, 3), velocity=(1, 4), acceleration=(2, 5))


@dataclass(frozen=True)
class Flight:
    """The truth at the measurement times: positions (T, 2), velocities (T, 2)."""

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    turn: tuple[float, float]


def flight() -> Flight:
    """Straight, a 180° coordinated turn at 3 g (to the left), straight back."""
    rate = TURN_ACCELERATION / SPEED
    turn_time = np.pi / rate
    end = 2 * LEG + turn_time
    times = np.arange(0.0, end + 1e-9, STEP)
    positions = np.zeros((len(times), 2))
    velocities = np.zeros((len(times), 2))
    radius = SPEED / rate
    for k, t in enumerate(times):
        if t <= LEG:
            positions[k] = (SPEED * t, 0.0)
            velocities[k] = (SPEED, 0.0)
        elif t <= LEG + turn_time:
            angle = rate * (t - LEG)
            positions[k] = (SPEED * LEG + radius * np.sin(angle), radius * (1 - np.cos(angle)))
            velocities[k] = (SPEED * np.cos(angle), SPEED * np.sin(angle))
        else:
            back = t - LEG - turn_time
            positions[k] = (SPEED * LEG - SPEED * back, 2 * radius)
            velocities[k] = (-SPEED, 0.0)
    return Flight(times, positions, velocities, (LEG, LEG + turn_time))


def _start(
    layout: StateLayout, model: TransitionModel, z: np.ndarray, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    state = np.zeros(layout.dim)
    variances = np.zeros(layout.dim)
    state[list(layout.position)] = z
    state[list(layout.velocity)] = v
    variances[list(layout.position)] = SIGMA**2
    variances[list(layout.velocity)] = 30.0**2
    if layout.acceleration:
        assert isinstance(model, Singer)
        variances[list(layout.acceleration)] = model.acceleration_std**2
    return state, np.diag(variances)


def run_ours(
    model: TransitionModel, layout: StateLayout, truth: Flight, measurements: np.ndarray
) -> np.ndarray:
    """Kalman filter: predict with the session's MappedMotion, update with the positions."""
    motion = MappedMotion(layout, model)
    h = np.zeros((2, layout.dim))
    h[[0, 1], list(layout.position)] = 1.0
    r = SIGMA**2 * np.eye(2)
    x, p = _start(layout, model, measurements[0], truth.velocities[0])
    estimates = [x[list(layout.position)]]
    for z in measurements[1:]:
        x, p = motion.predict(x[None], p[None], np.array([STEP]))
        x, p = x[0], p[0]
        s = h @ p @ h.T + r
        gain = np.linalg.solve(s, h @ p).T
        x = x + gain @ (z - h @ x)
        p = p - gain @ s @ gain.T
        p = (p + p.T) / 2
        estimates.append(x[list(layout.position)])
    return np.array(estimates)


def run_stone_soup(model: Singer, truth: Flight, measurements: np.ndarray) -> np.ndarray:
    """Stone Soup's Kalman filter with its Singer model on [x, ẋ, ẍ, y, ẏ, ÿ]."""
    axis = StoneSoupSinger(damping_coeff=1.0 / model.manoeuvre_time, noise_diff_coeff=model.q)
    transition = CombinedLinearGaussianTransitionModel([axis, axis])
    sensor = LinearGaussian(ndim_state=6, mapping=(0, 3), noise_covar=SIGMA**2 * np.eye(2))
    predictor, updater = KalmanPredictor(transition), KalmanUpdater(sensor)
    start = datetime.datetime(2026, 12, 3)
    x, p = _start(SINGER_LAYOUT, model, measurements[0], truth.velocities[0])
    prior = GaussianState(x[:, None], p, timestamp=start)
    estimates = [x[[0, 3]]]
    for k, z in enumerate(measurements[1:], start=1):
        when = start + datetime.timedelta(seconds=float(truth.times[k]))
        detection = Detection(z[:, None], timestamp=when, measurement_model=sensor)
        prediction = predictor.predict(prior, timestamp=when)
        prior = updater.update(SingleHypothesis(prediction, detection))
        estimates.append(np.asarray(prior.state_vector, dtype=np.float64)[[0, 3], 0])
    return np.array(estimates)


def _rmse(errors: list[np.ndarray]) -> float:
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))


def main() -> None:
    print(describe_machine())
    truth = flight()
    rng = np.random.default_rng(SEED)
    runs = [truth.positions + rng.normal(0.0, SIGMA, truth.positions.shape) for _ in range(N_RUNS)]
    settled = truth.times >= SETTLE * STEP
    turning = (truth.times >= truth.turn[0]) & (truth.times <= truth.turn[1] + AFTER_TURN)
    singer = Singer()
    filters: list[tuple[str, Callable[[np.ndarray], np.ndarray]]] = [
        (
            "constant_velocity q=1 (default)",
            lambda z: run_ours(ConstantVelocity(1.0), CV_LAYOUT, truth, z),
        ),
        (
            "constant_velocity q=342 (aircraft)",
            lambda z: run_ours(ConstantVelocity(342.1728), CV_LAYOUT, truth, z),
        ),
        ("singer (defaults)", lambda z: run_ours(singer, SINGER_LAYOUT, truth, z)),
        ("stone soup singer", lambda z: run_stone_soup(singer, truth, z)),
    ]
    print(
        f"3 g coordinated turn (ω = {TURN_ACCELERATION / SPEED:.4f} rad/s, "
        f"{truth.turn[1] - truth.turn[0]:.1f} s) between {LEG:.0f} s legs at {SPEED:.0f} m/s; "
        f"σ = {SIGMA:.0f} m every {STEP:.0f} s; {N_RUNS} runs, seed {SEED}"
    )
    print(f"{'filter':<36} {'RMSE all (m)':>13} {'RMSE turn (m)':>14} {'ms/step':>8}")
    estimates: dict[str, list[np.ndarray]] = {}
    for name, run in filters:
        started = time.perf_counter()
        estimates[name] = [run(z) for z in runs]
        per_step = 1e3 * (time.perf_counter() - started) / (N_RUNS * (len(truth.times) - 1))
        errors = [np.linalg.norm(e - truth.positions, axis=1) for e in estimates[name]]
        print(
            f"{name:<36} {_rmse([e[settled] for e in errors]):>13.2f} "
            f"{_rmse([e[turning] for e in errors]):>14.2f} {per_step:>8.3f}"
        )
    difference = max(
        float(np.abs(ours - theirs).max())
        for ours, theirs in zip(
            estimates["singer (defaults)"], estimates["stone soup singer"], strict=True
        )
    )
    print(f"singer vs stone soup singer: largest position difference {difference:.3g} m")


if __name__ == "__main__":
    main()
