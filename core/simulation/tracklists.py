"""Scenarios for track-to-track fusion: sensors that report track lists.

Each sensor runs its own tracker in reality; here a sensor's track of a
target is the true state plus an error drawn from the covariance it reports,
independently at every report (the estimates are consistent by construction;
the time correlation of real local-tracker errors is not modelled).

- :func:`t2t_four` — [T2T] §4 scenario 1 (Fig 3): four nearby targets seen by
  two sensors. The paper gives no coordinates; here the targets fly in a
  square of side ``separation`` at constant velocity.
- :func:`crossing_traffic` — a metre-scale scene: many targets on straight
  lines that cross inside a square, several sensors with P_D < 1, each
  reporting at its own staggered times.

Reports come in arrival order; every reported track carries the id of the
target it comes from (for evaluation only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.errors import ScenarioError
from core.simulation.scenario import TargetTruth


@dataclass(frozen=True)
class SensorTrackList:
    """One sensor's track list at one time.

    Attributes
    ----------
    sensor : sensor id.
    time : report time (s).
    step : the truth step the report follows (its estimates are of the truth at ``time``).
    track_ids : the sensor's local track ids.
    states, covariances : (n, 4) and (n, 4, 4), state ``[x, ẋ, y, ẏ]``.
    target_ids : (n,) the true target of each track (evaluation only).
    """

    sensor: str
    time: float
    step: int
    track_ids: tuple[str, ...]
    states: FloatArray
    covariances: FloatArray
    target_ids: IntArray


@dataclass(frozen=True)
class TrackListScenario:
    """Ground truth and the sensors' track lists, in arrival order."""

    name: str
    seed: int
    sensors: tuple[str, ...]
    truths: tuple[TargetTruth, ...]
    reports: tuple[SensorTrackList, ...]


def estimate_covariance(
    position_sigma: float, velocity_sigma: float, elongation: float = 1.0
) -> FloatArray:
    """Diagonal covariance of a ``[x, ẋ, y, ẏ]`` estimate.

    ``elongation`` stretches x by that factor and shrinks y by it (an elongated
    error ellipse, as a radar's range/bearing errors give); 1 is round.
    """
    sx, sy = elongation, 1.0 / elongation
    return np.diag(
        [
            (position_sigma * sx) ** 2,
            (velocity_sigma * sx) ** 2,
            (position_sigma * sy) ** 2,
            (velocity_sigma * sy) ** 2,
        ]
    )


def _constant_velocity(start: FloatArray, n_steps: int, time_interval: float) -> FloatArray:
    steps = np.arange(n_steps)[:, None] * time_interval
    states = np.repeat(start[None, :], n_steps, axis=0)
    states[:, 0] += start[1] * steps[:, 0]
    states[:, 2] += start[3] * steps[:, 0]
    return states


def _at(state: FloatArray, lag: float) -> FloatArray:
    """A constant-velocity state ``lag`` seconds later."""
    moved = state.copy()
    moved[0] += state[1] * lag
    moved[2] += state[3] * lag
    return moved


def _report(
    rng: np.random.Generator,
    sensor: str,
    time: float,
    step: int,
    lag: float,
    truths: tuple[TargetTruth, ...],
    covariance: FloatArray,
    p_detect: float,
    noise: float = 1.0,
) -> SensorTrackList:
    present = [truth for truth in truths if truth.alive(step) and rng.random() < p_detect]
    root = noise * np.linalg.cholesky(covariance)
    states = np.array(
        [_at(truth.state_at(step), lag) + root @ rng.standard_normal(4) for truth in present]
    )
    return SensorTrackList(
        sensor=sensor,
        time=time,
        step=step,
        track_ids=tuple(f"{sensor}-{truth.target_id}" for truth in present),
        states=states.reshape(len(present), 4),
        covariances=np.repeat(covariance[None], len(present), axis=0),
        target_ids=np.array([truth.target_id for truth in present], dtype=np.int64),
    )


def t2t_four(
    seed: int = 0,
    position_sigma: float = 0.5,
    noise: float = 1.0,
    elongation: float = 1.0,
    separation: float = 10.0,
    n_steps: int = 20,
    time_interval: float = 1.0,
) -> TrackListScenario:
    """Four targets in a square of side ``separation`` (m), flying east at 10 m/s; two sensors.

    The sensors report the covariance of ``position_sigma`` (velocity σ half of
    it); their actual errors are ``noise`` times that ([T2T] §4 varies the
    noise realisations under fixed reported covariances). With ``elongation``
    > 1, s1's errors are stretched along x and s2's along y.
    """
    if not (
        position_sigma > 0.0
        and noise >= 0.0
        and separation > 0.0
        and n_steps > 0
        and time_interval > 0.0
    ):
        raise ScenarioError("t2t_four needs positive noise, separation, steps and interval")
    rng = np.random.default_rng(seed)
    corners = [(0.0, 0.0), (separation, 0.0), (0.0, separation), (separation, separation)]
    truths = tuple(
        TargetTruth(k, 0, _constant_velocity(np.array([x, 10.0, y, 0.0]), n_steps, time_interval))
        for k, (x, y) in enumerate(corners)
    )
    covariances = {
        "s1": estimate_covariance(position_sigma, position_sigma / 2.0, elongation),
        "s2": estimate_covariance(position_sigma, position_sigma / 2.0, 1.0 / elongation),
    }
    reports = []
    for step in range(n_steps):
        for offset, sensor in enumerate(("s1", "s2")):
            time = step * time_interval + offset * 1e-3 * time_interval
            lag = time - step * time_interval
            reports.append(
                _report(rng, sensor, time, step, lag, truths, covariances[sensor], 1.0, noise)
            )
    return TrackListScenario("t2t-four", seed, ("s1", "s2"), truths, tuple(reports))


def crossing_traffic(
    seed: int = 0,
    n_targets: int = 20,
    n_sensors: int = 3,
    n_steps: int = 60,
    position_sigma: float = 5.0,
    p_detect: float = 0.9,
    extent: float = 1000.0,
    time_interval: float = 1.0,
) -> TrackListScenario:
    """Targets on straight lines through a square of side ``extent`` (m), crossing near its centre.

    Each target starts on the circle inscribed in the square (start bearings
    evenly spread and jittered) and heads for a point near the centre at
    8-20 m/s, so tracks cross; sensor ``s_k`` reports at
    ``step + k / n_sensors`` with P_D = ``p_detect`` and position error
    ``position_sigma`` (velocity error half of it).
    """
    if n_targets < 1 or n_sensors < 1 or n_steps < 1 or not 0.0 < p_detect <= 1.0:
        raise ScenarioError("crossing_traffic needs targets, sensors, steps and P_D in (0, 1]")
    rng = np.random.default_rng(seed)
    truths = []
    spacing = 2.0 * np.pi / n_targets
    for target in range(n_targets):
        # Evenly spread start bearings, jittered: no two targets are born on top of each other.
        angle = target * spacing + rng.uniform(-0.3, 0.3) * spacing
        start = extent / 2.0 * np.array([np.cos(angle), np.sin(angle)]) + extent / 2.0
        aim = extent / 2.0 + rng.uniform(-0.1, 0.1, 2) * extent
        speed = rng.uniform(8.0, 20.0)
        heading = (aim - start) / np.linalg.norm(aim - start)
        state = np.array([start[0], speed * heading[0], start[1], speed * heading[1]])
        truths.append(TargetTruth(target, 0, _constant_velocity(state, n_steps, time_interval)))
    sensors = tuple(f"s{k + 1}" for k in range(n_sensors))
    covariance = estimate_covariance(position_sigma, position_sigma / 2.0)
    reports = [
        _report(
            rng,
            sensor,
            (step + k / n_sensors) * time_interval,
            step,
            k / n_sensors * time_interval,
            tuple(truths),
            covariance,
            p_detect,
        )
        for step in range(n_steps)
        for k, sensor in enumerate(sensors)
    ]
    return TrackListScenario("crossing-traffic", seed, sensors, tuple(truths), tuple(reports))
